"""The controller's own model in and out (issue 33): UR calibration.conf import, kinematics YAML and
URDF export, tables -- against published facts of Universal Robots' driver and description packages.

Facts used (cited, no code copied):
- the three real arms' [mounting] deltas of ``UniversalRobots/Universal_Robots_ROS2_Driver``,
  ``ur_calibration/test/calibration_test.cpp`` (tests/data/controller/*.conf);
- the real UR10e DH table printed in ``ur_calibration/doc/algorithm.rst`` (nominal + deltas);
- the UR10 forward-kinematics points of the same test file (``ur10_fw_kinematics_real``);
- the ``hash`` of ``UniversalRobots/Universal_Robots_ROS2_Description``'s
  ``config/ur10/default_kinematics.yaml`` and ``config/ur10e/default_kinematics.yaml``.
"""

from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from robocal.cli.main import main
from robocal.io.ur_controller import parse_calibration_conf, read_kinematics_yaml, ur_driver_hash
from robocal.kinematics.remodel import EXTENDED_PRECISION, dh_table_fk
from robocal.robots import load_robot
from robocal.workflows.controller.models import UR_PI_2, _dh_mm, _pose_errors, import_ur, random_joints, ur_controller_dh

DATA = Path(__file__).parent / "data" / "controller"
REAL = [("ur10_driver_test.conf", "ur10"), ("ur10e_driver_test_a.conf", "ur10e"), ("ur10e_driver_test_b.conf", "ur10e")]

needs_ld = pytest.mark.skipif(not EXTENDED_PRECISION, reason="numpy.longdouble is float64 here: the 1e-9 mm "
                                                             "reference needs 80-bit extended precision")


def run(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


def test_driver_hash_reproduces_ur_description_defaults():
    # URSim's nominal tables (alphas +-1.570796327) give the hashes ur_description publishes.
    p2 = UR_PI_2
    assert ur_driver_hash([0] * 6, [0.1273, 0, 0, 0.163941, 0.1157, 0.0922], [0, -0.612, -0.5723, 0, 0, 0],
                          [p2, 0, 0, p2, -p2, 0]) == "calib_17227329492635474227"
    assert ur_driver_hash([0] * 6, [0.1807, 0, 0, 0.17415, 0.11985, 0.11655], [0, -0.6127, -0.57155, 0, 0, 0],
                          [p2, 0, 0, p2, -p2, 0]) == "calib_5119701370761913513"


def test_controller_table_matches_algorithm_rst():
    # The real UR10e of algorithm.rst: its printed table (15 digits) is nominal + the third test set's deltas,
    # with the controller's 1.570796327 for pi/2 (with exact pi/2 the alphas would differ in the 10th digit).
    cal = parse_calibration_conf((DATA / "ur10e_driver_test_b.conf").read_text())
    dh = ur_controller_dh(load_robot("ur10e"), cal)
    published = {
        "theta": "-2.4147806894359e-07 1.60233952386695 -1.68607190752171 0.0837331147700119 -1.01260355871158e-07 "
                 "3.91986209186124e-08",
        "a": "2.12234865571206e-05 0.0193171326277006 -0.569251663611088 -4.61409023720934e-05 -6.39280053471802e-05 0",
        "d": "0.180539811714259 439.140974079901 -446.027059806332 7.0603368964236 0.119811341150314 0.115670917257426",
        "alpha": "1.57014608044242 0.0013941666682559 0.00693818880325995 1.56998468543761 -1.57038520649543 0",
    }
    for key, text in published.items():
        assert ["%.15g" % v for v in dh[key]] == text.split(), key


def test_nominal_ur10_fk_matches_driver_test_points():
    # ur10_fw_kinematics_real: the UR10 with alphas 1.570796327, FK points in metres to 1e-15 m.
    dh = ur_controller_dh(load_robot("ur10"), None)
    th, d, a, al = _dh_mm(dh)
    q = np.array([[-1.6007002035724084976209269370884, -1.7271001974688928726209269370884,
                   -2.2029998938189905288709269370884, -0.80799991289247685699592693708837, 1.59510004520416259765625,
                   -0.03099996248354131012092693708837],
                  [1.32645022869110107421875, 2.426007747650146484375, 5.951572895050048828125,
                   1.27409040927886962890625, -0.54105216661562138824592693708837, 0.122173048555850982666015625]])
    expected_mm = np.array([[-0.179925914147547, -0.606869755162764, 0.230789102067257],
                            [0.39922988003280424074148413637886, 0.59688365069340565405298093537567,
                             -0.6677819040276375961440180617501]]) * 1000
    p = np.asarray(dh_table_fk(th, d, a, al, q)[:, :3, 3], dtype=float)
    assert np.abs(p - expected_mm).max() < 1e-9


@needs_ld
@pytest.mark.parametrize("conf,robot", REAL)
def test_real_deltas_import_exactly_and_well_conditioned(conf, robot):
    r = import_ur(DATA / conf, robot, n_check=1000, seed=3)
    assert r["verdict"].ok, r["verdict"].reasons
    m = r["model"]
    q = random_joints(m, 1000, seed=11)
    th, d, a, al = _dh_mm(r["dh"])
    dp, ang = _pose_errors(dh_table_fk(th, d, a, al, q), m.fk(q))
    assert dp.max() < 1e-9 and ang.max() < 1e-12
    # the controller table has |d| up to 446 m; the robot file's lengths stay near the nominal arm's
    assert max(abs(x) for x in r["dh"]["d"]) > 1.0
    assert max(abs(v) for k, v in m.params.as_dict().items() if k[0] in "ad" and not k.startswith("alpha")) < 700
    assert max(abs(v) for k, v in r["difference"].items() if k[0] in "ad" and not k.startswith("alpha")) < 2.0
    assert max(abs(np.degrees(v)) for k, v in r["difference"].items() if k.startswith(("alpha", "beta", "theta"))) < 1


@needs_ld
@pytest.mark.parametrize("conf,robot", REAL)
def test_round_trip_conf_robot_yaml_robot(tmp_path, conf, robot):
    a, y, b = tmp_path / "a.toml", tmp_path / "k.yaml", tmp_path / "b.toml"
    res = run("controller", "import", "ur", DATA / conf, robot, "--out", a)
    assert res.exit_code == 0, res.output
    h = ur_controller_hash = import_ur(DATA / conf, robot, n_check=2)["hash"]
    res = run("controller", "export", "ur", a, "--out", y, "--hash", h)
    assert res.exit_code == 0, res.output
    assert read_kinematics_yaml(y)[1] == ur_controller_hash
    res = run("controller", "import", "ur-kinematics", robot, y, "--out", b)
    assert res.exit_code == 0, res.output
    model_b = load_robot(b)
    dh = ur_controller_dh(load_robot(robot), parse_calibration_conf((DATA / conf).read_text()))
    th, d, al_, alpha = _dh_mm(dh)
    q = random_joints(model_b, 1000, seed=5)
    dp, ang = _pose_errors(dh_table_fk(th, d, al_, alpha, q), model_b.fk(q))
    assert dp.max() < 1e-9 and ang.max() < 1e-12


def test_ur_description_flange_and_tool0_are_the_last_joint_frame():
    # ur_macro.xacro: wrist_3_link -> flange rpy (0, -pi/2, -pi/2), flange -> tool0 rpy (pi/2, 0, pi/2):
    # tool0 is wrist_3_link, so the six joint origins end at the controller's flange.
    from robocal.kinematics.links import frame_from_xyz_rpy

    T = frame_from_xyz_rpy([0, 0, 0], [0, -np.pi / 2, -np.pi / 2]) @ frame_from_xyz_rpy([0, 0, 0], [np.pi / 2, 0,
                                                                                                       np.pi / 2])
    assert np.abs(T - np.eye(4)).max() < 1e-15


def test_import_cli_json_argument_order_and_gates(tmp_path):
    out = tmp_path / "r.toml"
    res = run("controller", "import", "ur", DATA / "ur10_driver_test.conf", "--robot", "ur10", "--out", out, "--json")
    assert res.exit_code == 0, res.output
    import json

    doc = json.loads(res.output)
    assert doc["status"] == "ok" and doc["calibration_status"] == 2 and doc["ur_driver_hash"].startswith("calib_")
    assert doc["fk_check"]["n"] == 1000
    # same input, robot first: refused without --overwrite, accepted with it
    res = run("controller", "import", "ur", "ur10", DATA / "ur10_driver_test.conf", "--out", out)
    assert res.exit_code == 1 and "exists" in res.output
    # an output that is the input is refused
    conf = tmp_path / "calibration.conf"
    conf.write_text((DATA / "ur10_driver_test.conf").read_text())
    res = run("controller", "import", "ur", "ur10", conf, "--out", conf, "--overwrite")
    assert res.exit_code == 1 and "replace the input" in res.output
    # deltas that do not cancel on the parallel axes: the gate fails, exit 3, no file
    text = conf.read_text().replace("1.4442162376284788", "1.4942162376284788")
    bad = tmp_path / "bad.conf"
    bad.write_text(text)
    res = run("controller", "import", "ur", "ur10", bad, "--out", tmp_path / "bad.toml")
    assert res.exit_code == 3 and not (tmp_path / "bad.toml").exists()
    assert "nominal" in res.output


def test_bad_calibration_conf_is_one_line_error(tmp_path):
    conf = tmp_path / "calibration.conf"
    conf.write_text("[mounting]\ndelta_theta = [0, 0, 0, 0, 0, 0]\ndelta_a = [0, 0, 0]\n")
    res = run("controller", "import", "ur", "ur10", conf, "--out", tmp_path / "x.toml")
    assert res.exit_code == 1
    assert res.output.count("\n") == 1 and "delta_a" in res.output and "line 3" in res.output


def test_export_table_and_urdf(tmp_path):
    a = tmp_path / "a.toml"
    assert run("controller", "import", "ur", "ur10", DATA / "ur10_driver_test.conf", "--out", a).exit_code == 0
    res = run("controller", "export", "table", a, "--out", tmp_path / "t.csv")
    assert res.exit_code == 0, res.output
    lines = (tmp_path / "t.csv").read_text().splitlines()
    header = [ln for ln in lines if not ln.startswith("#")][0]
    assert header == "joint,alpha_deg,a_mm,beta_deg,theta_deg,d_mm,type"
    rows = [ln.split(",") for ln in lines if ln.startswith("J")]
    assert len(rows) == 6 and abs(float(rows[2][2]) + 612.0) < 2  # a3 near the UR10's -612 mm
    res = run("controller", "export", "urdf", a, "--out", tmp_path / "r.urdf", "--json")
    assert res.exit_code == 0, res.output
    import json

    assert json.loads(res.output)["fk_check"]["max_mm"] < 1e-6


def test_export_ur_refuses_a_tool_off_the_axis(tmp_path):
    src = (Path(load_robot("ur10").extra["origin"])).read_text()
    f = tmp_path / "tool.toml"
    f.write_text(src + "\n[tool]\nxyz = [10.0, 0.0, 100.0]\nrpy = [0.0, 0.0, 0.0]\n")
    res = run("controller", "export", "ur", f, "--out", tmp_path / "k.yaml")
    assert res.exit_code == 1 and "flange" in res.output


# ------------------------------------------------------------------------------------------ probing
def _true_controller():
    """The hidden model: a UR10 running the real factory calibration of the UR driver's tests."""
    return import_ur(DATA / "ur10_driver_test.conf", "ur10", n_check=2)["model"]


@pytest.mark.parametrize("controller", ["ur", "abb", "kuka", "doosan"])
def test_probe_recovers_a_calibrated_controller_within_its_output_rounding(tmp_path, controller):
    from robocal.sim.controller import probe_pairs_text
    from robocal.workflows.controller.probe import model_diff

    true = _true_controller()
    pairs = tmp_path / "pairs.txt"
    # poses printed to 0.01 mm and 0.001 deg (UR rotation vectors, ABB quaternions: the same step)
    pairs.write_text(probe_pairs_text(true, random_joints(true, 200, seed=1), controller))
    out = tmp_path / "probed.toml"
    res = run("controller", "probe", "ur10", pairs, "--out", out, "--json")
    assert res.exit_code == 0, res.output
    import json

    doc = json.loads(res.output)
    assert doc["runs_nominal"] is False and doc["controller"] == controller
    assert doc["fit_residual"]["position_mm"]["max"] <= doc["tolerance"]["mm"]
    # a rounding of +-0.005 mm per coordinate leaves the recovered model ~1 um from the truth
    d = model_diff(true, load_robot(out), n_poses=1000, seed=7)
    assert d["position_mm"]["max"] < 0.005 and d["rotation_deg"]["max"] < 0.0005
    # and the changed parameters are the factory calibration's (same convention as `import ur`)
    changed = doc["changed_parameters"]
    assert abs(changed["a4"]["change"] - (true.params.as_dict()["a4"] - (-572.3))) < 5 * changed["a4"]["sigma"] + 1e-3


def test_probe_of_a_nominal_controller_and_of_a_non_geometric_compensation(tmp_path):
    from robocal.sim.controller import probe_pairs_text

    nominal = load_robot("ur10")
    q = random_joints(nominal, 120, seed=2)
    pairs = tmp_path / "nominal.txt"
    pairs.write_text(probe_pairs_text(nominal, q, "kuka"))
    res = run("controller", "probe", "ur10", pairs)
    assert res.exit_code == 0, res.output
    assert "runs the nominal model" in res.output
    # a controller adding a joint-2 dependent sag (not a rigid-chain effect): a remainder, exit 3, no file
    sag = tmp_path / "sag.txt"
    sag.write_text(probe_pairs_text(nominal, q, "kuka",
                                    compensation=lambda qq: np.stack([0 * qq[:, 0], 0 * qq[:, 0],
                                                                      -0.3 * np.cos(qq[:, 1]) ** 2], axis=1)))
    res = run("controller", "probe", "ur10", sag, "--out", tmp_path / "x.toml")
    assert res.exit_code == 3 and not (tmp_path / "x.toml").exists()
    assert "not a rigid chain" in res.output


def test_probe_programs_are_written_and_their_lines_read_back(tmp_path):
    from robocal.io.controller_pairs import parse_probe_pairs

    for lang, suffix in (("ur", "script"), ("abb", "mod"), ("kuka", "src"), ("doosan", "py")):
        out = tmp_path / f"probe.{suffix}"
        res = run("controller", "probe-program", "ur10", lang, "--count", 12, "--out", out)
        assert res.exit_code == 0, res.output
        text = out.read_text()
        assert text.count("robocal-pair") >= 1
    assert (tmp_path / "probe.script").read_text().count("get_forward_kin") == 12
    mod = (tmp_path / "probe.mod").read_text()
    assert mod.count("p := CalcRobT(jt, tool0") == 1 and mod.count("\n    w ") == 12
    assert (tmp_path / "probe.src").read_text().count("FORWARD(AX, ERR)") == 12
    # what the programs print, as a listener or a log records it (URScript's to_str lists, a log prefix)
    ur = ("2026-11-27 10:00:01 robocal-pair,ur,0,[0.1, -1.2, 1.0, 0.3, 1.5, 0.2],"
          "p[-0.612, -0.2561, 0.0116, 0.0, 2.2214, -2.2214]\n")
    p = parse_probe_pairs(ur)
    assert p.controller == "ur" and np.allclose(p.q[0], [0.1, -1.2, 1.0, 0.3, 1.5, 0.2])
    assert np.allclose(p.T[0, :3, 3], [-612.0, -256.1, 11.6])
    abb = "robocal-pair,abb,3,10,20,30,40,50,60,1000.5,-20.25,900,0.5,0.5,0.5,0.5\n"
    assert np.allclose(parse_probe_pairs(abb).q[0], np.radians([10, 20, 30, 40, 50, 60]))
    # a file whose records ran together (a printf without its newline)
    kuka = ("robocal-pair,kuka,0,1,2,3,4,5,6,1000,0,1500,10,20,30\\n"
            "robocal-pair,kuka,1,6,5,4,3,2,1,900,10,1400,-10,-20,-30\\n")
    assert parse_probe_pairs(kuka).q.shape == (2, 6)


def test_diff_cli_reports_statistics_map_and_accepts_cell(tmp_path):
    a = tmp_path / "controller.toml"
    assert run("controller", "import", "ur", "ur10", DATA / "ur10_driver_test.conf", "--out", a).exit_code == 0
    cell = tmp_path / "cell.toml"  # the floor and a table in front of the robot
    cell.write_text('format = "robocal-cell/1"\nlength_unit = "mm"\nangle_unit = "deg"\n[mounting]\nkind = "floor"\n'
                    '[[box]]\nname = "table"\nmin = [400.0, -500.0, 0.0]\nmax = [1000.0, 500.0, 300.0]\n')
    res = run("controller", "diff", "ur10", a, "--poses", 300, "--cell", cell, "--json",
              "--out", tmp_path / "d.csv", "--plots", tmp_path / "plots")
    assert res.exit_code == 0, res.output
    import json

    doc = json.loads(res.output)
    # every joint set of the map is one the robot can take in that cell
    from robocal.calib.cell import feasible
    from robocal.io.cell_file import read_cell

    rows = [ln.split(",") for ln in (tmp_path / "d.csv").read_text().splitlines()[1:]]
    q = np.radians(np.array([[float(v) for v in r[:6]] for r in rows]))
    assert feasible(read_cell(cell, load_robot("ur10")), load_robot("ur10"), q).all()
    assert 1.0 < doc["position_mm"]["max"] < 20.0  # a factory calibration moves the UR10's flange by mm
    assert len(doc["accuracy_map"]["by_reach"]) >= 3 and doc["notes"]
    assert len((tmp_path / "d.csv").read_text().splitlines()) == 301
    assert (tmp_path / "plots" / "accuracy_map.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    # a model against itself: zero
    res = run("controller", "diff", a, a, "--poses", 50, "--json")
    assert json.loads(res.output)["position_mm"]["max"] < 1e-9


def test_docs_walk_through_runs_as_written(tmp_path, monkeypatch):
    import json
    import re
    import shlex

    text = (Path(__file__).resolve().parents[1] / "docs" / "controller.md").read_text(encoding="utf-8")
    part = text[text.index("## Walk-through"):]
    block = re.findall(r"```\n(.*?)```", part, re.S)[0]
    commands = [ln for ln in block.splitlines() if ln.startswith("robocal ")]
    assert len(commands) == 6
    (tmp_path / "calibration.conf").write_text((DATA / "ur10_driver_test.conf").read_text())
    monkeypatch.chdir(tmp_path)
    for line in commands:
        res = CliRunner().invoke(main, shlex.split(line)[1:])
        assert res.exit_code == 0, (line, res.output)
    result = json.loads((tmp_path / "calib" / "result.json").read_text())
    assert result["validation"]["after"]["rms"] < 0.05  # the page quotes 0.038 mm
    res = run("controller", "diff", "ur10_controller.toml", "calib/calibrated_robot.toml", "--json")
    assert abs(json.loads(res.output)["position_mm"]["rms"] - 1.69) < 0.01  # the page quotes 1.69 mm RMS


@pytest.mark.parametrize("robot,controller", [("kuka_kr150_r3100", "kuka"), ("fanuc_r2000ic_165f", "abb")])
def test_probe_other_arms_with_sign_flips_and_coupling(tmp_path, robot, controller):
    # KUKA's joint signs and FANUC's J2/J3 coupling stay in the probed model; a hidden model 0.3 mm /
    # 0.02 deg (1 sigma per parameter) off nominal is recovered within the output rounding
    from robocal.sim.controller import probe_pairs_text
    from robocal.workflows.controller.probe import model_diff, probe_start_model

    start = probe_start_model(load_robot(robot))
    rng = np.random.default_rng(4)
    vals = start.params.values + np.where(start.params.free, rng.normal(0, 1, len(start.params)), 0.0) * np.where(
        np.array(start.params.units) == "mm", 0.3, np.radians(0.02))
    true = start.with_params(vals)
    pairs = tmp_path / "pairs.txt"
    pairs.write_text(probe_pairs_text(true, random_joints(true, 150, seed=8), controller))
    out = tmp_path / "probed.toml"
    res = run("controller", "probe", robot, pairs, "--out", out)
    assert res.exit_code == 0, res.output
    probed = load_robot(out)
    assert np.array_equal(probed.coupling, load_robot(robot).coupling)
    assert model_diff(true, probed, n_poses=500, seed=1)["position_mm"]["max"] < 0.005


@pytest.mark.parametrize("robot", ["ur10", "ur10e"])
def test_ur_description_default_yaml_reads_as_the_nominal_arm(tmp_path, robot):
    # The published default kinematics (alphas 1.570796327, z of 1e-11 m from ur_calibration's
    # arithmetic) read as URDF origins about z, ending at tool0 = the DH flange: robocal's nominal arm
    # to the 1.570796327-vs-pi/2 difference (2e-10 rad over ~1.3 m, < 1e-6 mm).
    from robocal.workflows.controller.models import model_from_kinematics_yaml

    f = DATA / f"ur_description_{robot}_default_kinematics.yaml"
    r = model_from_kinematics_yaml(f, robot)
    nominal = load_robot(robot)
    q = random_joints(nominal, 500, seed=2)
    dp, ang = _pose_errors(nominal.fk(q), r["model"].fk(q))
    assert dp.max() < 1e-6 and ang.max() < 1e-9
    assert r["hash"] == {"ur10": "calib_17227329492635474227", "ur10e": "calib_5119701370761913513"}[robot]
    # and robocal's export of the nominal arm gives the same chain as the published file
    y = tmp_path / "k.yaml"
    assert run("controller", "export", "ur", robot, "--out", y).exit_code == 0
    from robocal.workflows.controller.models import _origin_from_yaml, origins_fk

    ours = [_origin_from_yaml(xyz, rpy) for xyz, rpy in read_kinematics_yaml(y)[0]]
    dp, _ = _pose_errors(origins_fk(r["origins"], q), origins_fk(ours, q))
    assert dp.max() < 1e-6


def test_intrinsic_angles_read_as_urdf_rpy_would_move_the_flange():
    # The figure of docs/controller.md ("Angle convention, an open point"): robocal's joint origins of the
    # UR10 test arm, their intrinsic X-Y'-Z'' angles read as URDF rpy: up to 0.043 mm / 0.0036 deg.
    from robocal.kinematics.links import frame_from_xyz_rpy
    from robocal.transforms import euler_from_matrix
    from robocal.workflows.controller.models import origins_fk, ur_joint_origins

    m = import_ur(DATA / "ur10_driver_test.conf", "ur10", n_check=2)["model"]
    O = ur_joint_origins(m)
    mixed = [frame_from_xyz_rpy(T[:3, 3], euler_from_matrix(T[:3, :3], "xyz_intrinsic")) for T in O]
    q = random_joints(m, 1000, seed=0)
    dp, ang = _pose_errors(origins_fk(O, q), origins_fk(mixed, q))
    assert 0.040 < dp.max() < 0.047 and 0.0033 < np.degrees(ang.max()) < 0.0038


def test_probe_frees_a_flange_frame_that_differs_by_a_constant(tmp_path):
    # a controller whose flange convention is KUKA-like (x along the tool, a 90 deg turn about y) on top of a
    # 0.3 mm / 0.02 deg perturbed chain: --flange auto sees the constant and fits it
    from robocal.kinematics.links import frame_from_xyz_rpy
    from robocal.sim.controller import probe_pairs_text
    from robocal.workflows.controller.probe import model_diff, probe_start_model
    from robocal.kinematics.model import EndEffector

    start = probe_start_model(load_robot("kuka_kr150_r3100"))
    rng = np.random.default_rng(6)
    vals = start.params.values + np.where(start.params.free, rng.normal(0, 1, len(start.params)), 0.0) * np.where(
        np.array(start.params.units) == "mm", 0.3, np.radians(0.02))
    T_ee = frame_from_xyz_rpy([0.4, -0.2, 0.0], [0.001, np.pi / 2 + 0.002, 0.0])
    true = start.with_params(vals).replace(end_effectors=[EndEffector("flange", 5, T_ee)])
    pairs = tmp_path / "pairs.txt"
    pairs.write_text(probe_pairs_text(true, random_joints(true, 150, seed=9), "kuka"))
    out = tmp_path / "probed.toml"
    res = run("controller", "probe", "kuka_kr150_r3100", pairs, "--out", out)
    assert res.exit_code == 0, res.output
    assert "flange frame differs" in res.output
    assert model_diff(true, load_robot(out), n_poses=500, seed=1)["position_mm"]["max"] < 0.005
    res = run("controller", "probe", "kuka_kr150_r3100", pairs, "--flange", "fixed")
    assert res.exit_code == 3


def test_ur_nominal_tables_reproduce_ur_description_hashes():
    # every UR type's table: the hash ur_description publishes in config/<type>/default_kinematics.yaml
    from robocal.workflows.controller.models import load_nominal

    published = {"ur3": "calib_9122066269688285636", "ur5": "calib_209549117540498681",
                 "ur10": "calib_17227329492635474227", "ur3e": "calib_16756443741236045476",
                 "ur5e": "calib_12788084448423163542", "ur10e": "calib_5119701370761913513",
                 "ur16e": "calib_1935737212149401527", "ur20": "calib_4890363623803256388",
                 "ur30": "calib_12001109639981648826"}
    for arm, h in published.items():
        dh = ur_controller_dh(load_nominal(arm), None)
        assert ur_driver_hash(dh["theta"], dh["d"], dh["a"], dh["alpha"]) == h, arm


def test_table_reproduces_the_model_fk(tmp_path):
    # the MDH table read by its own header formula (written here independently of robocal's kernels)
    a = tmp_path / "a.toml"
    assert run("controller", "import", "ur", "ur10e", DATA / "ur10e_driver_test_b.conf", "--out", a).exit_code == 0
    assert run("controller", "export", "table", a, "--out", tmp_path / "t.csv").exit_code == 0
    lines = [ln for ln in (tmp_path / "t.csv").read_text().splitlines() if not ln.startswith("#")]
    cols = lines[0].split(",")
    rows = [dict(zip(cols, ln.split(","))) for ln in lines[1:]]

    def rx(t):
        c, s = np.cos(t), np.sin(t)
        return np.array([[1, 0, 0, 0], [0, c, -s, 0], [0, s, c, 0], [0, 0, 0, 1.0]])

    def ry(t):
        c, s = np.cos(t), np.sin(t)
        return np.array([[c, 0, s, 0], [0, 1, 0, 0], [-s, 0, c, 0], [0, 0, 0, 1.0]])

    def rz(t):
        c, s = np.cos(t), np.sin(t)
        return np.array([[c, -s, 0, 0], [s, c, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1.0]])

    def tr(x, y, z):
        T = np.eye(4)
        T[:3, 3] = (x, y, z)
        return T

    model = load_robot(a)
    for q in random_joints(model, 50, seed=4):
        T = np.eye(4)
        for r, qi in zip(rows, q):
            T = (T @ rx(np.radians(float(r["alpha_deg"]))) @ tr(float(r["a_mm"]), 0, 0)
                 @ ry(np.radians(float(r["beta_deg"]))) @ rz(np.radians(float(r["theta_deg"])) + qi)
                 @ tr(0, 0, float(r["d_mm"])))
        assert np.abs(T - model.fk(q)).max() < 1e-9


def test_probe_reads_a_ur_rtde_recording(tmp_path):
    # UR's RTDE record.py layout: a space-separated header with actual_q_* and actual_TCP_pose_* columns
    from robocal.transforms import pose_from_transform

    true = _true_controller()
    q = random_joints(true, 80, seed=12)
    pose = pose_from_transform(true.fk(q), "rotvec", "m", "rad")
    header = "timestamp " + " ".join(f"actual_q_{k}" for k in range(6)) + " " + " ".join(
        f"actual_TCP_pose_{k}" for k in range(6))
    rows = [" ".join(f"{v:.9f}" for v in [0.002 * i, *q[i], *pose[i]]) for i in range(len(q))]
    f = tmp_path / "robot_data.csv"
    f.write_text(header + "\n" + "\n".join(rows) + "\n")
    res = run("controller", "probe", "ur10", f, "--json", "--noise", 0.001, "--orientation-noise", 0.0001)
    assert res.exit_code == 0, res.output
    import json

    doc = json.loads(res.output)
    assert doc["controller"] == "ur" and doc["pairs"] == 80 and not doc["runs_nominal"]


def test_well_conditioned_form_is_a_fixed_point():
    # remodelling a calibrated (non-parallel) MDH + beta model with itself as reference gives it back
    from robocal.kinematics.remodel import model_axes, well_conditioned_mdh

    m = import_ur(DATA / "ur10e_driver_test_a.conf", "ur10e", n_check=2)["model"]
    again = well_conditioned_mdh(*model_axes(m), m)
    assert np.allclose(again.params.values, m.params.values, atol=1e-9)
    assert [L.fixed for L in again.links] == [L.fixed for L in m.links]


def test_import_gate_on_calibration_status_and_force(tmp_path):
    conf = tmp_path / "calibration.conf"
    conf.write_text((DATA / "ur10_driver_test.conf").read_text().replace("calibration_status = 2",
                                                                          "calibration_status = 1"))
    out = tmp_path / "r.toml"
    res = run("controller", "import", "ur", "ur10", conf, "--out", out)
    assert res.exit_code == 3 and not out.exists() and "notLinearised" in res.output
    res = run("controller", "import", "ur", "ur10", conf, "--out", out, "--force", "--json")
    assert res.exit_code == 3 and out.exists()
    import json

    assert json.loads(res.output)["status"] == "failed"
