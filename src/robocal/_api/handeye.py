"""Hand-eye calibration in memory: the camera on the flange (or in the cell) from paired robot
poses and target observations (AX = XB)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["HandEyeOptions", "HandEyeResult", "calibrate_hand_eye"]


@dataclass(frozen=True)
class HandEyeOptions:
    """Settings of :func:`calibrate_hand_eye`, all with defaults.

    Parameters
    ----------
    setup : {"eye_in_hand", "eye_to_hand"}, default "eye_in_hand"
        Camera on the flange (target fixed in the cell) or camera fixed in the cell (target on
        the flange).
    method : {"tsai", "park", "daniilidis"}, default "park"
        Linear AX = XB solver.
    """

    setup: str = "eye_in_hand"
    method: str = "park"


@dataclass(frozen=True)
class HandEyeResult:
    """The outcome of :func:`calibrate_hand_eye`.

    Attributes
    ----------
    T_hand_eye : numpy.ndarray, shape (4, 4)
        ``T_flange_camera`` (eye-in-hand) or ``T_base_camera`` (eye-to-hand) [mm].
    setup, method : str
        The options used.
    rotation_residual_deg : float
        RMS rotation error of ``A X = X B`` over all pose pairs [deg].
    translation_residual_mm : float
        RMS translation error of ``A X = X B`` over all pose pairs [mm].
    n_poses : int
        Number of robot poses used.
    """

    T_hand_eye: np.ndarray
    setup: str
    method: str
    rotation_residual_deg: float
    translation_residual_mm: float
    n_poses: int


def calibrate_hand_eye(T_base_flange, T_camera_target, *, options: HandEyeOptions | None = None) -> HandEyeResult:
    """The hand-eye transform from robot poses and target observations.

    Parameters
    ----------
    T_base_flange : array_like, shape (N, 4, 4)
        Flange poses in the robot base frame [mm], N >= 3 with rotations about two axes at least.
    T_camera_target : array_like, shape (N, 4, 4)
        The target (e.g. a checkerboard) seen by the camera at each pose [mm].
    options : HandEyeOptions, optional
        Set-up and solver.

    Returns
    -------
    HandEyeResult
        The transform and its AX = XB consistency residuals.

    Raises
    ------
    robocal.InputError
        Fewer than 3 poses, mismatched counts, or motions that cannot determine the transform.
    """
    from ..handeye import motion_pairs, robot_poses, solve_hand_eye

    o = options if options is not None else HandEyeOptions()
    X = solve_hand_eye(T_base_flange, T_camera_target, setup=o.setup, method=o.method)
    A, B = motion_pairs(robot_poses(T_base_flange, o.setup), T_camera_target)
    D = np.linalg.inv(A @ X) @ (X @ B)  # (M, 4, 4), identity when consistent
    cos = np.clip((np.trace(D[:, :3, :3], axis1=1, axis2=2) - 1.0) / 2.0, -1.0, 1.0)
    rot = np.degrees(np.arccos(cos))
    trans = np.linalg.norm(D[:, :3, 3], axis=1)
    return HandEyeResult(T_hand_eye=X, setup=o.setup, method=o.method,
                         rotation_residual_deg=float(np.sqrt(np.mean(rot ** 2))),
                         translation_residual_mm=float(np.sqrt(np.mean(trans ** 2))), n_poses=len(np.asarray(T_base_flange)))
