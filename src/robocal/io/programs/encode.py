"""New values for a target in its program's units and conventions, closest to the old numbers.

An orientation has several equivalent number triples (Euler angles +-360 deg or the second
solution with the middle angle mirrored, q and -q, a rotation vector of angle t or 2 pi - t about
the opposite axis). The writer picks the one nearest the numbers already in the program, so a
small correction gives small changes; an unchanged rotation (or position) keeps its numbers.
"""

from __future__ import annotations

import numpy as np

from ...transforms import (
    ANGLE_UNITS,
    LENGTH_UNITS,
    check_transforms,
    euler_from_matrix,
    matrix_from_euler,
    quaternion_from_matrix,
    rotvec_from_matrix,
)

__all__ = ["target_values", "UNCHANGED_MM", "UNCHANGED_ROTATION"]

#: A position closer than this to the old one [mm] keeps its numbers.
UNCHANGED_MM = 1e-9
#: A rotation whose matrix differs by less than this from the old one keeps its numbers.
UNCHANGED_ROTATION = 1e-12
_UNIT = {**LENGTH_UNITS, **ANGLE_UNITS, "1": 1.0}


def _nearest_turn(angle: float, previous: float) -> float:
    """``angle`` or ``angle +- 2 pi`` nearest ``previous``, staying within [-pi, pi]."""
    candidates = [a for a in (angle, angle - 2 * np.pi, angle + 2 * np.pi) if abs(a) <= np.pi + 1e-9]
    return min(candidates, key=lambda a: abs(a - previous))


def _euler_near(R, convention: str, previous) -> np.ndarray:
    """Euler triple [rad] of ``R`` nearest ``previous`` among the two solutions."""
    a = euler_from_matrix(R, convention)
    b = np.array([a[0] + np.pi, np.pi - a[1], a[2] + np.pi])
    b = (b + np.pi) % (2 * np.pi) - np.pi
    solutions = [a] + ([b] if np.allclose(matrix_from_euler(b, convention), R, atol=1e-12) else [])
    options = [np.array([_nearest_turn(x, p) for x, p in zip(c, previous)]) for c in solutions]
    return min(options, key=lambda c: float(np.max(np.abs(c - previous))))


def _rotvec_near(R, previous) -> np.ndarray:
    """Rotation vector [rad] of ``R``: angle t about u, or 2 pi - t about -u, nearest ``previous``."""
    r = rotvec_from_matrix(R)
    angle = np.linalg.norm(r)
    if angle < 1e-12:
        return r
    other = r * (angle - 2 * np.pi) / angle
    return min((r, other), key=lambda c: float(np.linalg.norm(c - previous)))


def _orientation(target, R) -> np.ndarray:
    """Orientation numbers [file units] of ``R`` for ``target``."""
    old = np.array(target.values[3:], dtype=float)
    scale = np.array([_UNIT[u] for u in target.units[3:]])
    if target.convention == "quaternion":
        q = quaternion_from_matrix(R)
        return -q if float(q @ old) < 0 else q
    if target.convention == "rotvec":
        return _rotvec_near(R, old * scale) / scale
    return _euler_near(R, target.convention, old * scale) / scale


def target_values(target, new) -> list[float]:
    """Numbers [file units] for ``target`` set to ``new``, in the order of ``target.spans``.

    new: (4, 4) pose [mm] in the target's frame for a Cartesian target, (n,) joints [rad; mm for
    linear axes] for a joint target.
    """
    scale = np.array([_UNIT[u] for u in target.units])
    if target.kind == "joint":
        q = np.asarray(new, dtype=float)
        if q.shape != (len(target.values),):
            raise ValueError(f"{target.name}: expected {len(target.values)} joint values, got shape {q.shape}")
        if not np.all(np.isfinite(q)):
            raise ValueError(f"{target.name}: joint values contain NaN or infinite values")
        return list(q / scale)
    T = check_transforms(np.asarray(new, dtype=float), f"{target.name} pose")
    if T.shape != (4, 4):
        raise ValueError(f"{target.name}: expected one (4, 4) pose, got shape {T.shape}")
    old_T = target.T_frame_tcp
    values = list(target.values)
    if np.max(np.abs(T[:3, 3] - old_T[:3, 3])) > UNCHANGED_MM:
        values[:3] = list(T[:3, 3] / scale[:3])
    if np.max(np.abs(T[:3, :3] - old_T[:3, :3])) > UNCHANGED_ROTATION:
        values[3:] = list(_orientation(target, T[:3, :3]))
    return values
