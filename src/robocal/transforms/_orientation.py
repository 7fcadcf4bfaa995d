"""Orientation conventions by explicit name: Euler angles, and pose vectors at the boundary.

Quaternions and the rotation-vector logarithm live in ``_quaternion``; pose vectors here use them
(``"quaternion"``, ``"rotvec"``) beside every Euler convention.

Every function is batched over leading ``...`` dimensions and works on rotation matrices shaped
``(..., 3, 3)``. Angles are radians here; only :func:`pose_from_transform` and
:func:`transform_from_pose` (the boundary to controllers and instruments) take declared units.
The exact matrix formula of every convention is in ``EULER_CONVENTIONS`` and in
``docs/conventions.md``. Nothing is ever guessed: an unknown name raises ``ValueError`` listing the
valid ones.

Euler angle ranges returned by :func:`euler_from_matrix`: first and third angle in (-pi, pi];
middle angle in [-pi/2, pi/2] for Tait-Bryan sequences (three different axes, e.g. KUKA ABC) and
in [0, pi] for proper Euler sequences (first axis repeated, e.g. Z-X'-Z'', Z-Y'-Z'').

Gimbal lock: when the middle angle is at a singularity (cos(middle) ~ 0 for Tait-Bryan,
sin(middle) ~ 0 for proper Euler), only the sum or difference of the first and third angle is
defined. Then the angle of the rightmost factor of the matrix formula is set to 0 (up to rounding)
and the leftmost angle carries the whole rotation: KUKA C = 0, FANUC/rpy/extrinsic W = roll = a = 0,
Z-X'-Z'' c = 0. In all cases the rightmost angle is computed from what remains after the other
two, so
``matrix_from_euler(euler_from_matrix(R, c), c)`` reproduces ``R`` to rounding everywhere.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ._basic import so3_exp, transforms_from
from ._checks import as_matrices, as_vectors, check_transforms
from ._quaternion import matrix_from_quaternion_named, quaternion_from_matrix, rotvec_from_matrix

__all__ = [
    "EULER_CONVENTIONS",
    "POSE_CONVENTIONS",
    "LENGTH_UNITS",
    "ANGLE_UNITS",
    "matrix_from_euler",
    "euler_from_matrix",
    "matrix_from_rotvec",
    "pose_from_transform",
    "transform_from_pose",
]

_AXIS = {"x": 0, "y": 1, "z": 2}


@dataclass(frozen=True)
class _Euler:
    seq: str  # intrinsic axis sequence: R = R_seq[0](u0) @ R_seq[1](u1) @ R_seq[2](u2)
    perm: tuple[int, int, int]  # (u0, u1, u2) = triple[perm]: user triple -> intrinsic order
    description: str


def _build_conventions() -> dict[str, _Euler]:
    conv: dict[str, _Euler] = {}

    def named(name, seq, perm, description):
        conv[name] = _Euler(seq, perm, description)

    named(
        "kuka_abc", "zyx", (0, 1, 2),
        "KUKA (A, B, C): intrinsic Z-Y'-X'', R = Rz(A) @ Ry(B) @ Rx(C); same matrix as "
        "fanuc_wpr with the triple reversed",
    )
    named(
        "fanuc_wpr", "zyx", (2, 1, 0),
        "FANUC (W, P, R): fixed axes X then Y then Z, R = Rz(R) @ Ry(P) @ Rx(W); same matrix "
        "as kuka_abc with (A, B, C) = (R, P, W)",
    )
    named(
        "kawasaki_oat", "zyz", (0, 1, 2),
        "Kawasaki (O, A, T): intrinsic Z-Y'-Z'', R = Rz(O) @ Ry(A) @ Rz(T)",
    )
    named(
        "rpy", "zyx", (2, 1, 0),
        "URDF (roll, pitch, yaw): fixed axes X then Y then Z, R = Rz(yaw) @ Ry(pitch) @ Rx(roll); "
        "same matrix as xyz_extrinsic",
    )
    named("zxz", "zxz", (0, 1, 2), "thesis (4-3) (a, b, c): intrinsic Z-X'-Z'', R = Rz(a) @ Rx(b) @ Rz(c)")
    named("zyz", "zyz", (0, 1, 2), "(a, b, c): intrinsic Z-Y'-Z'', R = Rz(a) @ Ry(b) @ Rz(c)")

    # Generic names for all 12 axis sequences, intrinsic and extrinsic.
    tait = ["xyz", "xzy", "yxz", "yzx", "zxy", "zyx"]
    proper = ["xyx", "xzx", "yxy", "yzy", "zxz", "zyz"]
    for seq in tait + proper:
        A, B, C = (s.upper() for s in seq)
        named(
            f"{seq}_intrinsic", seq, (0, 1, 2),
            f"(a, b, c): intrinsic (moving axes) {A}-{B}'-{C}'', "
            f"R = R{seq[0]}(a) @ R{seq[1]}(b) @ R{seq[2]}(c)",
        )
        named(
            f"{seq}_extrinsic", seq[::-1], (2, 1, 0),
            f"(a, b, c): extrinsic (fixed axes) {seq[0]} then {seq[1]} then {seq[2]}, "
            f"R = R{seq[2]}(c) @ R{seq[1]}(b) @ R{seq[0]}(a)",
        )
    return conv


_EULER = _build_conventions()

#: Euler conventions by name -> human-readable description with the exact matrix formula.
EULER_CONVENTIONS: dict[str, str] = {name: c.description for name, c in _EULER.items()}

#: Every name accepted by :func:`pose_from_transform` / :func:`transform_from_pose`.
POSE_CONVENTIONS: tuple[str, ...] = tuple(_EULER) + ("quaternion", "rotvec")

#: Boundary units: factor from the unit to the internal unit (mm, rad).
LENGTH_UNITS: dict[str, float] = {"mm": 1.0, "m": 1000.0}
ANGLE_UNITS: dict[str, float] = {"rad": 1.0, "deg": np.pi / 180.0}

_GIMBAL_EPS = 1e-14  # below this cos/sin of the middle angle, the first and third angle are one


def _euler(convention) -> _Euler:
    key = str(convention).strip().lower() if isinstance(convention, str) else None
    if key not in _EULER:
        raise ValueError(
            f"unknown Euler convention {convention!r}; valid names: {', '.join(sorted(_EULER))}"
        )
    return _EULER[key]


def _elementary(axis: int, angle: np.ndarray) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    R = np.zeros(angle.shape + (3, 3))
    m, n = (axis + 1) % 3, (axis + 2) % 3
    R[..., axis, axis] = 1.0
    R[..., m, m] = c
    R[..., n, n] = c
    R[..., m, n] = -s
    R[..., n, m] = s
    return R


def matrix_from_euler(angles, convention: str) -> np.ndarray:
    """Rotation matrices ``(..., 3, 3)`` from Euler triples ``(..., 3)`` [rad] in ``convention``.

    ``convention`` is a key of :data:`EULER_CONVENTIONS` (e.g. ``"kuka_abc"``, ``"fanuc_wpr"``,
    ``"zxz"``, ``"rpy"``, ``"xyz_extrinsic"``); the triple is in the order the convention names it
    (KUKA (A, B, C), FANUC (W, P, R), URDF (roll, pitch, yaw), ...).
    """
    conv = _euler(convention)
    angles = as_vectors(angles, 3, "angles")
    u = angles[..., list(conv.perm)]
    a0, a1, a2 = (_AXIS[ch] for ch in conv.seq)
    return _elementary(a0, u[..., 0]) @ _elementary(a1, u[..., 1]) @ _elementary(a2, u[..., 2])


def euler_from_matrix(R, convention: str) -> np.ndarray:
    """Euler triples ``(..., 3)`` [rad] in ``convention`` from rotations ``(..., 3, 3)``.

    Inverse of :func:`matrix_from_euler`. Ranges: first and third angle in (-pi, pi]; middle angle
    in [-pi/2, pi/2] (three different axes) or [0, pi] (first axis repeated). At gimbal lock
    the angle of the rightmost matrix factor (KUKA C, FANUC W, rpy roll, Z-X'-Z'' c) is set to 0
    (see the module docstring); the matrix round trip always holds.
    """
    conv = _euler(convention)
    R = as_matrices(R, "R")
    i, j, last = (_AXIS[ch] for ch in conv.seq)
    proper = i == last
    k = 3 - i - j  # the axis not among the first two
    s = 1.0 if (i, j, k) in ((0, 1, 2), (1, 2, 0), (2, 0, 1)) else -1.0

    if proper:
        # R = Ri(a) Rj(b) Ri(c): R[i,i] = cos b, column i = sin b * (., sin a, -s cos a) ...
        sb = np.hypot(R[..., i, j], R[..., i, k])
        b = np.arctan2(sb, R[..., i, i])
        regular = sb > _GIMBAL_EPS
        a_reg = np.arctan2(R[..., j, i], -s * R[..., k, i])
    else:
        # R = Ri(a) Rj(b) Rk(c): R[i,k] = s sin b, row i = cos b * (cos c, -s sin c, .) ...
        cb = np.hypot(R[..., i, i], R[..., i, j])
        b = np.arctan2(s * R[..., i, k], cb)
        regular = cb > _GIMBAL_EPS
        a_reg = np.arctan2(-s * R[..., j, k], R[..., k, k])
    # Gimbal lock: third angle 0, so column j of R is Ri(a) e_j = cos a e_j + s sin a e_k.
    a_lock = np.arctan2(s * R[..., k, j], R[..., j, j])
    a = np.where(regular, a_reg, a_lock)

    # Third angle from the remainder Rj(b)^T Ri(a)^T R = R_last(c): robust near the singularity
    # because any error in a is absorbed here.
    Rem = np.swapaxes(_elementary(i, a) @ _elementary(j, b), -1, -2) @ R
    m, n = (last + 1) % 3, (last + 2) % 3
    c = np.arctan2(Rem[..., n, m] - Rem[..., m, n], Rem[..., m, m] + Rem[..., n, n])
    u = np.stack([_wrap(a), b, _wrap(c)], axis=-1)
    out = np.empty_like(u)
    out[..., list(conv.perm)] = u
    return out


def _wrap(x: np.ndarray) -> np.ndarray:
    """Wrap angles to (-pi, pi]."""
    y = np.remainder(x + np.pi, 2.0 * np.pi) - np.pi
    return np.where(y <= -np.pi, y + 2.0 * np.pi, y)


# --- rotation vectors (axis * angle) -----------------------------------------------------------


def matrix_from_rotvec(rotvec) -> np.ndarray:
    """Rotation matrices ``(..., 3, 3)`` from rotation vectors ``(..., 3)`` = axis * angle [rad]."""
    return so3_exp(as_vectors(rotvec, 3, "rotvec"))


# --- poses at the boundary (declared units) ----------------------------------------------------


def _unit(value, table: dict[str, float], what: str) -> float:
    if value not in table:
        raise ValueError(f"unknown {what} {value!r}; valid: {', '.join(table)}")
    return table[value]


def _pose_convention(convention) -> str:
    key = convention.strip().lower() if isinstance(convention, str) else None
    if key not in POSE_CONVENTIONS:
        raise ValueError(
            f"unknown pose convention {convention!r}; valid names: "
            f"{', '.join(sorted(POSE_CONVENTIONS))}"
        )
    return key


def pose_from_transform(T, convention: str, length_unit: str = "mm", angle_unit: str = "deg") -> np.ndarray:
    """Controller/instrument pose vectors from transforms ``(..., 4, 4)`` (internal mm).

    Returns ``(..., 6)`` = (x, y, z, a, b, c) for an Euler ``convention`` or ``"rotvec"``
    (x, y, z, rx, ry, rz), or ``(..., 7)`` = (x, y, z, w, qx, qy, qz) for ``"quaternion"``.
    Position is in ``length_unit`` ("mm" or "m"); Euler and rotation-vector angles in
    ``angle_unit`` ("deg" or "rad"); quaternions are unitless (``angle_unit`` is ignored).
    Examples: KUKA ``("kuka_abc", "mm", "deg")``, ABB ``("quaternion", "mm")``,
    Universal Robots ``("rotvec", "m", "rad")``.
    """
    conv = _pose_convention(convention)
    T = check_transforms(T, "T")
    lf = _unit(length_unit, LENGTH_UNITS, "length_unit")
    af = _unit(angle_unit, ANGLE_UNITS, "angle_unit")
    p = T[..., :3, 3] / lf
    R = T[..., :3, :3]
    if conv == "quaternion":
        ori = quaternion_from_matrix(R)
    elif conv == "rotvec":
        ori = rotvec_from_matrix(R) / af
    else:
        ori = euler_from_matrix(R, conv) / af
    return np.concatenate([p, ori], axis=-1)


def transform_from_pose(values, convention: str, length_unit: str = "mm", angle_unit: str = "deg") -> np.ndarray:
    """Transforms ``(..., 4, 4)`` (internal mm) from pose vectors; inverse of :func:`pose_from_transform`.

    ``values`` is ``(..., 6)`` for Euler conventions and ``"rotvec"``, ``(..., 7)`` =
    (x, y, z, w, qx, qy, qz) for ``"quaternion"`` (normalized; ``ValueError`` if its norm is
    off 1 by more than 1e-3, see :func:`matrix_from_quaternion`).
    """
    conv = _pose_convention(convention)
    lf = _unit(length_unit, LENGTH_UNITS, "length_unit")
    af = _unit(angle_unit, ANGLE_UNITS, "angle_unit")
    n = 7 if conv == "quaternion" else 6
    values = np.asarray(values, dtype=float)
    if values.ndim < 1 or values.shape[-1] != n:
        layout = "x, y, z, w, qx, qy, qz" if n == 7 else "x, y, z + 3 orientation values"
        raise ValueError(
            f"values: convention {conv!r} expects shape (..., {n}) = ({layout}), got {values.shape}"
        )
    if not np.all(np.isfinite(values)):
        raise ValueError("values: contains NaN or infinite values")
    p = values[..., :3] * lf
    if conv == "quaternion":
        R = matrix_from_quaternion_named(values[..., 3:], 1e-3, "values[..., 3:7] (quaternion w, x, y, z)")
    elif conv == "rotvec":
        R = so3_exp(values[..., 3:] * af)
    else:
        R = matrix_from_euler(values[..., 3:] * af, conv)
    return transforms_from(R, p)
