"""The hand-eye entry points: pick the set-up and the method, check the poses, solve."""

from __future__ import annotations

import numpy as np

from ..transforms import invert_transforms
from .ax_xb import daniilidis, park_martin, tsai_lenz
from .ax_zb import shah
from .motions import HandEyeError, check_motions, motion_pairs, robot_poses

__all__ = ["AX_XB_METHODS", "solve_hand_eye", "solve_robot_world_hand_eye"]

#: the AX = XB solvers by name
AX_XB_METHODS = {"tsai": tsai_lenz, "park": park_martin, "daniilidis": daniilidis}


def solve_hand_eye(T_base_flange, T_camera_target, *, setup: str = "eye_in_hand", method: str = "tsai") -> np.ndarray:
    """The hand-eye transform (4, 4) [mm] by a linear AX = XB solver.

    T_base_flange, T_camera_target (N, 4, 4) [mm], one per image (see :mod:`.motions`). Returns
    ``T_flange_camera`` for ``setup="eye_in_hand"`` and ``T_base_camera`` for ``"eye_to_hand"``.
    method: ``tsai``, ``park`` or ``daniilidis``. Raises :class:`HandEyeError` for fewer than 3
    poses, mismatched counts, pure translations or rotations about one axis only.
    """
    if method not in AX_XB_METHODS:
        raise HandEyeError(f"unknown hand-eye method {method!r}; expected one of {', '.join(AX_XB_METHODS)}")
    A, B = motion_pairs(robot_poses(T_base_flange, setup), T_camera_target)
    check_motions(A)
    return AX_XB_METHODS[method](A, B)


def solve_robot_world_hand_eye(T_base_flange, T_camera_target, *, setup: str = "eye_in_hand") -> tuple:
    """Hand-eye and robot-world transforms together (AX = ZB, Shah's closed form).

    Returns ``(T_flange_camera, T_base_target)`` for eye-in-hand and ``(T_base_camera,
    T_flange_target)`` for eye-to-hand, (4, 4) each [mm]. Same checks as :func:`solve_hand_eye`.
    """
    F = robot_poses(T_base_flange, "eye_in_hand")
    C = np.asarray(T_camera_target, dtype=float)
    A, _ = motion_pairs(robot_poses(T_base_flange, setup), C)  # counts, >= 3 poses
    check_motions(A)
    if setup == "eye_in_hand":
        X, Z = shah(F, invert_transforms(C))
        return X, Z
    X, Z = shah(F, C)  # X = T_flange_target, Z = T_base_camera
    return Z, X
