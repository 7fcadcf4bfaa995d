"""File-to-file workflows through the command line: simulate -> calibrate -> correct.

Robot files written by ``save_robot`` round-trip exactly; a simulated UR10 campaign calibrates to
the noise floor on held-out poses and agrees with the hidden truth; bad input ends in one
``Error:`` line; corrected joint targets put the real (true) robot on its targets.
"""

import json
import re

import numpy as np
import pytest
from click.testing import CliRunner

from robocal.calib.outputs import corrected_joint_targets
from robocal.cli import main
from robocal.robots import list_robots, load_robot, save_robot
from robocal.robots.loader import frame_from_xyz_rpy
from robocal.transforms import pose_from_transform

SEED = 11


def run(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


def one_error_line(r, *needles):
    assert r.exit_code != 0, r.output
    lines = [line for line in r.output.strip().splitlines() if line]
    assert len(lines) == 1 and lines[0].startswith("Error:"), r.output
    for n in needles:
        assert n in lines[0], lines[0]
    return lines[0]


def random_joints(model, n, seed):
    lo, hi = np.where(np.isfinite(model.limits), model.limits, [-3.0, 3.0]).T
    return np.random.default_rng(seed).uniform(lo, hi, (n, model.n_joints))


# ------------------------------------------------------------------------------------ robot files
@pytest.mark.parametrize("name", list_robots())
def test_save_robot_round_trip_is_exact(tmp_path, name):
    m = load_robot(name)
    m2 = load_robot(save_robot(m, tmp_path / f"{name}.toml"))
    assert m2.params.names == m.params.names
    assert np.array_equal(m2.params.values, m.params.values)
    assert np.array_equal(m2.params.free, m.params.free)
    assert np.array_equal(m2.coupling, m.coupling) and np.array_equal(m2.limits, m.limits)
    assert m2.controller_joints == m.controller_joints and m2.kind == m.kind
    assert [e.name for e in m2.end_effectors] == [e.name for e in m.end_effectors]
    assert m2.extra["length_unit"] == m.extra["length_unit"] and m2.extra["angle_unit"] == m.extra["angle_unit"]
    q = random_joints(m, 40, 0)
    assert np.array_equal(m2.fk_all(q), m.fk_all(q))


def test_save_robot_with_base_tool_and_changed_values(tmp_path):
    m = load_robot("kuka_kr150_r3100")
    rng = np.random.default_rng(1)
    m = m.with_params(m.params.values + rng.normal(0, 1e-3, len(m.params)))
    base = frame_from_xyz_rpy([2100.5, -300.25, 12.0], np.radians([0.3, -1.1, 120.0]))
    tool = frame_from_xyz_rpy([10.0, -5.0, 230.0], np.radians([0.0, 90.0, 0.0]))
    m = m.replace(T_world_base=base, end_effectors=[m.end_effectors[0].__class__("tool", len(m.links) - 1, tool)])
    p = save_robot(m, tmp_path / "r.toml")
    m2 = load_robot(p)
    # arbitrary radians have no exact degree twin: equal to the last bit or two
    v, v2 = m.params.values, m2.params.values
    assert np.all(np.abs(v2 - v) <= 2 * np.spacing(np.abs(v)))
    q = random_joints(m, 40, 2)
    assert np.abs(m2.fk(q) - m.fk(q)).max() < 1e-9
    assert m2.end_effectors[0].name == "tool"
    with pytest.raises(FileExistsError):
        save_robot(m, p)
    save_robot(m, p, overwrite=True)


# ------------------------------------------------------------------------------------ end to end
@pytest.fixture(scope="module")
def campaign(tmp_path_factory):
    d = tmp_path_factory.mktemp("ur10")
    csv = d / "ur10.csv"
    r = run("simulate", "tracker", "ur10", "--poses", 100, "--noise", 0.02, "--seed", SEED, "--out", csv)
    assert r.exit_code == 0, r.output
    out = d / "cal"
    r = run("calibrate", "ur10", csv, "--out", out, "--holdout", 0.25, "--seed", 3)
    assert r.exit_code == 0, r.output
    return {"dir": d, "csv": csv, "truth": json.loads((d / "ur10.truth.json").read_text()), "out": out,
            "result": json.loads((out / "result.json").read_text()), "output": r.output}


def true_model(truth):
    nominal = load_robot(truth["robot"])
    values = np.array([truth["true_parameters"][n] for n in nominal.params.names])
    return nominal.with_params(values).replace(T_world_base=np.array(truth["T_tracker_base"]))


def test_calibration_reaches_the_noise_floor_on_held_out_poses(campaign):
    res = campaign["result"]
    val = res["validation"]
    assert val["n_poses"] == 25
    assert val["before"]["rms"] > 0.5
    assert val["after"]["rms"] < 0.05
    assert res["solver"]["converged"]
    assert res["residuals"]["after"]["rms"] < 0.05 < 0.5 < res["residuals"]["before"]["rms"]
    assert "held-out poses, after" in campaign["output"]
    for name in ("result.json", "calibrated_robot.toml", "calibrated_robot.urdf", "report.html"):
        assert (campaign["out"] / name).stat().st_size > 500
    html = (campaign["out"] / "report.html").read_text()
    assert html.count('<div class="fig"') >= 4 and "Parameters not identifiable" in html
    # the per-pose figure draws one bar per calibration pose and set (before and after)
    per_pose = html.split('aria-label="error per pose">')[1].split("</div>")[0].split("<svg xmlns")[1]
    bar_groups = re.findall(r'<g fill="[^"]*" fill-opacity="[^"]*">(.*?)</g>', per_pose)
    rows = (campaign["out"] / "residuals.csv").read_text().splitlines()
    assert rows[0] == "set,pose_id,target,error_before_mm,error_after_mm"
    n_train = len({r.split(",")[1] for r in rows[1:] if r.startswith("calibration,")})
    assert [g.count("<rect ") for g in bar_groups] == [n_train, n_train]


def test_per_pose_arrays_are_in_csv_side_files(campaign):
    """result.json holds summaries and names the side files; the per-point errors and the accuracy
    map are in residuals.csv / accuracy_map.csv, one row per point / pose, and agree with the summaries."""
    res, out = campaign["result"], campaign["out"]
    assert "per_point" not in res["residuals"] and "per_point" not in res["validation"]
    ref = res["residuals"]["per_point_file"]
    assert ref["file"] == "residuals.csv" and ref["set"] == "calibration"
    rows = [r.split(",") for r in (out / "residuals.csv").read_text().splitlines()[1:]]
    cal = [r for r in rows if r[0] == "calibration"]
    hold = [r for r in rows if r[0] == "holdout"]
    assert len(cal) == ref["n"] and len(hold) == res["validation"]["per_point_file"]["n"]
    after = np.array([float(r[4]) for r in cal])
    # 6 significant digits in the file: the RMS agrees with result.json to ~1e-6 relative
    assert np.sqrt(np.mean(after**2)) == pytest.approx(res["residuals"]["after"]["rms"], rel=1e-5)
    amap = res["accuracy_map"]
    assert amap["file"] == "accuracy_map.csv" and "predicted_std_mm" not in amap
    arows = (out / "accuracy_map.csv").read_text().splitlines()
    assert arows[0] == "pose_id,flange_x_mm,flange_y_mm,flange_z_mm,predicted_std_mm"
    assert len(arows) - 1 == amap["n_poses"] == res["metadata"]["n_poses_file"]
    std = np.array([float(r.split(",")[4]) for r in arows[1:]])
    assert std.max() == pytest.approx(amap["statistics"]["max"], rel=1e-5)


def test_result_agrees_with_the_truth(campaign):
    res, truth = campaign["result"], campaign["truth"]
    dropped = res["identifiability"]["dropped"]
    # parameters that absorb a dropped one (d2 takes d3 + d4 on parallel axes) have no "true" value
    partners = {p["name"] for d in dropped for p in d["trades_off_with"]}
    checked = 0
    for p in res["parameters"]:
        if p["block"] != "geometry" or not p["identifiable"] or p["name"] in partners:
            continue
        err = p["value"] - truth["true_parameters"][p["name"]]
        assert abs(err) < 4 * p["std"], (p["name"], err, p["std"])
        checked += 1
    assert checked >= 12
    # the gauge-free check: the calibrated robot file predicts the true reflector positions
    cal = load_robot(campaign["out"] / "calibrated_robot.toml")
    true = true_model(truth)
    q = random_joints(load_robot("ur10"), 200, 5) * 0.5
    refl = np.array(res["targets"][0]["point_mm"])
    p_cal = cal.fk(q)[:, :3, :3] @ refl + cal.fk(q)[:, :3, 3]
    p_true = true.fk(q)[:, :3, :3] @ np.array(truth["reflectors_mm"][0]) + true.fk(q)[:, :3, 3]
    assert np.sqrt(np.mean(np.sum((p_cal - p_true) ** 2, axis=1))) < 0.03
    # the reported std of the base position is consistent with its spread (and the numbers are there)
    assert res["bases"][0]["T_instrument_base"][3] == [0.0, 0.0, 0.0, 1.0]
    assert len(res["covariance"]["names"]) == res["solver"]["rank"]


def test_existing_outputs_are_never_overwritten(campaign):
    before = (campaign["out"] / "result.json").read_bytes()
    one_error_line(run("calibrate", "ur10", campaign["csv"], "--out", campaign["out"]), "result.json", "--overwrite")
    assert (campaign["out"] / "result.json").read_bytes() == before
    one_error_line(run("simulate", "tracker", "ur10", "--poses", 10, "--seed", 1, "--out", campaign["csv"]),
                   "ur10.csv", "exists")


def _rewrite(src, dst, fn):
    lines = src.read_text().splitlines()
    dst.write_text("\n".join(fn(lines)) + "\n")
    return dst


def test_bad_input_gives_one_clear_error_line(campaign, tmp_path):
    csv = campaign["csv"]
    one_error_line(run("calibrate", "ur10", tmp_path / "nope.csv", "--out", tmp_path / "o"), "nope.csv")
    # a file whose joint columns are not the robot's
    bad = _rewrite(csv, tmp_path / "joints.csv", lambda ls: [l.replace(",J6,", ",J7,") if l.startswith("pose,") else l
                                                               for l in ls])
    one_error_line(run("calibrate", "ur10", bad, "--out", tmp_path / "o"), "joints.csv", "J6")
    # the file of another robot
    one_error_line(run("calibrate", "kuka_kr150_r3100", csv, "--out", tmp_path / "o"), "ur10.csv")

    # metres written into a file that declares millimetres
    def to_metres(lines):
        out = []
        for l in lines:
            if l[:1].isdigit():
                f = l.split(",")
                f[7:10] = [repr(float(v) / 1000.0) for v in f[7:10]]
                l = ",".join(f)
            out.append(l)
        return out

    one_error_line(run("calibrate", "ur10", _rewrite(csv, tmp_path / "metres.csv", to_metres), "--out",
                       tmp_path / "o"), "metres.csv", "length_unit: m")
    few = _rewrite(csv, tmp_path / "few.csv", lambda ls: [l for l in ls if not l[:1].isdigit()] +
                   [l for l in ls if l[:1].isdigit()][:8])
    one_error_line(run("calibrate", "ur10", few, "--out", tmp_path / "o"), "too few poses")
    one_error_line(run("calibrate", "ur10", csv, "--out", tmp_path / "o", "--free", "a2,b7"), "b7")
    one_error_line(run("calibrate", "ur10", csv, "--out", tmp_path / "o", "--holdout", 1.5), "--holdout")
    assert not (tmp_path / "o" / "result.json").exists()


# ------------------------------------------------------------------------------------ corrected targets
def test_corrected_targets_put_the_true_robot_on_its_targets(campaign):
    truth = campaign["truth"]
    true, nominal = true_model(truth), load_robot("ur10")
    q_taught = random_joints(nominal, 30, 9) * 0.6
    T = nominal.replace(T_world_base=true.T_world_base).fk(q_taught)  # where the programs want the flange
    c = corrected_joint_targets(true, nominal, T, q_seed=q_taught)
    assert c.all_converged
    reached = true.fk(c.q)
    assert np.abs(reached[:, :3, 3] - T[:, :3, 3]).max() < 1e-6
    assert np.abs(reached[:, :3, :3] - T[:, :3, :3]).max() < 1e-9
    # the nominal solution is the taught pose; the correction is the calibration's millimetres
    assert np.abs(c.q_nominal - q_taught).max() < 1e-9
    shift = np.linalg.norm(c.T_filtered_world[:, :3, 3] - T[:, :3, 3], axis=1)
    assert 0.1 < shift.max() < 20.0
    # a nominal-model controller given the filtered targets computes the corrected joints
    assert np.allclose(nominal.fk(c.q), c.T_filtered, atol=1e-9)
    # position-only targets without a seed
    c2 = corrected_joint_targets(true, nominal, T[:, :3, 3])
    assert c2.all_converged and np.abs(true.fk(c2.q)[:, :3, 3] - T[:, :3, 3]).max() < 1e-6


def test_correct_command_with_the_calibrated_robot_file(campaign, tmp_path):
    robot_file = campaign["out"] / "calibrated_robot.toml"
    cal, nominal = load_robot(robot_file), load_robot("ur10")
    q_taught = random_joints(nominal, 6, 4) * 0.6
    T = cal.fk(q_taught + 0.001)
    pose = pose_from_transform(T, "kuka_abc", length_unit="mm", angle_unit="deg")
    lines = ["# format: robocal-targets/1", "# length_unit: mm", "# angle_unit: deg", "# orientation: kuka_abc",
             "# frame: world", "name,x,y,z,rx,ry,rz," + ",".join(nominal.controller_joints)]
    for i in range(len(T)):
        lines.append(",".join([f"P{i}", *(repr(float(v)) for v in pose[i]),
                               *(repr(float(v)) for v in np.degrees(q_taught[i]))]))
    targets = tmp_path / "targets.csv"
    targets.write_text("\n".join(lines) + "\n")
    out = tmp_path / "corrected.csv"
    r = run("correct", robot_file, targets, "--out", out)
    assert r.exit_code == 0, r.output
    rows = [l.split(",") for l in out.read_text().splitlines() if not l.startswith("#")]
    header, rows = rows[0], rows[1:]
    assert header[:7] == ["name", "J1", "J2", "J3", "J4", "J5", "J6"] and len(rows) == 6
    q = np.radians(np.array([[float(v) for v in row[1:7]] for row in rows]))
    assert all(row[header.index("converged")] == "yes" for row in rows)
    assert np.abs(cal.fk(q)[:, :3, 3] - T[:, :3, 3]).max() < 1e-6
    one_error_line(run("correct", robot_file, targets, "--out", out), "corrected.csv", "exists")
    bad = tmp_path / "bad.csv"
    bad.write_text(targets.read_text().replace("# orientation: kuka_abc\n", ""))
    one_error_line(run("correct", robot_file, bad, "--out", tmp_path / "x.csv"), "bad.csv", "orientation")
    no_frame = tmp_path / "no_frame.csv"  # issue 27: a targets file must say its frame
    no_frame.write_text(targets.read_text().replace("# frame: world\n", ""))
    one_error_line(r := run("correct", robot_file, no_frame, "--out", tmp_path / "y.csv"), "no_frame.csv", "frame")
    assert "# frame: world" in r.output and "# frame: base" in r.output
