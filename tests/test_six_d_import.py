"""Issue 31, acceptance: a user's 6-D campaign from the vendors' exports to the result with no
hand edits. A UR10 carries a 6-DoF probe (a Leica T-Mac-like export: semicolon CSV, decimal comma,
``Rx, Ry, Rz [deg]`` fixed-axis angles, quote-prefixed time stamps); the controller's joints come
from a UR RTDE log (``timestamp actual_q_0 .. actual_q_5``, radians). ``robocal import`` and
``robocal calibrate`` must recover the simulator's hidden probe rotation within 3 sigma and report
orientation errors; a KUKA log streamed at 10 Hz pairs by time with a one-line summary.
"""

import json
from datetime import datetime, timedelta

import numpy as np
import pytest
from click.testing import CliRunner

from robocal.cli import main
from robocal.robots import load_robot
from robocal.sim.six_d_exports import (
    EXPORT_T0,
    PROBE_SIGMA_MM,
    PROBE_W_MM_PER_RAD,
    probe_campaign,
    probe_tool,
    read_corrected_joints,
    write_leica_tmac,
    write_pose_targets,
    write_rtde_log,
)
from robocal.transforms import so3_log

SIGMA_MM = PROBE_SIGMA_MM
W = PROBE_W_MM_PER_RAD  # mm per rad: the CLI's default rotation weight (0.02 mm ~ 0.0115 deg)
T0 = EXPORT_T0
true_tool = probe_tool
write_leica, write_rtde = write_leica_tmac, write_rtde_log  # the exports' writers (robocal.sim.six_d_exports)


def run(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


def simulate(n=60, seed=11, truth=False, effects=False):
    """Joints and measured probe poses (N, 4, 4) in the tracker frame (and, with ``truth``, the
    virtual robot and the tracker's frame T_inst): :func:`robocal.sim.six_d_exports.probe_campaign`.
    With ``effects`` and ``truth`` the noise-free measured poses are returned last."""
    c = probe_campaign(n, seed, effects=effects)
    if effects and truth:
        return c["q"], c["T"], c["virtual"], c["T_inst"], c["rng"], c["T_free"]
    return (c["q"], c["T"], c["virtual"], c["T_inst"], c["rng"]) if truth else (c["q"], c["T"])


def _stamp(t: datetime) -> str:
    return t.strftime("%d.%m.%Y %H:%M:%S.") + f"{t.microsecond // 1000:03d}"


@pytest.fixture(scope="module")
def campaign(tmp_path_factory):
    d = tmp_path_factory.mktemp("sixd_import")
    q, T, virtual, T_inst, rng = simulate(truth=True)
    times = [T0 + timedelta(seconds=4.0 * k) for k in range(len(q))]
    leica = write_leica(d / "tmac.csv", T, times)
    rtde = write_rtde(d / "rtde.csv", q)
    imp = run("import", leica, "--joints", rtde, "--robot", "ur10", "--orientation", "rpy", "--out", d / "m.csv")
    cal = run("calibrate", "ur10", d / "m.csv", "--out", d / "cal", "--sigma", SIGMA_MM)
    return {"dir": d, "q": q, "T": T, "virtual": virtual, "T_inst": T_inst, "rng": rng, "import": imp, "calibrate": cal, "leica": leica, "rtde": rtde,
            "result": json.loads((d / "cal" / "result.json").read_text()) if (d / "cal" / "result.json").exists()
            else None}


def test_import_writes_the_orientations(campaign):
    r = campaign["import"]
    assert r.exit_code == 0, r.output
    assert "60 pose(s) paired; 0 point(s) and 0 joint row(s) not paired" in r.output
    assert "(positions and orientations)" in r.output
    text = (campaign["dir"] / "m.csv").read_text()
    assert "# orientation: rpy" in text
    # joint values in the unit's precision: no conversion noise such as 255.37100000000004
    row = text.split("\n")[text.split("\n").index(next(x for x in text.split("\n") if x.startswith("pose,"))) + 1]
    assert all(len(c.split(".")[-1]) <= 13 for c in row.split(",")[1:]), row


def test_six_d_calibration_recovers_the_probe_rotation_within_3_sigma(campaign):
    r = campaign["calibrate"]
    assert r.exit_code == 0, r.output
    res = campaign["result"]
    tf = res["tool_frame"]
    T = np.array(tf["T_flange_measured"])
    err = so3_log(T[:3, :3] @ true_tool()[:3, :3].T)
    std = np.array(tf["std_rotvec_rad"])
    assert np.all(std > 0) and np.all(std < 1e-3), std
    assert np.all(np.abs(err) < 3 * std), (err, std)


@pytest.fixture(scope="module")
def realistic(tmp_path_factory):
    """The exports of :func:`campaign` with the ``realistic`` campaign effects (reducer
    transmission error, 20 ppm growth during the campaign, 5 ppm tracker scale; docs/testing.md),
    imported and calibrated with the noise given (``--sigma``: sigma not scaled by the misfit),
    every pose trained (``--holdout 0``), and the first-order bias of that fit derived from the
    hidden truth (tests/_first_order.py ``six_d_fit_bias``)."""
    from _first_order import six_d_fit_bias

    d = tmp_path_factory.mktemp("sixd_realistic")
    q, T, virtual, T_inst, _, T_free = simulate(truth=True, effects=True)
    times = [T0 + timedelta(seconds=4.0 * k) for k in range(len(q))]
    leica, rtde = write_leica(d / "tmac.csv", T, times), write_rtde(d / "rtde.csv", q)
    r = run("import", leica, "--joints", rtde, "--robot", "ur10", "--orientation", "rpy", "--out", d / "m.csv")
    assert r.exit_code == 0, r.output
    r = run("calibrate", "ur10", d / "m.csv", "--out", d / "cal", "--sigma", SIGMA_MM, "--holdout", 0, "--no-report")
    assert r.exit_code == 0, r.output
    res = json.loads((d / "cal" / "result.json").read_text())
    estimated = [p["name"] for p in res["model_parameters"] if p["estimated"]]
    fit = (virtual.true_model, estimated, q, T_inst, true_tool(), T_free, W)
    return {"dir": d, "q": q, "virtual": virtual, "T_inst": T_inst, "result": res, "estimated": estimated,
            "fit": fit, "bias": six_d_fit_bias(*fit)}


def test_exports_with_effects_the_model_lacks_give_the_probe_rotation_within_3_sigma_of_its_bias(realistic):
    """On :func:`realistic`: rotation within 3 sigma and origin within 4 sigma of truth + bias;
    the residual RMS within 10 % of the first-order misfit plus the noise and above twice the
    noise (the effects are visible). Measured: rotation |z| 1.8 / 0.8 / 2.6 after the bias
    (1.8 / 0.9 / 2.3 plain), origin |z| <= 0.6; residual RMS 0.0768 mm against 0.0787 predicted
    (ratio 0.98) and 0.035 mm of noise."""
    res, bias, q = realistic["result"], realistic["bias"], realistic["q"]
    tf = res["tool_frame"]
    T_fit = np.array(tf["T_flange_measured"])
    err = so3_log(T_fit[:3, :3] @ true_tool()[:3, :3].T)
    std, std_xyz = np.array(tf["std_rotvec_rad"]), np.array(tf["std_xyz_mm"])
    origin_err = T_fit[:3, 3] - true_tool()[:3, 3]
    n_var = len(realistic["estimated"]) + 12  # the noise part keeps the fraction 1 - variables / residuals
    rms_pred = np.hypot(bias["residual_rms_mm"], SIGMA_MM * np.sqrt(3 * (1 - n_var / (6 * len(q)))))
    rms = res["residuals"]["after"]["rms"]
    assert np.all(np.abs(err - bias["tool_rotvec"]) < 3 * std), (err, bias["tool_rotvec"], std)
    assert np.all(np.abs(origin_err - bias["tool_xyz"]) < 4 * std_xyz), (origin_err, bias["tool_xyz"], std_xyz)
    assert 0.9 < rms / rms_pred < 1.1, (rms, rms_pred)
    assert rms > 2 * SIGMA_MM * np.sqrt(3), rms


def test_orientation_errors_printed_and_in_result_json(campaign):
    out, res = campaign["calibrate"].output, campaign["result"]
    assert "orientation error [deg]" in out
    assert "held-out poses, calibrated" in out
    o = res["orientation"]
    assert o["unit"] == "deg"
    held = o["holdout"]["calibrated"]
    # noise 0.02/100 rad per axis: the angle's RMS is sqrt(3) * 2e-4 rad = 0.02 deg; calibrated near it
    assert held["rms"] < 0.05 and held["max"] < 0.15, held
    assert o["holdout"]["baseline"]["rms"] > held["rms"]
    assert set(o["train"]) == {"nominal", "baseline", "calibrated"}
    assert "T_flange_tool" in res["baseline"]


def test_calibrated_robot_carries_the_probe_frame_as_its_tool(campaign):
    d = campaign["dir"]
    robot = load_robot(d / "cal" / "calibrated_robot.toml")
    assert robot.end_effectors[0].name == "tool"
    T_tool = np.asarray(robot.end_effectors[0].T_link_ee)
    assert np.degrees(np.linalg.norm(so3_log(T_tool[:3, :3] @ true_tool()[:3, :3].T))) < 0.05
    assert np.allclose(T_tool[:3, 3], true_tool()[:3, 3], atol=0.5)
    # fk of the calibrated file is the probe pose (base frame); --tool 0,0,0 gives the flange back
    q = campaign["q"][0]
    res = json.loads(run("fk", d / "cal" / "calibrated_robot.toml", *q, "--json").output)
    flange = json.loads(run("fk", d / "cal" / "calibrated_robot.toml", *q, "--json", "--tool", "0,0,0").output)
    R_f, p_f = np.array(flange["rotation"]), np.array(flange["position_mm"])
    assert np.allclose(res["position_mm"], p_f + R_f @ T_tool[:3, 3], atol=1e-6)


def test_calibrate_format_reads_the_exports_directly(campaign, tmp_path):
    r = run("calibrate", "ur10", campaign["leica"], "--format", "tracker-csv", "--joints", campaign["rtde"],
            "--orientation", "rpy", "--out", tmp_path / "c", "--sigma", SIGMA_MM, "--no-report")
    assert r.exit_code == 0, r.output
    assert "6-D: positions and orientations" in r.output


def test_angles_without_a_convention_are_dropped_with_the_reason(campaign, tmp_path):
    r = run("import", campaign["leica"], "--joints", campaign["rtde"], "--robot", "ur10", "--out", tmp_path / "m.csv")
    assert r.exit_code == 0, r.output
    assert "orientation columns (Rx [deg], Ry [deg], Rz [deg]) NOT imported" in r.output and "--orientation" in r.output
    assert "# orientation:" not in (tmp_path / "m.csv").read_text()


def test_time_pairing_with_a_streamed_kuka_log_prints_a_summary(campaign, tmp_path):
    q = campaign["q"]
    rows = ["Zeit;AxisAct_A1;AxisAct_A2;AxisAct_A3;AxisAct_A4;AxisAct_A5;AxisAct_A6"]
    for k in range(len(q)):  # 10 Hz while the robot holds each pose for 4 s
        for s in range(40):
            t = T0 + timedelta(seconds=4.0 * k + 0.1 * s - 0.03)
            rows.append(";".join([_stamp(t)] + [f"{v:.6f}".replace(".", ",") for v in np.degrees(q[k])]))
    log = tmp_path / "kuka.csv"
    log.write_text("\n".join(rows) + "\n", encoding="utf-8")
    r = run("import", campaign["leica"], "--joints", log, "--robot", "ur10", "--angle-unit", "deg", "--orientation",
            "rpy", "--pair", "time", "--tolerance", 0.05, "--out", tmp_path / "m.csv")
    assert r.exit_code == 0, r.output
    lines = r.output.splitlines()
    head = next(x for x in lines if "pose(s) paired" in x)
    assert head.startswith("60 pose(s) paired; 0 point(s) and 2340 joint row(s) not paired; |dt| median 0.03 s")
    assert len(lines) < 20, r.output


def test_calibrate_format_takes_the_id_pairing_options(campaign, tmp_path):
    q = campaign["q"]
    log = tmp_path / "ids.csv"
    log.write_text("Pose;J1;J2;J3;J4;J5;J6\n" + "\n".join(
        f"{k + 1};" + ";".join(f"{v:.9f}" for v in row) for k, row in enumerate(q)) + "\n")
    r = run("calibrate", "ur10", campaign["leica"], "--format", "tracker-csv", "--joints", log, "--angle-unit", "rad",
            "--pair", "id", "--id-match", "number", "--orientation", "rpy", "--out", tmp_path / "c", "--no-report",
            "--sigma", SIGMA_MM)
    assert r.exit_code == 0, r.output


def _correct_targets(cal_dir, virtual, T_inst, tmp_path):
    """Tool-pose targets in the tracker frame (8 poses of the true robot, seed 99), corrected with
    ``cal_dir``'s calibrated_robot.toml; returns (targets (8, 4, 4) [mm], corrected joints (8, 6)
    [rad])."""
    joints = ("J1", "J2", "J3", "J4", "J5", "J6")
    q_t = virtual.random_configurations(8, np.random.default_rng(99), margin=0.2)
    targets = T_inst @ virtual.true_poses(q_t) @ true_tool()
    write_pose_targets(tmp_path / "t.csv", targets, q_t, joints)
    r = run("correct", cal_dir / "calibrated_robot.toml", tmp_path / "t.csv", "--out", tmp_path / "c.csv")
    assert r.exit_code == 0, r.output
    q_c = read_corrected_joints(tmp_path / "c.csv", joints)
    return targets, q_c


def test_correct_with_the_calibrated_tool_lands_the_true_probe_on_the_targets(campaign, tmp_path):
    """At the robot: tool-pose targets in the tracker frame, corrected with calibrated_robot.toml
    (its [tool] = the identified probe frame), executed by the hidden true robot with the true
    probe."""
    virtual, T_inst = campaign["virtual"], campaign["T_inst"]
    targets, q_c = _correct_targets(campaign["dir"] / "cal", virtual, T_inst, tmp_path)
    reached = T_inst @ virtual.true_poses(q_c) @ true_tool()
    pos_err = np.linalg.norm(reached[:, :3, 3] - targets[:, :3, 3], axis=1)
    rot_err = np.degrees(np.linalg.norm(so3_log(reached[:, :3, :3] @ np.swapaxes(targets[:, :3, :3], 1, 2)),
                                        axis=1))
    assert pos_err.max() < 0.15 and rot_err.max() < 0.05, (pos_err, rot_err)


def test_correct_on_effects_the_model_lacks_lands_where_first_order_theory_says(realistic, tmp_path):
    """At the robot on :func:`realistic`: the true robot executing the corrected joints has the
    campaign's transmission error and is grown as at its end (tests/_first_order.py
    ``poses_with_effects(after_campaign=True)``). Each landing error, position and orientation as
    vectors in the tracker frame, must equal the first-order miss ``e_at - J_at delta``
    (``six_d_fit_bias`` with ``q_at``) within 3 sigma of the corrected target's prediction (the
    noise's part, from the same Jacobians: ``sigma_at_mm``, ``sigma_at_rad``; the RMS length of a
    3-vector, so 3 sigma is a wide bound for one vector). Some target must miss by more than 3 sigma
    in position and in orientation (the ideal test's "< 0.15 mm" is then not what is checked: the
    effects are). The ideal test's orientation claim (< 0.05 deg) holds here as well, and the
    first-order theory says why: ``|miss| + 3 sigma`` stays below 0.05 deg for every target (the
    transmission error turns the flange by at most 6 x (0.005 + 0.003) = 0.048 deg, the growth
    not at all, and the fit absorbs part of it). Measured: position landing 0.024-0.162 mm,
    predicted 0.022-0.160 mm, vector difference <= 0.019 mm against sigma 0.012-0.016 mm;
    orientation landing 0.002-0.018 deg, predicted 0.003-0.015 deg, vector difference <= 0.0072
    deg against sigma 0.0035-0.0040 deg."""
    from _first_order import poses_with_effects, six_d_fit_bias

    virtual, T_inst = realistic["virtual"], realistic["T_inst"]
    targets, q_c = _correct_targets(realistic["dir"] / "cal", virtual, T_inst, tmp_path)
    phases = np.random.default_rng(11 + 1000).uniform(0.0, 2 * np.pi, (2, 6))  # as simulate(seed=11)
    reached = poses_with_effects(virtual.true_model, q_c, T_inst, true_tool(), phases, after_campaign=True)[1]
    first = six_d_fit_bias(*realistic["fit"], q_at=q_c, T_at=reached, noise_mm=SIGMA_MM)
    sigma, sigma_rot = first["sigma_at_mm"], first["sigma_at_rad"]
    d_pos = reached[:, :3, 3] - targets[:, :3, 3]
    d_rot = so3_log(reached[:, :3, :3] @ np.swapaxes(targets[:, :3, :3], 1, 2))  # rad, tracker frame
    miss_pos, miss_rot = first["miss_at"][:, :3], first["miss_at"][:, 3:]
    assert np.all(np.linalg.norm(d_pos - miss_pos, axis=1) < 3 * sigma), (d_pos, miss_pos, sigma)
    assert np.all(np.linalg.norm(d_rot - miss_rot, axis=1) < 3 * sigma_rot), (d_rot, miss_rot, sigma_rot)
    assert np.linalg.norm(d_pos, axis=1).max() > 3 * sigma.max()  # the effects are visible at the robot
    assert np.linalg.norm(d_rot, axis=1).max() > 3 * sigma_rot.max()
    rot_deg = np.degrees(np.linalg.norm(d_rot, axis=1))
    assert np.degrees(np.linalg.norm(miss_rot, axis=1) + 3 * sigma_rot).max() < 0.05
    assert rot_deg.max() < 0.05, rot_deg


def test_export_options_with_robocal_s_own_file_are_refused(campaign, tmp_path):
    r = run("calibrate", "ur10", campaign["dir"] / "m.csv", "--orientation", "rpy", "--out", tmp_path / "c")
    assert r.exit_code == 1 and "--orientation: for --format tracker-csv or sa-text" in r.output, r.output
