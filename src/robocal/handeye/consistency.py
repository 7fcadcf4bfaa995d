"""Consistency of hand-eye data without a solution: the screw invariants of paired motions.

For every pair of images (i, j) the flange motion ``A`` and the camera motion ``B`` are conjugate
(``A X = X B``), so they share two numbers that do not depend on the unknown hand-eye transform:
the rotation angle and the screw pitch (the translation along the rotation axis, mm). Eye-in-hand:
``A = F_i^-1 F_j``, ``B = C_i C_j^-1``; eye-to-hand: ``A = F_j F_i^-1``, ``B = C_j C_i^-1``
(``F`` = T_base_flange, ``C`` = T_camera_target from PnP; :mod:`.motions`).

* A pose row paired with the wrong image (swapped, shifted, shuffled) or read in the wrong Euler
  convention breaks the **angle** invariant for that image's pairs.
* Inverted flange poses (``T_flange_base`` exported) and the wrong set-up keep the angles (the
  motions are conjugate either way) but break the **pitch** invariant.

Per image the median mismatch over its pairs names the images that disagree; the median over all
pairs scores a hypothesis (shifted pairing, inverted poses, another convention) for the cause.
Math only: numpy.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np

from ..transforms import invert_transforms

__all__ = ["MotionMismatch", "motion_mismatch", "PITCH_MIN_ANGLE_DEG"]

#: Pairs rotating less than this [deg] have a poorly defined screw axis: no pitch comparison.
PITCH_MIN_ANGLE_DEG = 10.0


@dataclass(frozen=True)
class MotionMismatch:
    """Screw-invariant mismatch of paired flange and camera motions.

    angle_deg (N, N): |angle(A_ij) - angle(B_ij)| [deg] (NaN on the diagonal and for unusable
    images); pitch_mm (N, N): |pitch(A_ij) - pitch(B_ij)| [mm] (NaN where either rotation is below
    ``PITCH_MIN_ANGLE_DEG``); per_image_angle_deg, per_image_pitch_mm (N,): the median over each
    image's pairs; angle_deg_median, pitch_mm_median: the median over all pairs.
    """

    angle_deg: np.ndarray
    pitch_mm: np.ndarray
    per_image_angle_deg: np.ndarray
    per_image_pitch_mm: np.ndarray
    angle_deg_median: float
    pitch_mm_median: float


def _screws(T) -> tuple:
    """(angle [rad], pitch [mm]) of transforms (..., 4, 4): the rotation angle and the translation
    along the rotation axis (the axis oriented so that the angle is positive)."""
    R = T[..., :3, :3]
    tr = np.clip((np.trace(R, axis1=-2, axis2=-1) - 1.0) / 2.0, -1.0, 1.0)
    angle = np.arccos(tr)
    w = np.stack([R[..., 2, 1] - R[..., 1, 2], R[..., 0, 2] - R[..., 2, 0], R[..., 1, 0] - R[..., 0, 1]], axis=-1)
    n = np.linalg.norm(w, axis=-1, keepdims=True)
    axis = np.divide(w, n, out=np.zeros_like(w), where=n > 1e-12)
    pitch = np.einsum("...i,...i->...", axis, T[..., :3, 3])
    return angle, pitch


def _nanmedian(a, axis=None):
    """np.nanmedian without the all-NaN warning (NaN where nothing is finite)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        return np.nanmedian(np.asarray(a, dtype=float), axis=axis)


def motion_mismatch(T_base_flange, T_camera_target, setup: str = "eye_in_hand") -> MotionMismatch:
    """The screw-invariant mismatch of every pair of images (module docstring).

    T_base_flange (N, 4, 4) [mm]; T_camera_target (N, 4, 4) [mm] from PnP, NaN for an image
    without a pose; setup ``"eye_in_hand"`` | ``"eye_to_hand"``.
    """
    F = np.asarray(T_base_flange, dtype=float)
    C = np.asarray(T_camera_target, dtype=float)
    N = len(F)
    good = np.all(np.isfinite(C), axis=(1, 2)) & np.all(np.isfinite(F), axis=(1, 2))
    Fg = np.where(good[:, None, None], F, np.eye(4))
    Cg = np.where(good[:, None, None], C, np.eye(4))
    Fi, Ci = invert_transforms(Fg), invert_transforms(Cg)
    if setup == "eye_in_hand":
        A = Fi[:, None] @ Fg[None, :]   # A_ij = F_i^-1 F_j
        B = Cg[:, None] @ Ci[None, :]   # B_ij = C_i C_j^-1
    else:
        A = Fg[None, :] @ Fi[:, None]   # A_ij = F_j F_i^-1
        B = Cg[None, :] @ Ci[:, None]   # B_ij = C_j C_i^-1
    a_ang, a_pitch = _screws(A)
    b_ang, b_pitch = _screws(B)
    mask = good[:, None] & good[None, :] & ~np.eye(N, dtype=bool)
    angle = np.where(mask, np.degrees(np.abs(a_ang - b_ang)), np.nan)
    big = np.degrees(np.minimum(a_ang, b_ang)) >= PITCH_MIN_ANGLE_DEG
    pitch = np.where(mask & big, np.abs(a_pitch - b_pitch), np.nan)
    upper = np.triu(mask, 1)
    return MotionMismatch(
        angle_deg=angle, pitch_mm=pitch,
        per_image_angle_deg=_nanmedian(angle, axis=1), per_image_pitch_mm=_nanmedian(pitch, axis=1),
        angle_deg_median=float(_nanmedian(angle[upper])),
        pitch_mm_median=float(_nanmedian(pitch[upper & big])))
