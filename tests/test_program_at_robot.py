"""Issue 27: a corrected robot program must bring the TRUE robot closer to its targets.

End to end through the command line, judged at the robot: ``robocal simulate tracker`` (hidden
true robot), ``robocal calibrate``, ``robocal correct`` on a program with wrist-flipped and
arm-back targets, a tool, a base / work-object frame and taught joint targets, then
``robocal simulate execute`` runs the original and the corrected program with the virtual
controller (nominal model, the program's configuration, tool and frames) on the true robot.

The programs are taught offline with the nominal model at known joints, the configuration data
derived from those joints. The tool is the reflector the campaign identified (what ``correct``
offers as a tool), the physical tool the true reflector; the cell's frames are given in the
calibrated base frame (``--cell-base``), so every parameter the TCP depends on was identified:
each target must land within 0.15 mm, closer than before and within 3 sigma of its prediction.
"""

from __future__ import annotations

import csv
import json

import numpy as np
import pytest
from click.testing import CliRunner

from robocal.cli import main
from robocal.io.programs import read_program
from robocal.io.programs.configuration import configuration_text
from robocal.kinematics.arm_configuration import arm_signature
from robocal.robots import load_robot
from robocal.sim.taught_programs import fanuc_program, krl_program, rapid_program, ur_program
from robocal.transforms import euler_from_matrix, rotvec_from_matrix


class _Config:
    def __init__(self, config):
        self.config = config


def _run(args):
    r = CliRunner().invoke(main, [str(a) for a in args])
    return r


def _campaign(tmp_path, robot, seed, effects="ideal"):
    """Simulated tracker campaign (3 reflectors) and calibration; returns (truth, calibrated
    robot file, identified r1 [mm], true r1 [mm]). ``effects="realistic"``: the campaign has the
    effects the model lacks, and the calibration fits the reflector positions of every pose
    (``--no-orientation --holdout 0``: the fit whose first-order bias :func:`_realistic_miss` derives;
    ``--noise 0.02``, the tracker's: the reported sigma is the noise part, not scaled by the misfit)."""
    meas = tmp_path / "cell.csv"
    r = _run(["simulate", "tracker", robot, "--poses", 40, "--reflectors", 3, "--seed", seed, "--out", meas,
              "--effects", effects])
    assert r.exit_code == 0, r.output
    fit = [] if effects == "ideal" else ["--no-orientation", "--holdout", 0, "--noise", 0.02]
    r = _run(["calibrate", robot, meas, "--out", tmp_path / "cal", "--no-report", *fit])
    assert r.exit_code == 0, r.output
    truth = tmp_path / "cell.truth.json"
    result = json.loads((tmp_path / "cal" / "result.json").read_text())
    r1 = next(t["point_mm"] for t in result["targets"] if t["name"] == "r1")
    r1_true = json.loads(truth.read_text())["reflectors_mm"][0]
    return truth, tmp_path / "cal" / "calibrated_robot.toml", r1, r1_true


def _execute(truth, program, cal, extra, intended=None):
    args = ["simulate", "execute", truth, program, "--json", "--cell-base", cal, *extra]
    if intended is not None:
        args += ["--intended", intended]
    r = _run(args)
    assert r.exit_code == 0, r.output
    return {row["target"]: row for row in json.loads(r.output)["targets"]}


def _report(path):
    with open(path, newline="") as f:
        return {row["target"]: row for row in csv.DictReader(line for line in f if not line.startswith("#"))}


def _realistic_miss(truth, cal, q_exec):
    """First-order landing miss (M, 3) [mm] of the true robot with the campaign's effects at the
    executed joints ``q_exec`` (M, n) [rad] (tests/_first_order.py: the bias ``J^+ e`` of the
    calibration from the effects in its training poses, then ``e - J delta`` at the targets)."""
    from robocal.sim.first_order import tracker_campaign_bias

    from robocal.io.measurements import read_measurements

    t = json.loads(truth.read_text())
    result = json.loads((cal.parent / "result.json").read_text())
    q_train = read_measurements(truth.parent / t["simulation"]["measurements_file"]).joints
    estimated = [p["name"] for p in result["model_parameters"] if p["estimated"]]  # the identified ones
    return tracker_campaign_bias(t, estimated, q_train, q_exec)


def _judge(tmp_path, src, truth, cal, r1_true, options, execute_options=(), effects="ideal"):
    """Correct ``src`` and judge it at the true robot; returns the before/after errors [mm].

    ``effects="realistic"``: the true robot carries effects the model lacks, so "within 3 sigma
    and 0.15 mm" no longer holds by construction; instead each landing error must equal the
    first-order miss ``|e - J delta|`` derived from the hidden truth (:func:`_realistic_miss`)
    within 3 sigma of the corrected target's prediction (the noise part), and the effects must be
    visible (some target beyond 3 sigma: a correction that ignored them would pass the old test)."""
    out = src.with_name("corrected" + src.suffix)
    r = _run(["correct", cal, src, "--out", out, *options])
    assert r.exit_code == 0, r.output
    assert "Warning:" not in r.output  # the TCP is an identified point: nothing unknown
    true_tool = ",".join(f"{v!r}" for v in r1_true)
    extra = [*execute_options, "--true-tool", true_tool]
    before = _execute(truth, src, cal, extra)
    after = _execute(truth, out, cal, extra, intended=src)
    report = _report(out.with_name(out.name + ".report.csv"))
    old, new = read_program(src), read_program(out)
    errors, sigmas, q_exec = {}, {}, {}
    for t in old.targets:
        n = new.target(t.name)
        assert n.config == t.config, t.name  # configuration data unchanged
        assert after[t.name]["configuration"] == before[t.name]["configuration"], t.name  # same branch
        if t.kind == "joint":
            assert n.values == t.values and report[t.name]["status"] == "kept"  # taught joints and home kept
            assert after[t.name]["error_mm"] == pytest.approx(0.0, abs=1e-9)
            continue
        e0, e1 = before[t.name]["error_mm"], after[t.name]["error_mm"]
        sigma = float(report[t.name]["sigma_mm"])
        assert report[t.name]["status"] == "corrected"
        assert e1 < e0, (t.name, e0, e1)
        if effects == "ideal":
            assert e1 <= 3 * sigma, (t.name, e1, sigma)
            assert e1 <= 0.15, (t.name, e1)
        assert max(abs(a - b) for a, b in zip(after[t.name]["joints_deg"], before[t.name]["joints_deg"])) < 2.0
        errors[t.name], sigmas[t.name], q_exec[t.name] = (e0, e1), sigma, np.radians(after[t.name]["joints_deg"])
    assert len(errors) >= 3
    if effects != "ideal":
        names = list(errors)
        miss = np.linalg.norm(_realistic_miss(truth, cal, np.array([q_exec[n] for n in names])), axis=1)
        e1 = np.array([errors[n][1] for n in names])
        sig = np.array([sigmas[n] for n in names])
        assert np.all(np.abs(e1 - miss) <= 3 * sig), (names, e1, miss, sig)
        assert np.any(e1 > 3 * sig), (e1, sig)  # the effects are far above the noise: the old claim fails
    return errors


# front, wrist flipped (A5 < 0), arm back (overhead), arm back with the elbow down
KR150_Q = [[10, -80, 100, 5, 40, 20], [-25, -60, 85, -30, -60, -10], [41, -83, -87, -271, 63, 231],
           [-59, -66, -90, -210, 34, 82]]
KR150_BASE = [1500, -300, 400, 0, 0, 10]


@pytest.fixture(scope="module")
def kr150(tmp_path_factory):
    d = tmp_path_factory.mktemp("kr150")
    return d, *_campaign(d, "kuka_kr150_r3100", 1)


def _krl_files(d, tool, name="cell"):
    text, config_dat = krl_program("kuka_kr150_r3100", KR150_Q, [0, -90, 90, 0, 0, 0], tool, KR150_BASE)
    src, cdat = d / f"{name}.dat", d / f"{name}_config.dat"
    src.write_bytes(text.encode("latin-1"))
    cdat.write_bytes(config_dat.encode("latin-1"))
    return src, cdat


def test_krl_program_at_the_true_kr150(kr150, tmp_path):
    _, truth, cal, r1, r1_true = kr150
    src, cdat = _krl_files(tmp_path, [*r1, 0, 0, 0])
    errors = _judge(tmp_path, src, truth, cal, r1_true, ["--config-dat", cdat], ["--config-dat", cdat])
    assert min(e0 for e0, _ in errors.values()) > 1.0  # a real error to correct


def test_a_tool_the_calibration_never_saw_gets_a_warning_and_its_uncertainty(kr150, tmp_path):
    """A 250 mm gripper: the TCP depends on the last link, which the reflectors cannot separate from
    their own offsets. The correction says so (Warning: size, what to measure) and its sigma
    counts it; the true robot lands within 3 sigma. Sharper, from the hidden truth: the landing
    error equals the held parameters' error at the gripper, derived to first order
    (:func:`_gripper_lands_where_first_order_theory_says`), within 3 sigma of the noise part.
    Measured (seed 1): landing 0.270 / 0.262 / 0.273 / 0.290 mm, derived 0.266 mm each, noise
    sigma 0.013-0.015 mm, reported sigma with the unknown part ~0.74 mm."""
    _, truth, cal, _, _ = kr150
    src, cdat = _krl_files(tmp_path, [0, 0, 250, 0, 0, 0], "gripper")
    out = tmp_path / "gripper_corrected.dat"
    r = _run(["correct", cal, src, "--out", out, "--config-dat", cdat])
    assert r.exit_code == 0, r.output
    warning = next(line for line in r.output.splitlines() if line.startswith("Warning:"))
    assert "theta6" in warning and "d6" in warning and "mm" in warning and "Measure the actual tool" in warning
    before = _execute(truth, src, cal, ["--config-dat", cdat])
    after = _execute(truth, out, cal, ["--config-dat", cdat], intended=src)
    report = _report(out.with_name(out.name + ".report.csv"))
    for name in ("XP1", "XP2", "XP3", "XP4"):
        assert float(report[name]["unknown_mm"]) > 0.1
        assert after[name]["error_mm"] <= 3 * float(report[name]["sigma_mm"]), (name, after[name], report[name])
        assert after[name]["error_mm"] < before[name]["error_mm"]
    _gripper_lands_where_first_order_theory_says(truth, cal, before, after, report)


def _gripper_lands_where_first_order_theory_says(truth, cal, before, after, report, point=(0.0, 0.0, 250.0)):
    """The gripper's landing errors [mm] against the first-order miss from the hidden truth
    (``tracker_campaign_bias(..., point=)``: the held parameters at nominal and the campaign's
    effects, if any) within 3 sigma of the noise part ``sqrt(sigma^2 - unknown^2)`` of the report;
    the miss is far above that noise. Returns (landing errors, miss, noise sigma)."""
    from robocal.sim.first_order import tracker_campaign_bias

    from robocal.io.measurements import read_measurements

    names = ["XP1", "XP2", "XP3", "XP4"]
    t = json.loads(truth.read_text())
    result = json.loads((cal.parent / "result.json").read_text())
    q_train = read_measurements(truth.parent / t["simulation"]["measurements_file"]).joints
    estimated = [p["name"] for p in result["model_parameters"] if p["estimated"]]
    q_exec = np.radians([after[n]["joints_deg"] for n in names])
    miss = np.linalg.norm(tracker_campaign_bias(t, estimated, q_train, q_exec, point=list(point)), axis=1)
    e1 = np.array([after[n]["error_mm"] for n in names])
    sigma = np.array([float(report[n]["sigma_mm"]) for n in names])
    noise = np.sqrt(sigma**2 - np.array([float(report[n]["unknown_mm"]) for n in names]) ** 2)
    assert np.all(np.abs(e1 - miss) <= 3 * noise), (e1, miss, noise)
    assert np.all(e1 > 3 * noise), (e1, noise)  # the held parameters' error is far above the noise
    assert np.all(e1 < np.array([before[n]["error_mm"] for n in names]))
    return e1, miss, noise


@pytest.fixture(scope="module")
def kr150_realistic(tmp_path_factory):
    """The KR150 campaign on ``simulate tracker --effects realistic`` (seed 1), calibrated as
    :func:`_campaign` says."""
    d = tmp_path_factory.mktemp("kr150_realistic")
    return d, *_campaign(d, "kuka_kr150_r3100", 1, effects="realistic")


def test_krl_program_at_a_true_kr150_with_effects_the_model_lacks(kr150_realistic, tmp_path):
    """The KRL case on ``robocal simulate tracker --effects realistic`` (reducer transmission
    error, 20 ppm growth during the campaign, 5 ppm tracker scale; docs/testing.md): the true
    robot that runs the program has the same transmission error and is as warm as at the
    campaign's end. The landing errors match the first-order miss from the hidden truth within
    3 sigma; the ideal test's "within 3 sigma" is false here. Measured (seed 1): landing errors
    0.015 / 0.143 / 0.178 / 0.123 mm, first-order miss 0.020 / 0.139 / 0.191 / 0.135 mm, sigma
    0.012-0.016 mm (before correction: > 1 mm)."""
    _, truth, cal, r1, r1_true = kr150_realistic
    src, cdat = _krl_files(tmp_path, [*r1, 0, 0, 0])
    _judge(tmp_path, src, truth, cal, r1_true, ["--config-dat", cdat], ["--config-dat", cdat], effects="realistic")


def test_a_tool_the_calibration_never_saw_on_effects_the_model_lacks(kr150_realistic, tmp_path):
    """The 250 mm gripper on the realistic campaign. Its TCP is not a fitted point: its error has
    the part robocal reports as unknown (the last link's parameters, held at nominal, which the
    true robot does not have) and the campaign's effects. Both are derived from the hidden truth to
    first order (:func:`_gripper_lands_where_first_order_theory_says`: the held parameters'
    nominal values enter the fit's data and the gripper's prediction, the effects as in the KRL
    case). Tolerance: each landing error equals that miss within 3 sigma of the noise part
    (``sqrt(sigma^2 - unknown^2)``: the tracker's 0.02 mm carried through the fit). The ideal
    test's "within 3 sigma" (sigma with the unknown part, 0.74 mm here) is far looser. Measured
    (seed 1): landing 0.295 / 0.162 / 0.375 / 0.317 mm, first-order miss 0.297 / 0.164 / 0.386 /
    0.318 mm, noise sigma 0.014-0.016 mm (before correction: 3.3-4.2 mm)."""
    _, truth, cal, _, _ = kr150_realistic
    src, cdat = _krl_files(tmp_path, [0, 0, 250, 0, 0, 0], "gripper")
    out = tmp_path / "gripper_corrected.dat"
    r = _run(["correct", cal, src, "--out", out, "--config-dat", cdat])
    assert r.exit_code == 0, r.output
    assert any(line.startswith("Warning:") and "theta6" in line for line in r.output.splitlines())
    before = _execute(truth, src, cal, ["--config-dat", cdat])
    after = _execute(truth, out, cal, ["--config-dat", cdat], intended=src)
    _gripper_lands_where_first_order_theory_says(truth, cal, before, after,
                                                 _report(out.with_name(out.name + ".report.csv")))


def test_offline_joint_targets_are_corrected_only_when_asked_and_within_the_bound(kr150, tmp_path):
    _, truth, cal, r1, _ = kr150
    src, cdat = _krl_files(tmp_path, [*r1, 0, 0, 0])
    out = tmp_path / "c.dat"
    r = _run(["correct", cal, src, "--out", out, "--config-dat", cdat, "--joint-targets", "correct"])
    assert r.exit_code == 0, r.output
    home_old, home_new = read_program(src).target("XHOME").joints, read_program(out).target("XHOME").joints
    change = np.degrees(np.abs(home_new - home_old)).max()
    assert 1e-4 < change < 1.0
    r = _run(["correct", cal, src, "--out", tmp_path / "d.dat", "--config-dat", cdat, "--joint-targets", "correct",
              "--max-joint-change", "0.0001"])
    assert r.exit_code == 5 and "XHOME" in r.output and "bound" in r.output


def test_programs_that_do_not_fit_the_robot_are_refused(kr150, tmp_path):
    _, _, cal, _, _ = kr150
    ur = tmp_path / "pick.script"
    ur.write_text("def pick():\n  movej([0.1, -1.5, 1.5, -1.5, -1.5, 0.0])\nend\n")
    r = _run(["correct", cal, ur, "--out", tmp_path / "x.script"])
    assert r.exit_code == 1 and "UR script" in r.output and "kuka_kr150_r3100" in r.output
    krl = tmp_path / "seven.dat"
    krl.write_text("DEFDAT seven\nDECL E6AXIS XH={A1 0.0,A2 -90.0,A3 90.0,A4 0.0,A5 0.0,A6 0.0}\nENDDAT\n")
    src, _ = _krl_files(tmp_path, [0, 0, 250, 0, 0, 0])
    r = _run(["correct", cal, src, "--out", tmp_path / "y.dat"])  # TOOL_DATA[1] without values
    assert r.exit_code == 1 and "TOOL_DATA[1]" in r.output and "--config-dat" in r.output


def test_fk_prints_the_base_frame_by_default(kr150):
    _, _, cal, _, _ = kr150
    q = ["0", "-90", "90", "0", "30", "0"]
    base = json.loads(_run(["fk", cal, *q, "--deg", "--json"]).output)
    world = json.loads(_run(["fk", cal, *q, "--deg", "--json", "--frame", "world"]).output)
    tool = json.loads(_run(["fk", cal, *q, "--deg", "--json", "--tool", "0,0,200"]).output)
    model = load_robot(cal)
    T_world = model.fk(np.radians([0, -90, 90, 0, 30, 0]))
    assert base["frame"] == "base" and np.allclose(base["position_mm"], (np.linalg.inv(model.T_world_base) @ T_world)[:3, 3])
    assert np.linalg.norm(np.subtract(base["position_mm"], [1965, 0, 1984])) < 250  # near nominal, not the tracker's
    assert np.allclose(world["position_mm"], T_world[:3, 3])
    assert abs(np.linalg.norm(np.subtract(tool["position_mm"], base["position_mm"])) - 200.0) < 1e-9


def test_a_ur_waypoint_used_in_two_configurations_is_flagged(tmp_path):
    """One pose variable reached from two different current joints (UR: nearest solution) lands in two
    arm configurations; one corrected value cannot serve both."""
    nom = load_robot("ur10")
    q1, q2 = np.radians([-30, -100, 100, -90, -90, 0]), np.radians([-30, -100, 100, 80, 90, -160])  # wrist flipped
    T = nom.fk(np.radians([-25, -95, 100, -95, -90, 10]))
    pv = ", ".join(f"{v:.7f}" for v in [*(T[:3, 3] / 1000), *rotvec_from_matrix(T[:3, :3])])
    j = lambda q: ", ".join(f"{v:.6f}" for v in q)  # noqa: E731
    src = tmp_path / "two.script"
    src.write_text(f"def two():\n  global wp_p=p[{pv}]\n  movej([{j(q1)}])\n  movel(wp_p)\n  movej([{j(q2)}])\n"
                   "  movel(wp_p)\nend\n")
    model = tmp_path / "cal.toml"
    from robocal.robots import save_robot
    from robocal.sim import VirtualRobot

    save_robot(VirtualRobot.perturbed(nom, np.random.default_rng(3)).true_model, model)
    r = _run(["correct", model, src, "--out", tmp_path / "out.script"])
    assert r.exit_code == 5 and "two configurations" in r.output


@pytest.mark.parametrize("effects", ["ideal", "realistic"])
def test_rapid_program_at_the_true_irb140(tmp_path, effects):
    """``realistic``: as the KRL case with effects, a RAPID module (tool data, work object,
    confdata) run by the virtual controller on the true IRB 140 that carries the campaign's
    transmission error and is grown by 20 ppm. Tolerance: each landing error equals the
    first-order miss ``|e - J delta|`` derived from the hidden truth (``_realistic_miss``: the
    bias ``delta = J^+ e`` the effects put into the fit, then what the effects and that bias leave
    at the executed joints) within 3 sigma, sigma the corrected target's reported noise part
    (``--noise 0.02``: not scaled by the misfit, so it is the tracker's 0.02 mm carried through
    the fit); some target must miss by more than 3 sigma. Measured (seed 2): landing 0.076 / 0.070
    / 0.100 / 0.050 mm, first-order miss 0.057 / 0.059 / 0.103 / 0.047 mm, sigma 0.012-0.013 mm."""
    d = tmp_path / "campaign"
    d.mkdir()
    truth, cal, r1, r1_true = _campaign(d, "abb_irb140", 2, effects=effects)
    q = [[10, 20, 10, 5, 40, 20], [-20, 30, -10, -30, -60, -10], [-73, -67, -124, 53, -50, 33],
         [100, -45, -110, 30, 60, -40]]
    src = tmp_path / "cell.mod"
    src.write_text(rapid_program("abb_irb140", q, [0, 0, 0, 0, 30, 0], [*r1, 0, 0, 0], [500, -100, 300, 0, 0, 20]))
    _judge(tmp_path, src, truth, cal, r1_true, [], effects=effects)


@pytest.mark.parametrize("effects", ["ideal", "realistic"])
def test_fanuc_program_at_the_true_r2000ic(tmp_path, effects):
    """``realistic``: as the RAPID case, a FANUC TP program (UTOOL / UFRAME given as options,
    CONFIG strings) on the true R-2000iC with the campaign's effects; the same tolerance (landing
    error = first-order miss from the hidden truth within 3 sigma of the noise part; some target
    beyond 3 sigma). Measured (seed 2): landing 0.366 / 0.353 / 0.088 / 0.185 mm, first-order miss
    0.366 / 0.352 / 0.092 / 0.189 mm, sigma 0.012-0.014 mm."""
    d = tmp_path / "campaign"
    d.mkdir()
    truth, cal, r1, r1_true = _campaign(d, "fanuc_r2000ic_165f", 2, effects=effects)
    q = [[10, 10, 10, 5, 40, 20], [-20, 20, -10, -30, -60, -10], [112, -20, 94, -284, 88, -71],
         [-70, 13, 117, 162, -60, 124]]
    base = [1200, -200, 300, 0, 0, 15]
    src = tmp_path / "cell.ls"
    src.write_text(fanuc_program("fanuc_r2000ic_165f", q, [0, 0, 0, 0, -90, 0], [*r1, 0, 0, 0], base))
    frames = ["--tool", ",".join(repr(v) for v in [*r1, 0, 0, 0]), "--base", ",".join(str(v) for v in base)]
    _judge(tmp_path, src, truth, cal, r1_true, frames, frames, effects=effects)
    r = _run(["correct", cal, src, "--out", tmp_path / "x.ls"])  # UTOOL 1 / UFRAME 1 without values
    assert r.exit_code == 1 and "Error:" in r.output and "UTOOL 1" in r.output


@pytest.mark.parametrize("effects", ["ideal", "realistic"])
def test_urscript_program_at_the_true_ur10(tmp_path, effects):
    """``realistic``: as the KRL case with effects (the landing errors against the first-order
    miss). Measured (seed 3): landing 0.174 / 0.176 / 0.170 / 0.010 mm, first-order miss
    0.206 / 0.208 / 0.190 / 0.007 mm, sigma 0.011-0.021 mm."""
    d = tmp_path / "campaign"
    d.mkdir()
    truth, cal, r1, r1_true = _campaign(d, "ur10", 3, effects=effects)
    home = [-30, -100, 100, -90, -90, 0]
    moves = [("j", home), ("l", [-30, -104, 112, -98, -90, 10]), ("l", [-20, -90, 100, -100, -90, 20]),
             ("j", [-20, -90, 100, -100, 60, 20]), ("l", [-15, -95, 100, -95, 70, 10]),   # wrist flipped
             ("j", [150, -80, -100, -90, 90, 0]), ("l", [155, -85, -95, -85, 80, 10]),  # arm turned back
             ("j", home)]
    src = tmp_path / "cell.script"
    src.write_text(ur_program("ur10", moves, [*r1, 0, 0, 0]))
    _judge(tmp_path, src, truth, cal, r1_true, [], effects=effects)


def test_target_orientations_are_checked_against_their_taught_joints(kr150, tmp_path):
    """Radians under a deg header, or KUKA A, B, C declared as FANUC W, P, R: refused, naming what fits."""
    _, _, cal, _, _ = kr150
    nom = load_robot("kuka_kr150_r3100")
    q = np.radians(KR150_Q)
    T = nom.fk(q)

    def targets_file(name, values, unit, convention):
        head = ["# format: robocal-targets/1", "# length_unit: mm", f"# angle_unit: {unit}",
                f"# orientation: {convention}", "# frame: base", "name,x,y,z,rx,ry,rz,A1,A2,A3,A4,A5,A6"]
        rows = [f"P{k},{','.join(repr(float(v)) for v in [*T[k, :3, 3], *values[k]])},"
                + ",".join(repr(float(v)) for v in np.degrees(q[k])) for k in range(len(q))]
        (tmp_path / name).write_text("\n".join(head + rows) + "\n")
        return tmp_path / name

    abc = np.array([euler_from_matrix(t[:3, :3], "kuka_abc") for t in T])  # [rad]
    ok = _run(["correct", cal, targets_file("ok.csv", np.degrees(abc), "deg", "kuka_abc"), "--out", tmp_path / "o.csv"])
    assert ok.exit_code == 0, ok.output
    r = _run(["correct", cal, targets_file("rad.csv", abc, "deg", "kuka_abc"), "--out", tmp_path / "r.csv"])
    assert r.exit_code == 1 and "'# angle_unit: rad'" in r.output and "taught joints" in r.output
    r = _run(["correct", cal, targets_file("wpr.csv", np.degrees(abc), "deg", "fanuc_wpr"), "--out", tmp_path / "w.csv"])
    assert r.exit_code == 1 and "'# orientation: kuka_abc'" in r.output


def test_turn_bits_are_rewritten_when_a_correction_crosses_zero(kr150, tmp_path):
    """A4 and A6 taught at -0.03 deg: the correction moves them past 0, so KUKA's T (turn) bits must
    change for the controller to pick the corrected joints; S and the branch stay."""
    _, truth, cal, r1, r1_true = kr150
    text, config_dat = krl_program("kuka_kr150_r3100", [[-25, -60, 85, -0.03, -60, -0.03]], [0, -90, 90, 0, 0, 0],
                                   [*r1, 0, 0, 0], KR150_BASE)
    src, cdat = tmp_path / "turn.dat", tmp_path / "turn_config.dat"
    src.write_text(text)
    cdat.write_text(config_dat)
    out = tmp_path / "turn_corrected.dat"
    r = _run(["correct", cal, src, "--out", out, "--config-dat", cdat])
    assert r.exit_code == 0, r.output
    old, new = read_program(src).target("XP1"), read_program(out).target("XP1")
    assert new.config["S"] == old.config["S"] and new.config["T"] != old.config["T"]
    extra = ["--config-dat", cdat, "--true-tool", ",".join(repr(v) for v in r1_true)]
    before = _execute(truth, src, cal, extra)["XP1"]
    after = _execute(truth, out, cal, extra, intended=src)["XP1"]
    assert after["configuration"] == before["configuration"]
    assert after["error_mm"] < 0.15 < before["error_mm"]
    q_new = np.radians(after["joints_deg"])
    assert configuration_text(new, "krl", q_new, arm_signature(load_robot("kuka_kr150_r3100"), q_new)[0]) == \
        {"S": new.config["S"], "T": new.config["T"]}


def test_a_rapid_target_used_with_two_tools_is_flagged(tmp_path):
    text = rapid_program("abb_irb140", [[10, 20, 10, 5, 40, 20]], [0, 0, 0, 0, 30, 0], [0, 0, 150, 0, 0, 0],
                         [500, -100, 300, 0, 0, 20])
    text = text.replace("  ENDPROC", "    MoveL p1,v100,fine,tool0;\n  ENDPROC")
    src = tmp_path / "two.mod"
    src.write_text(text)
    assert read_program(src).target("p1").other_frames == (("tool0", "wobj0"),)
    model = tmp_path / "cal.toml"
    from robocal.robots import save_robot
    from robocal.sim import VirtualRobot

    save_robot(VirtualRobot.perturbed(load_robot("abb_irb140"), np.random.default_rng(3)).true_model, model)
    r = _run(["correct", model, src, "--out", tmp_path / "out.mod"])
    assert r.exit_code == 5 and "two configurations" in r.output and "tSmr/wTable, tool0/wobj0" in r.output


def test_fanuc_flip_reads_as_published():
    """Strybis, "The perils of six-axis robots" (onerobotics.com, 2013), R-2000iB/165F: one pose is
    'NUT 000' at J1..J6 = 7.962, -5.284, -36.250, 77.661, -51.975, -79.273 deg and 'FUT 000' at
    J4, J5, J6 = -102.339, 51.975, 100.727 deg."""
    from robocal.io.programs.configuration import configuration_of

    model = load_robot("fanuc_r2000ic_165f")
    nut = np.radians([7.962, -5.284, -36.250, 77.661, -51.975, -79.273])
    fut = np.radians([7.962, -5.284, -36.250, -102.339, 51.975, 100.727])
    sig = arm_signature(model, np.stack([nut, fut]))
    for text, ok in (("N U T, 0, 0, 0", [True, False]), ("F U T, 0, 0, 0", [False, True])):
        cfg = configuration_of(_Config({"CONFIG": text}), "fanuc")
        assert cfg.matches(sig, np.stack([nut, fut])).tolist() == ok
    assert configuration_text(_Config({"CONFIG": ""}), "fanuc", nut, sig[0])["CONFIG"] == "N U T, 0, 0, 0"
    assert configuration_text(_Config({"CONFIG": ""}), "fanuc", fut, sig[1])["CONFIG"] == "F U T, 0, 0, 0"
