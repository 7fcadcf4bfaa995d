"""Issue 10, items 1, 2 and 5: a 6-D campaign through ``robocal calibrate`` (tool frame recovered
within 3 sigma), the 6-D start for a line of points, a given train / held-out protocol, the weak
prior, honest non-convergence (warning, report, exit code) and the console parameter table."""

import json
import warnings

import numpy as np
import pytest
from click.testing import CliRunner

from robocal.calib import solve
from robocal.calib.initial import frame_from_orientations, rigid_fit
from robocal.calib.pose_problem import PoseCalibrationProblem
from robocal.calib.solve import NotConvergedWarning
from robocal.cli import main
from robocal.io.measurements import write_measurements
from robocal.robots import load_robot
from robocal.sim import VirtualRobot
from robocal.sim.six_d_campaign import SIX_D_ROBOT, SIX_D_SIGMA_MM, SIX_D_W_MM_PER_RAD, six_d_true_tool
from robocal.sim.six_d_campaign import six_d_campaign as _six_d_campaign
from robocal.transforms import so3_exp, so3_log

SIGMA_MM = SIX_D_SIGMA_MM
W_MM_PER_RAD = SIX_D_W_MM_PER_RAD  # the CLI default: rotation noise SIGMA_MM / W rad
ROBOT = SIX_D_ROBOT


def run(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


def true_tool():
    return six_d_true_tool()


def six_d_campaign(n=60, seed=3, q=None, effects=False):
    """(Measurements, truth): :func:`robocal.sim.six_d_campaign.six_d_campaign` (a 6-D probe on a
    35/-20/180 mm, 38 deg tool; the last link true = nominal; ``effects``: the ``realistic`` effects)."""
    return _six_d_campaign(n, seed, q, effects)


@pytest.fixture(scope="module")
def campaign(tmp_path_factory):
    d = tmp_path_factory.mktemp("sixd")
    meas, truth = six_d_campaign()
    path = write_measurements(d / "probe.csv", meas, length_unit="mm", angle_unit="deg", orientation="kuka_abc")
    out = d / "cal"
    r = run("calibrate", ROBOT, path, "--out", out, "--noise", SIGMA_MM)
    return {"dir": d, "path": path, "out": out, "run": r, "truth": truth,
            "result": json.loads((out / "result.json").read_text())}


def test_six_d_campaign_recovers_the_tool_rotation_within_3_sigma(campaign):
    r = campaign["run"]
    assert r.exit_code == 0, r.output
    assert "6-D: positions and orientations, rotation weight 100 mm/rad" in r.output
    res = campaign["result"]
    assert res["six_d"] is True
    tf = res["tool_frame"]
    T = np.array(tf["T_flange_measured"])
    err = so3_log(T[:3, :3] @ campaign["truth"]["T_tool"][:3, :3].T)  # rad, small
    std = np.array(tf["std_rotvec_rad"])
    assert np.all(std > 0) and np.all(std < 1e-4), std
    assert np.all(np.abs(err) < 3 * std), (err, std)
    origin_err = T[:3, 3] - campaign["truth"]["T_tool"][:3, 3]
    # the origin: z is at 3.0 sigma with this seed (the geometry's z-scores have RMS 0.86): 4 sigma
    assert np.all(np.abs(origin_err) < 4 * np.array(tf["std_xyz_mm"])), (origin_err, tf["std_xyz_mm"])
    assert res["validation"]["after"]["rms"] < 2.5 * SIGMA_MM * np.sqrt(3)


def test_six_d_campaign_with_effects_the_model_lacks_recovers_the_tool_within_3_sigma_of_its_bias(tmp_path):
    """The campaign above with the ``realistic`` campaign effects (reducer transmission error,
    20 ppm growth during the campaign, 5 ppm instrument scale; docs/testing.md). The tool frame is
    then biased; the bias is derived to first order from the hidden truth (tests/_first_order.py
    ``six_d_fit_bias``: ``J^+ e`` over the estimated parameters, base and tool frames, with the
    CLI's rotation weight). Asserted: the tool rotation within 3 sigma and the origin within
    4 sigma (as above) of truth + bias, with sigma the noise's (``--noise``, not scaled by the
    misfit); the residual RMS equals the first-order misfit plus the noise within 10 %, far above
    the noise alone. Measured: tool rotation |z| 2.0 / 1.4 / 2.8 plain, 1.3 / 0.6 / 0.7 after the
    bias; origin |z| up to 3.6 plain, 2.8 after; residual RMS 0.147 mm against 0.150 predicted (ratio 0.98) and 0.035 mm of
    noise."""
    from _first_order import six_d_fit_bias

    meas, truth = six_d_campaign(effects=True)
    path = write_measurements(tmp_path / "probe.csv", meas, length_unit="mm", angle_unit="deg",
                              orientation="kuka_abc")
    r = run("calibrate", ROBOT, path, "--out", tmp_path / "cal", "--noise", SIGMA_MM, "--holdout", 0, "--no-report")
    assert r.exit_code == 0, r.output
    res = json.loads((tmp_path / "cal" / "result.json").read_text())
    estimated = [p["name"] for p in res["model_parameters"] if p["estimated"]]
    bias = six_d_fit_bias(truth["model"], estimated, truth["q"], truth["T_inst"], truth["T_tool"], truth["T_free"],
                          W_MM_PER_RAD)
    tf = res["tool_frame"]
    T = np.array(tf["T_flange_measured"])
    err = so3_log(T[:3, :3] @ truth["T_tool"][:3, :3].T)
    std, std_xyz = np.array(tf["std_rotvec_rad"]), np.array(tf["std_xyz_mm"])
    origin_err = T[:3, 3] - truth["T_tool"][:3, 3]
    # the misfit the effects leave plus the noise (3 coordinates): the fit minimises what J^+ says
    # (the noise part keeps the fraction 1 - variables / residuals of its square)
    n_var = len(estimated) + 12
    rms_pred = np.hypot(bias["residual_rms_mm"], SIGMA_MM * np.sqrt(3 * (1 - n_var / (6 * len(truth["q"])))))
    assert 0.9 < res["residuals"]["after"]["rms"] / rms_pred < 1.1, (res["residuals"]["after"], rms_pred)
    assert res["residuals"]["after"]["rms"] > 3 * SIGMA_MM * np.sqrt(3)  # the effects are far above the noise
    assert np.all(np.abs(err - bias["tool_rotvec"]) < 3 * std), (err, bias["tool_rotvec"], std)
    assert np.all(np.abs(origin_err - bias["tool_xyz"]) < 4 * std_xyz), (origin_err, bias["tool_xyz"], std_xyz)


def test_six_d_correct_on_effects_the_model_lacks_lands_where_first_order_theory_says(tmp_path):
    """At the robot, 6-D: the realistic campaign above calibrated through the command line, then
    ``robocal correct`` on tool-pose targets (8 poses the true robot can take, in the tracker
    frame, with their taught joints); the hidden true robot runs the corrected joints with the
    campaign's transmission error and grown by 20 ppm, as at the campaign's end
    (tests/_first_order.py ``poses_with_effects(after_campaign=True)``), carrying the true probe.

    Tolerance, derived, not measured: each landing error (position and rotation vector in the
    tracker frame) equals the first-order miss ``e_at - J_at delta`` from the hidden truth
    (``six_d_fit_bias`` with ``q_at``) within 3 sigma, sigma the RMS length of the noise part of
    that target's prediction (``noise sqrt(tr(J_p (J^T J)^-1 J_p^T))``, the CLI's rotation weight,
    ``--noise 0.02``); some target misses by more than 3 sigma in position (the effects are
    visible: "within 3 sigma of the target" would fail), and in rotation. The at-the-robot orientation claim of the
    ideal tests (< 0.05 deg) is asserted with its first-order reason: ``|miss| + 3 sigma`` < 0.05 deg
    for every target (the transmission error turns the flange by at most 6 x 0.008 = 0.048 deg,
    the growth not at all). Measured (seed 3): position landing 0.13-0.32 mm, vector difference
    to the prediction <= 0.016 mm against sigma 0.011-0.013 mm; rotation landing 0.008-0.022 deg,
    predicted 0.008-0.017 deg, difference <= 0.0056 deg against sigma 0.0032-0.0040 deg."""
    from _first_order import poses_with_effects, six_d_fit_bias

    from robocal.sim.six_d_exports import read_corrected_joints, write_pose_targets

    meas, truth = six_d_campaign(effects=True)
    path = write_measurements(tmp_path / "probe.csv", meas, length_unit="mm", angle_unit="deg",
                              orientation="kuka_abc")
    r = run("calibrate", ROBOT, path, "--out", tmp_path / "cal", "--noise", SIGMA_MM, "--holdout", 0, "--no-report")
    assert r.exit_code == 0, r.output
    res = json.loads((tmp_path / "cal" / "result.json").read_text())
    estimated = [p["name"] for p in res["model_parameters"] if p["estimated"]]
    model, T_inst, T_tool = truth["model"], truth["T_inst"], truth["T_tool"]
    q_t = VirtualRobot(load_robot(ROBOT), model).random_configurations(8, np.random.default_rng(99), margin=0.2)
    targets = T_inst @ model.fk(q_t) @ T_tool  # poses the true robot (without effects) takes: reachable
    joints = [f"A{j + 1}" for j in range(6)]
    write_pose_targets(tmp_path / "t.csv", targets, q_t, joints)
    r = run("correct", tmp_path / "cal" / "calibrated_robot.toml", tmp_path / "t.csv", "--out", tmp_path / "c.csv")
    assert r.exit_code == 0, r.output
    q_c = read_corrected_joints(tmp_path / "c.csv", joints)
    phases = np.random.default_rng(3 + 1000).uniform(0.0, 2 * np.pi, (2, 6))  # as six_d_campaign(seed=3)
    reached = poses_with_effects(model, q_c, T_inst, T_tool, phases, after_campaign=True)[1]
    first = six_d_fit_bias(model, estimated, truth["q"], T_inst, T_tool, truth["T_free"], W_MM_PER_RAD, q_at=q_c,
                           T_at=reached, noise_mm=SIGMA_MM)
    sigma, sigma_rot = first["sigma_at_mm"], first["sigma_at_rad"]
    d_pos = reached[:, :3, 3] - targets[:, :3, 3]
    d_rot = so3_log(reached[:, :3, :3] @ np.swapaxes(targets[:, :3, :3], 1, 2))  # rad
    miss_pos, miss_rot = first["miss_at"][:, :3], first["miss_at"][:, 3:]
    assert np.all(np.linalg.norm(d_pos - miss_pos, axis=1) < 3 * sigma), (d_pos, miss_pos, sigma)
    assert np.all(np.linalg.norm(d_rot - miss_rot, axis=1) < 3 * sigma_rot), (d_rot, miss_rot, sigma_rot)
    assert np.linalg.norm(d_pos, axis=1).max() > 3 * sigma.max()  # the effects are visible at the robot
    assert np.linalg.norm(d_rot, axis=1).max() > 3 * sigma_rot.max()
    assert np.degrees(np.linalg.norm(miss_rot, axis=1) + 3 * sigma_rot).max() < 0.05
    assert np.degrees(np.linalg.norm(d_rot, axis=1)).max() < 0.05


def test_console_shows_identified_parameters_with_change_and_sigma(campaign):
    out = campaign["run"].output
    assert "identified (" in out and "not identified (" in out
    row = next(line for line in out.splitlines() if line.strip().startswith("tool.rz"))
    value, change, sigma = (float(x) for x in row.split()[2:5])
    assert abs(value - np.degrees(0.6)) < 0.5 and 0 < sigma < 0.01
    held = next(line for line in out.splitlines() if line.strip().startswith("theta6"))
    assert "trades off" in held


def test_orientation_columns_can_be_ignored(campaign, tmp_path):
    r = run("calibrate", ROBOT, campaign["path"], "--out", tmp_path / "c", "--no-orientation")
    assert r.exit_code == 0, r.output
    assert "measurements: positions of 1 target(s)" in r.output
    assert "orientation columns were NOT used" in r.output


def test_line_of_points_gets_its_base_frame_from_the_orientations():
    nominal = load_robot(ROBOT)
    q = np.tile(np.radians([10.0, -80.0, 100.0, 5.0, 40.0, 0.0]), (12, 1))
    q[:, 5] = np.linspace(-2.5, 2.5, 12)  # only the flange turns: the tool origin hardly moves
    meas, truth = six_d_campaign(n=12, seed=4, q=q)
    with pytest.raises(ValueError, match="collinear"):
        rigid_fit(np.zeros((12, 3)) + np.arange(12)[:, None] * [1.0, 0, 0], meas.points)
    prob = PoseCalibrationProblem(nominal, meas.joints, meas.points, meas.rotations, free=[],
                                  tool_rotation0=truth["T_tool"][:3, :3], point_sigma_mm=SIGMA_MM)
    assert prob.base_start == "orientations"
    T0 = prob.base_initial[0]
    ang = np.linalg.norm(so3_log(T0[:3, :3] @ truth["T_inst_base"][:3, :3].T))
    assert ang < 0.01, ang  # nominal geometry and noise: well inside the solver's reach
    res = solve(prob)
    assert res.converged and res.rms_after < 3.0  # nominal geometry: mm-level residuals remain


def test_frame_from_orientations_is_exact_without_noise():
    rng = np.random.default_rng(0)
    T = np.eye(4)
    T[:3, :3], T[:3, 3] = so3_exp([0.3, -1.0, 2.0]), [100.0, 200.0, -50.0]
    Ra = so3_exp(rng.normal(0, 1, (5, 3)))
    a = rng.normal(0, 100, (5, 3))
    got = frame_from_orientations(Ra, T[:3, :3] @ Ra, a, a @ T[:3, :3].T + T[:3, 3])
    assert np.allclose(got, T, atol=1e-9)


def test_given_train_and_holdout_ids_are_followed(campaign, tmp_path):
    ids = (tmp_path / "holdout.txt")
    ids.write_text("51\n52,53\n54 55 56 57 58 59 60\n")
    train = ",".join(str(i) for i in range(1, 41))
    r = run("calibrate", ROBOT, campaign["path"], "--out", tmp_path / "c", "--train-ids", train,
            "--holdout-ids", f"@{ids}")
    assert r.exit_code == 0, r.output
    res = json.loads((tmp_path / "c" / "result.json").read_text())
    held = [row.split(",")[1] for row in (tmp_path / "c" / "residuals.csv").read_text().splitlines()[1:]
            if row.startswith("holdout,")]
    assert list(dict.fromkeys(held)) == [str(i) for i in range(51, 61)]
    assert res["validation"]["n_poses"] == 10
    assert res["metadata"]["n_poses_calibration"] == 40 and res["metadata"]["split"] == "given pose ids"
    assert "10 pose(s) of the file in neither list" in r.output
    bad = run("calibrate", ROBOT, campaign["path"], "--out", tmp_path / "d", "--holdout-ids", "7,P99")
    assert bad.exit_code == 1 and "Error: --holdout-ids: pose id(s) not in the measurement file: P99" in bad.output


def test_prior_pulls_the_geometry_towards_nominal(campaign, tmp_path):
    r = run("calibrate", ROBOT, campaign["path"], "--out", tmp_path / "c", "--prior", "--prior-sigma", "0.001",
            "0.0001")
    assert r.exit_code == 0, r.output
    res = json.loads((tmp_path / "c" / "result.json").read_text())
    free = {p["name"]: p for p in res["model_parameters"] if p["estimated"]}
    loose = {p["name"]: p for p in campaign["result"]["model_parameters"] if p["estimated"]}
    assert res["metadata"]["prior_sigma_mm_deg"] == [0.001, 0.0001]
    lengths = [n for n, p in free.items() if p["unit"] == "mm"]
    assert max(abs(free[n]["change"]) for n in lengths) < 0.005
    assert max(abs(loose[n]["change"]) for n in lengths if n in loose) > 0.1


def test_non_convergence_warns_marks_the_report_and_exits_4(campaign, tmp_path):
    r = run("calibrate", ROBOT, campaign["path"], "--out", tmp_path / "c", "--max-iterations", "1")
    assert r.exit_code == 4, r.output
    warning = next(line for line in r.output.splitlines() if line.startswith("Warning:"))
    assert "maximum iterations reached" in warning and "condition number" in warning
    res = json.loads((tmp_path / "c" / "result.json").read_text())
    assert res["solver"]["converged"] is False and "condition number" in res["solver"]["warning"]
    assert res["convergence"]["converged"] is False and res["convergence"]["n_not_converged"] >= 1
    assert not (tmp_path / "c" / "calibrated_robot.toml").exists()  # no model from a fit that did not converge
    assert sum(line.startswith("Warning:") for line in r.output.splitlines()) == 1
    html = (tmp_path / "c" / "report.html").read_text()
    assert "NOT CONVERGED" in html and "did not converge" in html
    ok = run("calibrate", ROBOT, campaign["path"], "--out", tmp_path / "d", "--max-iterations", "1",
             "--allow-unconverged")
    assert ok.exit_code == 0 and "Warning:" in ok.output
    assert (tmp_path / "d" / "calibrated_robot.toml").exists()


def test_solve_raises_not_converged_warning():
    meas, _ = six_d_campaign(n=30, seed=5)
    nominal = load_robot(ROBOT)
    prob = PoseCalibrationProblem(nominal, meas.joints, meas.points, meas.rotations, point_sigma_mm=SIGMA_MM)
    with pytest.warns(NotConvergedWarning, match="condition number"):
        res = solve(prob, max_iterations=1)
    assert not res.converged
    with warnings.catch_warnings():
        warnings.simplefilter("error", NotConvergedWarning)
        assert solve(prob).converged
