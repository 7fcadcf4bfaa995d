"""Pose conventions, relative motions and degeneracy checks for hand-eye calibration
(METHODS.md section 3, "Hand-eye").

Inputs everywhere: ``T_base_flange`` (N, 4, 4) [mm], the robot's flange poses in its base frame
(the controller's reading), and ``T_camera_target`` (N, 4, 4) [mm], the target's pose in the
camera frame (e.g. from ``solvePnP``), one of each per image.

* **eye-in-hand** (camera on the flange): unknown ``X = T_flange_camera``; constant
  ``T_base_target = T_base_flange_i X T_camera_target_i``.
* **eye-to-hand** (camera fixed in the cell, target on the flange): unknown
  ``X = T_base_camera``; constant ``T_flange_target = T_base_flange_i^-1 X T_camera_target_i``.

Eye-to-hand is eye-in-hand with the flange poses inverted (``T_flange_base`` in place of
``T_base_flange``); :func:`robot_poses` does that inversion so every solver sees one form. For
images i < j the motions ``A = F_j^-1 F_i`` and ``B = C_j C_i^-1`` (F the possibly inverted
robot poses, C the observations) satisfy ``A X = X B``.
"""

from __future__ import annotations
from ..errors import InputError

import numpy as np

from ..transforms import invert_transforms, so3_log

__all__ = ["SETUPS", "HandEyeError", "robot_poses", "motion_pairs", "check_motions"]

#: the two camera set-ups by name
SETUPS = ("eye_in_hand", "eye_to_hand")


class HandEyeError(InputError):
    """A pose set from which the hand-eye transform cannot be determined (the message says why)."""


def _frames(T, name):
    T = np.asarray(T, dtype=float)
    if T.ndim != 3 or T.shape[1:] != (4, 4):
        raise HandEyeError(f"{name}: expected (N, 4, 4) transforms, got shape {T.shape}")
    return T


def robot_poses(T_base_flange, setup: str) -> np.ndarray:
    """The robot poses as the solvers use them: ``T_base_flange`` for eye-in-hand,
    ``T_flange_base`` (inverted) for eye-to-hand, (N, 4, 4)."""
    T = _frames(T_base_flange, "T_base_flange")
    if setup == "eye_in_hand":
        return T
    if setup == "eye_to_hand":
        return invert_transforms(T)
    raise HandEyeError(f"unknown set-up {setup!r}; expected eye_in_hand or eye_to_hand")


def motion_pairs(F, C) -> tuple:
    """All relative motions over pairs i < j: ``(A, B)``, each (M, 4, 4), ``A X = X B``.

    F (N, 4, 4): robot poses from :func:`robot_poses`; C (N, 4, 4): ``T_camera_target``.
    """
    F, C = _frames(F, "robot poses"), _frames(C, "T_camera_target")
    if len(F) != len(C):
        raise HandEyeError(f"{len(F)} robot poses but {len(C)} target observations: they must pair one to one")
    if len(F) < 3:
        raise HandEyeError(f"hand-eye calibration needs at least 3 poses (2 motions with different rotation axes), "
                           f"got {len(F)}")
    i, j = np.triu_indices(len(F), k=1)
    A = invert_transforms(F[j]) @ F[i]
    B = C[j] @ invert_transforms(C[i])
    return A, B


def check_motions(A, *, min_angle: float = np.radians(0.5), parallel_tol: float = 1e-3) -> None:
    """Raise :class:`HandEyeError` naming the problem if the motions A (M, 4, 4) cannot determine
    X: no rotation at all (pure translations: the rotation is undetermined), or every rotation
    about one axis (the translation along that axis is undetermined). ``min_angle`` [rad]: smaller
    rotations do not count; ``parallel_tol``: the second singular value of the rotation axes
    (as a fraction of the first) below which they are called parallel."""
    w = so3_log(np.asarray(A)[:, :3, :3])
    angle = np.linalg.norm(w, axis=1)
    turning = angle > min_angle
    if not np.any(turning):
        raise HandEyeError(f"degenerate poses: the robot only translates (largest relative rotation "
                           f"{np.degrees(angle.max()):.3g} deg); rotations about two different axes are needed")
    axes = w[turning] / angle[turning, None]
    axes *= np.where(axes @ axes[0] < 0, -1.0, 1.0)[:, None]  # an axis and its opposite are one axis
    s = np.linalg.svd(axes, compute_uv=False)
    if len(s) < 2 or s[1] < parallel_tol * s[0]:
        axis = np.round(axes.mean(0) / np.linalg.norm(axes.mean(0)), 3)
        raise HandEyeError(f"degenerate poses: every rotation is about one axis (flange-frame direction "
                           f"{axis.tolist()}); the translation along it is undetermined. Tilt the flange "
                           f"about a second axis")
