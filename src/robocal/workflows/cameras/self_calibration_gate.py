"""The sanity gate of ``robocal self-calibrate`` (issue 29) and its clock diagnosis.

:func:`robocal.handeye.gate.self_calibration_verdict` judges the solve. When it fails, the pairing
of images with joint readings is checked without a solution: the camera's motion between two
images (per-image PnP) and the camera end effector's motion relative to the board's carrier
(forward kinematics of the matched joints) share their rotation angle whatever the camera mount
(:mod:`robocal.handeye.consistency`). Shifting the frame times by a trial clock offset and
re-matching, the offset whose motions agree best (and clearly better than as given) is named; no
agreement at any offset names permuted frame times.
"""

from __future__ import annotations

import numpy as np

from ...handeye.consistency import motion_mismatch
from ...handeye.gate import MOTION_ANGLE_LIMIT_DEG
from ...io.capture_times import match_capture_times
from ...transforms import invert_transforms

__all__ = ["clock_reasons", "CLOCK_SEARCH_S", "estimate_joint_noise", "JOINT_NOISE_LADDER_DEG"]

#: Joint-reading noise levels tried [deg] when none is given, smallest first.
JOINT_NOISE_LADDER_DEG = (0.002, 0.005, 0.01, 0.02, 0.05, 0.1, 0.2, 0.5, 1.0, 2.0)
#: The joint readings are taken as exact when their residuals are within this factor of the corner
#: noise; the estimate is the smallest ladder level whose variance factor is at most this.
EXACT_VARIANCE_FACTOR = 1.2


def estimate_joint_noise(solve_with) -> tuple:
    """``(joint_noise_deg or None, result, source)``: the readings taken as exact when the solve's
    variance factor is at most ``EXACT_VARIANCE_FACTOR``, else the smallest level of
    ``JOINT_NOISE_LADDER_DEG`` that brings it there (errors in variables with that prior; the
    largest level when none does: the gate then refuses the result). ``solve_with(noise_deg or
    None)`` returns a :class:`~robocal.handeye.self_calibration.SelfCalibration`. Without it, a
    0.05 deg reading noise taken as exact left offsets 17 sigma off at a variance factor of 2.4
    (tests/test_self_calibration_pipeline.py)."""
    res = solve_with(None)
    if not res.variance_factor > EXACT_VARIANCE_FACTOR:
        return None, res, "exact readings (variance factor %.3g)" % res.variance_factor
    for noise in JOINT_NOISE_LADDER_DEG:
        res = solve_with(noise)
        if res.variance_factor <= EXACT_VARIANCE_FACTOR:
            break
    return noise, res, f"estimated: the smallest of {list(JOINT_NOISE_LADDER_DEG)} deg with variance factor <= " \
        f"{EXACT_VARIANCE_FACTOR:g}"

#: Clock offsets tried: +- this [s] (at least 4 x the pairing tolerance), in steps of the log's sampling
#: interval (at most the pairing tolerance), each paired within one step.
CLOCK_SEARCH_S = 3.0


def _relative_flange(model, q, camera_end_effector, carrier) -> np.ndarray:
    """(N, 4, 4) the camera end effector in its board carrier's frame (the base for ``world``)."""
    cam = model.kinematics_with(q, T_world_base=np.eye(4),
                                end_effectors=[model.end_effector_index(camera_end_effector)])[0][:, 0]
    if carrier == "world":
        return cam
    B = model.kinematics_with(q, T_world_base=np.eye(4), end_effectors=[model.end_effector_index(carrier)])[0][:, 0]
    return invert_transforms(B) @ cam


def _angle_mismatch(model, t_img, t_log, q_log, idx, C, on, camera_end_effector, tolerance, match, offset) -> float:
    q, _, reasons = match_capture_times(t_img[idx], t_log, q_log, tolerance=tolerance, mode=match, offset=offset)
    ok = np.array([r is None for r in reasons])
    carriers = np.array(on, dtype=object)
    values = []
    for c in dict.fromkeys(on):
        sel = ok & (carriers == c)
        if sel.sum() < 4:
            continue
        F = _relative_flange(model, q[sel], camera_end_effector, c)
        values.append(motion_mismatch(F, C[sel], "eye_in_hand").angle_deg_median)
    finite = [v for v in values if np.isfinite(v)]
    return float(np.mean(finite)) if finite else float("nan")


def clock_reasons(*, model, t_img, t_log, q_log, idx, image_points, target_points, camera, carriers,
                  camera_end_effector: str, tolerance: float, match: str, min_points: int) -> tuple:
    """``(reasons, checks)`` on the pairing of the used images ``idx`` with the joint log.

    t_img (N,) [s] frame times; t_log (M,) [s], q_log (M, n) the joint log; image_points (N, P, 2)
    [px]; carriers: the board's carrier of each used image; tolerance [s], match: the pairing
    settings of the run. A reason names the clock offset at which the motions agree, or permuted
    frame times when none does.
    """
    from ...handeye import solve_pnp

    idx = np.asarray(idx)
    C = solve_pnp(camera, target_points, np.asarray(image_points)[idx], min_points=min_points)[0]
    t_img = np.asarray(t_img, dtype=float)
    args = (model, t_img, t_log, q_log, idx, C, list(carriers), camera_end_effector, tolerance, match)
    as_given = _angle_mismatch(*args, 0.0)
    checks = {"pairing_angle_mismatch": {"value": as_given, "limit": MOTION_ANGLE_LIMIT_DEG, "unit": "deg",
                                         "passed": bool(np.isfinite(as_given) and as_given <= MOTION_ANGLE_LIMIT_DEG)}}
    if not np.isfinite(as_given):
        return [], checks
    # trial offsets on a grid of the log's sampling interval, each matched that tightly
    dt_log = float(np.median(np.diff(t_log))) if len(t_log) > 1 else tolerance
    step = min(max(dt_log, 0.005), tolerance)
    span = max(CLOCK_SEARCH_S, 4.0 * tolerance)
    offsets = np.arange(-span, span + step / 2, step)
    tight = args[:-2] + (step, match)
    scores = np.array([_angle_mismatch(*tight, float(o)) for o in offsets])
    if not np.isfinite(scores).any():
        return [], checks
    k = int(np.nanargmin(scores))
    score = float(scores[k])
    agree = np.isfinite(scores) & (scores <= max(3.0 * score, 0.1 * MOTION_ANGLE_LIMIT_DEG))
    lo = hi = k  # the run of agreeing offsets around the best one (the robot stands still at each pose)
    while lo > 0 and agree[lo - 1]:
        lo -= 1
    while hi < len(offsets) - 1 and agree[hi + 1]:
        hi += 1
    best = float(0.5 * (offsets[lo] + offsets[hi]))
    checks["best_clock_offset_s"] = {"value": best, "range_s": [float(offsets[lo]), float(offsets[hi])],
                                     "angle_mismatch_deg": score, "unit": "s",
                                     "passed": not score < 0.5 * as_given}
    if abs(best) > step and score <= MOTION_ANGLE_LIMIT_DEG and score < 0.5 * as_given:
        return [f"likely cause: the camera clock is offset from the joint log's by about {best:+.2f} s (frame time "
                f"minus robot time): with the log's times shifted by {offsets[lo]:+.2f} to {offsets[hi]:+.2f} s the "
                f"camera and robot motions agree (median angle mismatch {score:.3g} deg instead of {as_given:.3g} "
                "deg); correct the frame times"], checks
    if as_given > MOTION_ANGLE_LIMIT_DEG and score > MOTION_ANGLE_LIMIT_DEG:
        return [f"likely cause: the images are paired with joint readings of other poses (median angle mismatch "
                f"{as_given:.3g} deg, limit {MOTION_ANGLE_LIMIT_DEG:g} deg, at every clock offset within +-{span:g} s): "
                "permuted frame times, or a joint log or frames file of another run"], checks
    return [], checks
