"""The sanity gate of ``robocal handeye solve`` (issue 29): the verdict of
:func:`robocal.handeye.gate.handeye_verdict` on a solution and, when it fails, the likely causes,
each tried on the same detections:

* the pose rows shifted against the images by 1 or 2 rows (image i with pose i +- k);
* one image's pose row wrong (the others, solved without it, fit);
* the other set-up, which is the same as inverted flange poses (eye-in-hand with ``T_flange_base``
  gives exactly the eye-to-hand chain);
* the flange-pose file read in another orientation convention (``--poses`` files with Euler angles);
* intrinsics calibrated on the same images instead of the given ones.

A hypothesis fits when its motions agree (screw invariants) and its linear solution back-projects
within the gate's limit; the reasons then say ``likely cause: ...``.
"""

from __future__ import annotations

import math

import numpy as np

from ...calib.sanity import Verdict
from ...handeye import HandEyeError
from ...handeye.consistency import motion_mismatch
from ...handeye.gate import (
    HANDEYE_NOISE_FACTOR,
    HANDEYE_RMS_FLOOR_PX,
    MOTION_ANGLE_LIMIT_DEG,
    Hypothesis,
    cause_reasons,
    handeye_verdict,
)
from ...transforms import invert_transforms, rotation_angle
from .camera_common import backprojection

__all__ = ["chain_T_camera_target", "handeye_gate", "pairing_causes", "ALTERNATIVE_CONVENTIONS"]

#: Conventions tried when the flange poses' motions disagree with the camera's (6-value pose files).
ALTERNATIVE_CONVENTIONS = ("kuka_abc", "fanuc_wpr", "kawasaki_oat", "zxz", "xyz_intrinsic", "rotvec")


def chain_T_camera_target(setup: str, camera_pose, target_pose, T_base_flange) -> np.ndarray:
    """(N, 4, 4) the target in the camera through the robot chain: eye-in-hand
    ``X^-1 F_i^-1 Z`` (X = T_flange_camera, Z = T_base_target), eye-to-hand ``X^-1 F_i Z``
    (X = T_base_camera, Z = T_flange_target)."""
    F = np.asarray(T_base_flange, dtype=float)
    links = invert_transforms(F) if setup == "eye_in_hand" else F
    return invert_transforms(camera_pose)[None] @ links @ np.asarray(target_pose)[None]


def _rms(residuals) -> float:
    r = np.asarray(residuals, dtype=float).reshape(-1, 2)
    r = r[np.isfinite(r).all(axis=1)]
    return float(np.sqrt(np.mean(np.sum(r ** 2, axis=1)))) if len(r) else float("nan")


def _linear_rms(camera, setup, F, C, X, uv) -> float:
    """Back-projection RMS [px] of Shah's linear solution for these pairs (NaN when unsolvable)."""
    from ...handeye import solve_robot_world_hand_eye

    good = np.all(np.isfinite(C), axis=(1, 2))
    if good.sum() < 3:
        return float("nan")
    try:
        cam, target = solve_robot_world_hand_eye(F[good], C[good], setup=setup)
    except (HandEyeError, np.linalg.LinAlgError, ValueError):
        return float("nan")
    return _rms(backprojection(camera, chain_T_camera_target(setup, cam, target, F[good]), X, uv[good])[1])


def _hypothesis(cause, camera, setup, F, C, X, uv) -> Hypothesis:
    return Hypothesis(cause, motion_mismatch(F, C, setup).angle_deg_median, _linear_rms(camera, setup, F, C, X, uv))


def _shifts(camera, setup, F_all, idx, C, X, uv, names, labels) -> list:
    out = []
    for k in (1, -1, 2, -2):
        j = idx + k
        ok = (j >= 0) & (j < len(F_all))
        if ok.sum() < 3:
            continue
        first = int(np.flatnonzero(ok)[0])
        where = f"{abs(k)} row{'s' if abs(k) > 1 else ''} {'after' if k > 0 else 'before'}"
        cause = (f"the flange poses are shifted against the images: each image fits the pose {where} its own "
                 f"(image {names[idx[first]]} fits the pose listed with {names[j[first]]}); re-pair the "
                 "images with the pose rows")
        out.append(_hypothesis(cause, camera, setup, F_all[j[ok]], C[ok], X, uv[ok]))
    return out


def _leave_one_out(camera, setup, F, C, X, uv, names_used) -> list:
    """One hypothesis per image: its pose row is wrong (the others, solved without it, fit)."""
    n = len(F)
    if n < 5:
        return []
    out = []
    for i in range(n):
        keep = np.arange(n) != i
        out.append(_hypothesis(f"the flange pose of image {names_used[i]} is wrong (a typo, a pose taken at another "
                               "moment, a row of another image): the other images fit without it; retake or drop it, or solve with --loss huber",
                               camera, setup, F[keep], C[keep], X, uv[keep]))
    return out


def _conventions(camera, setup, poses_file, labels_used, C, X, uv) -> list:
    from ...io.tcp_files import TcpFileError, read_flange_poses_csv

    declared = read_flange_poses_csv(poses_file)
    if declared.convention == "quaternion":
        return []
    out = []
    for conv in ALTERNATIVE_CONVENTIONS:
        if conv == declared.convention:
            continue
        try:
            alt = read_flange_poses_csv(poses_file, convention=conv)
        except (TcpFileError, ValueError):
            continue
        by_label = dict(zip(alt.labels, alt.T_base_flange))
        F = np.array([by_label[label] for label in labels_used])
        out.append(_hypothesis(f"the flange poses' orientation is in the {conv} convention, not the declared "
                               f"{declared.convention} (fix the file's '# orientation:' line)", camera, setup, F, C,
                               X, uv))
    return out


def _intrinsics(camera, setup, F, X, uv, image_size, min_points) -> list:
    from ...handeye import calibrate_camera, solve_pnp

    try:
        cal = calibrate_camera(uv, X, image_size, min_points=min_points).camera
        C2 = solve_pnp(cal, X, uv, min_points=min_points)[0]
    except (HandEyeError, np.linalg.LinAlgError, ValueError):
        return []
    given = ", ".join(f"{n} {getattr(camera, n):.1f}" for n in ("fx", "fy", "cx", "cy"))
    found = ", ".join(f"{n} {getattr(cal, n):.1f}" for n in ("fx", "fy", "cx", "cy"))
    return [_hypothesis(f"the given intrinsics do not fit these images ({given} px); a camera calibrated on the "
                        f"same images has {found} px: pass the right camera file", cal, setup, F, C2, X, uv)]


def handeye_gate(*, camera, result, T_base_flange, used, image_points, target_points, setup: str, method: str,
                 names, labels, back_rms_px: float, per_image_back_px=None, exclude=(), poses_file=None, camera_given: bool = False,
                 image_size=None, min_points: int = 6) -> Verdict:
    """The verdict on a hand-eye solution with its likely causes (module docstring).

    camera: the camera the PnP poses were solved with; result: the
    :class:`~robocal.handeye.HandEyeRefinement` (its ``T_camera_target`` are the used images' PnP
    poses); T_base_flange (N, 4, 4) [mm] of all images; used (N,) bool; image_points (N, P, 2)
    [px]; target_points (P, 3) [mm]; names, labels (N): image names and pose labels;
    back_rms_px: the back-projection RMS through the reported poses (per_image_back_px (n used):
    per image, NaN for excluded images); exclude: indices of images a robust loss rejected (not judged,
    they are reported as outliers); poses_file: the flange-pose
    CSV (to try other conventions); camera_given: try intrinsics calibrated on the images.
    """
    F_all = np.asarray(T_base_flange, dtype=float)
    idx = np.flatnonzero(used)
    C = np.asarray(result.T_camera_target, dtype=float).copy()
    C[[k for k, i in enumerate(idx) if int(i) in set(exclude)]] = np.nan  # rejected by a robust loss
    F, uv, X = F_all[idx], np.asarray(image_points, dtype=float)[idx], np.asarray(target_points, dtype=float)
    good = np.all(np.isfinite(C), axis=(1, 2))
    pnp_rms = _rms(backprojection(camera, np.where(good[:, None, None], C, np.eye(4)), X, uv)[1][good])
    mismatch = motion_mismatch(F, C, setup)
    lin_cam = result.linear[method][0]
    dp = float(np.linalg.norm(lin_cam[:3, 3] - result.camera_pose[:3, 3]))
    dr = float(np.degrees(rotation_angle(lin_cam[:3, :3].T @ result.camera_pose[:3, :3])))
    verdict = handeye_verdict(backprojection_rms_px=back_rms_px, pnp_rms_px=pnp_rms, mismatch=mismatch,
                              linear_difference=(dp, dr), image_names=[names[i] for i in idx],
                              pose_labels=[labels[i] for i in idx], per_image_backprojection_px=per_image_back_px)
    verdict.checks["corner_noise_pnp_rms_px"] = {"value": pnp_rms, "unit": "px", "passed": True}
    if verdict.ok:
        return verdict
    causes = _likely_causes(camera, setup, F_all, idx, C, X, uv, names, labels, pnp_rms, poses_file, camera_given,
                            image_size, min_points)
    named = verdict.checks["images_disagreeing"]["value"] or any("back-project far worse" in r for r in verdict.reasons)
    if not causes and not named:
        if mismatch.angle_deg_median > MOTION_ANGLE_LIMIT_DEG:
            causes = ["likely cause: the flange poses are in another order than the images (shuffled) or belong to "
                      "another run (no shift of the rows, other convention or set-up fits); check how images and "
                      "pose rows are paired"]
        else:
            causes = ["likely cause: wrong intrinsics, a wrong robot model or lengths, or flange poses taken at "
                      "another moment than the images"]
    return Verdict(verdict.reasons + tuple(causes), verdict.checks)


def _likely_causes(camera, setup, F_all, idx, C, X, uv, names, labels, pnp_rms, poses_file, camera_given,
                   image_size, min_points) -> list:
    """Every hypothesis tried on the same detections (shifted rows, inverted poses or the other
    set-up, one wrong pose, another convention, intrinsics from the images), as the reasons of
    those that fit within the back-projection limit."""
    F = F_all[idx]
    limit = max(HANDEYE_RMS_FLOOR_PX, HANDEYE_NOISE_FACTOR * pnp_rms) if math.isfinite(pnp_rms) else \
        HANDEYE_RMS_FLOOR_PX
    hyps = _shifts(camera, setup, F_all, idx, C, X, uv, names, labels)
    other = "eye_to_hand" if setup == "eye_in_hand" else "eye_in_hand"
    hyps.append(_hypothesis(f"the flange poses are inverted (T_flange_base exported instead of T_base_flange), or "
                            f"the set-up is {other} (--{other.replace('_', '-')}), not {setup}",
                            camera, other, F, C, X, uv))
    hyps += _leave_one_out(camera, setup, F, C, X, uv, [names[i] for i in idx])
    if poses_file is not None:
        hyps += _conventions(camera, setup, poses_file, [labels[i] for i in idx], C, X, uv)
    if camera_given and image_size is not None:
        hyps += _intrinsics(camera, setup, F, X, uv, image_size, min_points)
    return cause_reasons(hyps, limit, _linear_rms(camera, setup, F, C, X, uv))


def pairing_causes(*, camera, T_base_flange, used, image_points, target_points, setup: str, names, labels,
                   poses_file=None, camera_given: bool = False, image_size=None, min_points: int = 6) -> list:
    """The likely causes when no solution exists (the refinement diverged): the same hypotheses as
    :func:`handeye_gate`, judged on per-image PnP poses and linear solutions only."""
    from ...handeye import solve_pnp

    F_all = np.asarray(T_base_flange, dtype=float)
    idx = np.flatnonzero(used)
    F, uv, X = F_all[idx], np.asarray(image_points, dtype=float)[idx], np.asarray(target_points, dtype=float)
    C = solve_pnp(camera, X, uv, min_points=min_points)[0]
    good = np.all(np.isfinite(C), axis=(1, 2))
    pnp_rms = _rms(backprojection(camera, np.where(good[:, None, None], C, np.eye(4)), X, uv)[1][good])
    causes = _likely_causes(camera, setup, F_all, idx, C, X, uv, names, labels, pnp_rms, poses_file, camera_given,
                            image_size, min_points)
    angle = motion_mismatch(F, C, setup).angle_deg_median
    if not causes and math.isfinite(angle) and angle > MOTION_ANGLE_LIMIT_DEG:
        causes = [f"likely cause: the flange poses are in another order than the images (shuffled) or belong to "
                  f"another run (flange and camera motions disagree by {angle:.3g} deg in the median)"]
    return causes
