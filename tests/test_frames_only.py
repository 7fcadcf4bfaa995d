"""Issue 31, items 4 and 5: re-registering a calibrated robot in a new cell (``--frames-only``),
an empty ``--free`` refused, and a 6-D start that converges on a line of 20 poses.

The line-shaped campaign: the flange moves along an 800 mm straight line (20 poses) with its
orientation varying by ~2 deg, carrying a 6-DoF probe turned by ~170 deg; the robot's geometry is
known (the "calibrated" model is the truth), the tracker stands somewhere new. With the tool
rotation started as identity this needed hundreds of iterations; estimated from the data (relative
rotations turn the same axes in both frames), the default 50 are plenty.
"""

import json

import numpy as np
import pytest
from click.testing import CliRunner

from robocal.calib.initial import base_and_tool_from_orientations
from robocal.calib.sanity import Verdict
from robocal.cli import main
from robocal.io.measurements import Measurements, write_measurements
from robocal.robots import load_robot
from robocal.sim.line_campaign import LINE_ROBOT, LINE_TOOL_ROTVEC, line_campaign_poses
from robocal.transforms import so3_exp, so3_log
from robocal.workflows.calibration.calibrate import _non_convergence_first

ROBOT = LINE_ROBOT
TOOL_ROTVEC = list(LINE_TOOL_ROTVEC)  # ~170 deg


def run(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


def line_campaign(path, seed=5, n=20, effects=False):
    """Write the line campaign (:func:`robocal.sim.line_campaign.line_campaign_poses`) to ``path``;
    returns (tool, instrument frame) [mm]; with ``effects`` (the ``realistic`` campaign effects) also
    the joints and the noise-free measured poses."""
    c = line_campaign_poses(seed, n, effects)
    write_measurements(path, Measurements(c["q"], c["points"], joint_names=c["model"].controller_joints,
                                          rotations=c["rotations"], metadata={"robot": ROBOT}), orientation="quaternion")
    return (c["tool"], c["instrument"], c["q"], c["T_measured"]) if effects else (c["tool"], c["instrument"])


@pytest.fixture(scope="module")
def line(tmp_path_factory):
    d = tmp_path_factory.mktemp("line")
    tool, inst = line_campaign(d / "line.csv")
    r = run("calibrate", ROBOT, d / "line.csv", "--out", d / "cal", "--frames-only", "--holdout", 0, "--no-report")
    return {"dir": d, "tool": tool, "inst": inst, "run": r, "result": json.loads((d / "cal" / "result.json").read_text())}


def test_line_shaped_re_registration_converges_at_defaults(line):
    r, res = line["run"], line["result"]
    assert r.exit_code == 0, r.output
    assert "base frame and the tool rotation were started from the measured orientations" in r.output
    assert res["baseline"]["converged"] and res["baseline"]["iterations"] < 25, res["baseline"]["iterations"]
    assert res["solver"]["converged"]
    T = np.array(res["tool_frame"]["T_flange_measured"])
    err = so3_log(T[:3, :3] @ line["tool"][:3, :3].T)  # a line with ~2 deg of wrist motion: weakly fixed
    std = np.array(res["tool_frame"]["std_rotvec_rad"])
    assert np.all(np.abs(err) < 3 * std), (err, std)


def test_re_registration_with_effects_the_model_lacks_lands_within_3_sigma_of_its_bias(tmp_path):
    """The line campaign with the ``realistic`` campaign effects (transmission error, 20 ppm growth
    along the campaign, 5 ppm instrument scale; docs/testing.md), re-registered with
    ``--frames-only`` and the noise given (``--noise``: sigma not scaled by the misfit). The bias
    of the tool frame is derived to first order from the hidden truth (tests/_first_order.py
    ``six_d_fit_bias`` with no geometric parameter free). Asserted: tool rotation within 3 sigma
    and origin within 4 sigma of truth + bias, the residual RMS within 10 % of the first-order
    misfit plus the noise. Measured: tool rotation |z| 2.0 / 2.1 / 2.2 plain, 1.5 / 1.5 / 1.6
    after the bias; origin |z| 1.5 / 1.6 / 0.2 plain, 0.4 / 0.8 / 0.0; residual RMS 0.0397 mm
    against 0.0408 predicted (ratio 0.97). On a line of 20 poses the effects (~0.024 mm RMS of
    misfit) are below the noise (0.035 mm): this case checks the bias's size, not a large one."""
    from _first_order import six_d_fit_bias

    tool, inst, q, T_free = line_campaign(tmp_path / "line.csv", effects=True)
    r = run("calibrate", ROBOT, tmp_path / "line.csv", "--out", tmp_path / "cal", "--frames-only", "--holdout", 0,
            "--noise", 0.02, "--no-report")
    assert r.exit_code == 0, r.output
    res = json.loads((tmp_path / "cal" / "result.json").read_text())
    bias = six_d_fit_bias(load_robot(ROBOT), [], q, inst, tool, T_free, 100.0)
    tf = res["tool_frame"]
    T = np.array(tf["T_flange_measured"])
    err = so3_log(T[:3, :3] @ tool[:3, :3].T)
    std, std_xyz = np.array(tf["std_rotvec_rad"]), np.array(tf["std_xyz_mm"])
    origin_err = T[:3, 3] - tool[:3, 3]
    # the noise part of the residual keeps the fraction 1 - (variables / residuals) of its square
    rms_pred = np.hypot(bias["residual_rms_mm"], 0.02 * np.sqrt(3 * (1 - 12 / (6 * len(q)))))
    assert np.all(np.abs(err - bias["tool_rotvec"]) < 3 * std), (err, bias["tool_rotvec"], std)
    assert np.all(np.abs(origin_err - bias["tool_xyz"]) < 4 * std_xyz), (origin_err, bias["tool_xyz"], std_xyz)
    assert 0.9 < res["residuals"]["after"]["rms"] / rms_pred < 1.1, (res["residuals"]["after"], rms_pred)


def test_frames_only_holds_the_geometry(line):
    res = line["result"]
    assert res["metadata"]["free"] == [] and res["metadata"]["frames_only"] is True
    nominal = load_robot(ROBOT)
    calibrated = load_robot(line["dir"] / "cal" / "calibrated_robot.toml")
    np.testing.assert_allclose(calibrated.params.values, nominal.params.values, atol=1e-12)
    assert res["orientation"]["train"]["calibrated"]["rms"] < 0.05  # deg: 0.0115 deg noise per axis


def test_empty_free_and_frames_only_with_free_are_errors(line, tmp_path):
    r = run("calibrate", ROBOT, line["dir"] / "line.csv", "--out", tmp_path / "a", "--free", "")
    assert r.exit_code == 1 and "--free names no parameter" in r.output, r.output
    r = run("calibrate", ROBOT, line["dir"] / "line.csv", "--out", tmp_path / "b", "--frames-only", "--free", "a2")
    assert r.exit_code == 1 and "--frames-only holds the whole geometry" in r.output, r.output


def test_base_and_tool_rotation_from_orientations_are_exact_without_noise():
    rng = np.random.default_rng(2)
    R_b, R_t = so3_exp([0.4, -1.2, 2.0]), so3_exp([2.9, 0.3, 0.2])
    Re = so3_exp(rng.normal(0, 0.05, (8, 3)))  # small, varied wrist motions
    T, R = base_and_tool_from_orientations(Re, R_b @ Re @ R_t)
    assert np.allclose(T[:3, :3], R_b, atol=1e-9) and np.allclose(R, R_t, atol=1e-9)
    with pytest.raises(ValueError, match="cannot be told apart"):  # one axis only, no points
        base_and_tool_from_orientations(so3_exp(np.outer(np.linspace(0, 1, 5), [0, 0, 1.0])),
                                        R_b @ so3_exp(np.outer(np.linspace(0, 1, 5), [0, 0, 1.0])) @ R_t)


def test_a_failed_gate_after_non_convergence_names_the_non_convergence_first():
    v = Verdict(("1 parameter(s) changed beyond physical plausibility: likely swapped joint columns",), {})
    got = _non_convergence_first(v, ["the solver did not converge: maximum iterations reached"], 50)
    assert got.reasons[0].startswith("the solver did not converge within 50 iterations")
    assert got.reasons[1] == v.reasons[0]
    assert _non_convergence_first(v, [], 50) is v
