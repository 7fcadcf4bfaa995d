"""Link conventions as sequences of elementary transforms.

Every model kind (standard DH, DH with Hayati's beta, Craig's modified DH, URDF joints, fixed
frames) is written as a short product of elementary operations ``Rx, Ry, Rz, Tx, Ty, Tz`` and a
rotation/translation about a unit axis ``u``. A parameter of the model is the argument of one
operation; a joint variable adds to the argument of its link's motion operation. This single
representation gives forward kinematics, the joint Jacobian and the identification Jacobian
((3-6) of METHODS.md) for every model kind without model-specific derivative code.

Link transforms (METHODS.md section 2):

- ``dh``:       ``Rz(theta) Tz(d) Tx(a) Rx(alpha)``                      (2-15)
- ``dh_beta``:  ``Rz(theta) Tz(d) Tx(a) Rx(alpha) Ry(beta)``             (2-18, Hayati; the thesis's "MDH")
- ``mdh``:      ``Rx(alpha) Tx(a) Ry(beta) Rz(theta) Tz(d)``             (Craig's modified DH; beta optional)
- ``urdf``:     ``Tx(x) Ty(y) Tz(z) Rz(yaw) Ry(pitch) Rx(roll) R_u(theta)`` (origin xyz/rpy, motion about axis u)
- ``frame``:    ``Tx(x) Ty(y) Tz(z) Rz(yaw) Ry(pitch) Rx(roll)``         (a fixed frame, any model kind)
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

# Operation codes shared with the compiled kernels.
OP_RX, OP_RY, OP_RZ, OP_TX, OP_TY, OP_TZ, OP_RU, OP_TU = range(8)
OP_NAMES = ("Rx", "Ry", "Rz", "Tx", "Ty", "Tz", "Ru", "Tu")
ROTATION_OPS = (OP_RX, OP_RY, OP_RZ, OP_RU)

MODEL_KINDS = ("dh", "dh_beta", "mdh", "urdf")
JOINT_TYPES = ("revolute", "prismatic", "fixed")

LENGTH_PARAMS = {"d", "a", "x", "y", "z"}
ANGLE_PARAMS = {"theta", "alpha", "beta", "roll", "pitch", "yaw"}


@dataclass(frozen=True)
class Link:
    """One link entry of a robot: a (possibly fixed) joint and the constant geometry around it.

    ``params`` maps parameter name (``theta, d, a, alpha, beta, x, y, z, roll, pitch, yaw``) to its
    value in millimetres / radians. ``convention`` is one of ``dh, dh_beta, mdh, urdf, frame``.
    ``parent`` is the index of the parent link, ``-1`` for the robot base.
    """

    name: str
    joint_type: str
    convention: str
    params: dict
    parent: int = -1
    axis: tuple = (0.0, 0.0, 1.0)
    fixed: frozenset = field(default_factory=frozenset)

    def __post_init__(self):
        if self.joint_type not in JOINT_TYPES:
            raise ValueError(f"link {self.name!r}: joint type {self.joint_type!r}, expected one of {JOINT_TYPES}")
        expected = link_param_names(self.convention, self.joint_type, has_beta="beta" in self.params)
        missing = [p for p in expected if p not in self.params]
        extra = [p for p in self.params if p not in expected]
        if missing or extra:
            raise ValueError(
                f"link {self.name!r} ({self.convention}, {self.joint_type}): parameters {sorted(self.params)}; "
                f"expected {list(expected)}"
                + (f" (missing {missing})" if missing else "")
                + (f" (unexpected {extra})" if extra else "")
            )
        for k, v in self.params.items():
            if not np.isfinite(v):
                raise ValueError(f"link {self.name!r}: parameter {k} = {v} is not a finite number")
        bad_fixed = set(self.fixed) - set(self.params)
        if bad_fixed:
            raise ValueError(f"link {self.name!r}: 'fixed' names unknown parameters {sorted(bad_fixed)}")
        ax = np.asarray(self.axis, dtype=float)
        if ax.shape != (3,) or not np.isclose(np.linalg.norm(ax), 1.0, atol=1e-6):
            raise ValueError(f"link {self.name!r}: axis must be a unit 3-vector, got {self.axis}")

    @property
    def moves(self) -> bool:
        return self.joint_type != "fixed"


def link_param_names(convention: str, joint_type: str, has_beta: bool = True) -> tuple:
    """Ordered parameter names of a link of the given convention."""
    if convention == "dh":
        return ("theta", "d", "a", "alpha") + (("beta",) if has_beta else ())
    if convention == "dh_beta":
        return ("theta", "d", "a", "alpha", "beta")
    if convention == "mdh":
        return ("alpha", "a") + (("beta",) if has_beta else ()) + ("theta", "d")
    if convention == "urdf":
        offset = () if joint_type == "fixed" else (("theta",) if joint_type == "revolute" else ("d",))
        return ("x", "y", "z", "roll", "pitch", "yaw") + offset
    if convention == "frame":
        return ("x", "y", "z", "roll", "pitch", "yaw")
    raise ValueError(f"unknown link convention {convention!r}, expected one of {MODEL_KINDS + ('frame',)}")


def link_operations(link: Link):
    """Elementary operations of ``link`` as ``(op_code, param_name, moves_with_joint)`` tuples.

    ``moves_with_joint`` marks the operation whose argument is ``param + q_model``: ``theta`` of a
    revolute DH/MDH joint, ``d`` of a prismatic one, the axis motion of a URDF joint.
    """
    rev = link.joint_type == "revolute"
    pri = link.joint_type == "prismatic"
    c = link.convention
    if c in ("dh", "dh_beta"):
        ops = [(OP_RZ, "theta", rev), (OP_TZ, "d", pri), (OP_TX, "a", False), (OP_RX, "alpha", False)]
        if "beta" in link.params:
            ops.append((OP_RY, "beta", False))
        return ops
    if c == "mdh":
        ops = [(OP_RX, "alpha", False), (OP_TX, "a", False)]
        if "beta" in link.params:
            ops.append((OP_RY, "beta", False))
        return ops + [(OP_RZ, "theta", rev), (OP_TZ, "d", pri)]
    ops = [(OP_TX, "x", False), (OP_TY, "y", False), (OP_TZ, "z", False),
           (OP_RZ, "yaw", False), (OP_RY, "pitch", False), (OP_RX, "roll", False)]
    if c == "urdf" and rev:
        ops.append((OP_RU, "theta", True))
    elif c == "urdf" and pri:
        ops.append((OP_TU, "d", True))
    return ops


def elementary_transforms(op: int, value, axis=(0.0, 0.0, 1.0)) -> np.ndarray:
    """Batched 4x4 transforms of one elementary operation; ``value`` (...,) in mm or rad."""
    value = np.asarray(value, dtype=float)
    T = np.zeros(value.shape + (4, 4))
    T[..., 0, 0] = T[..., 1, 1] = T[..., 2, 2] = T[..., 3, 3] = 1.0
    if op in (OP_TX, OP_TY, OP_TZ):
        T[..., op - OP_TX, 3] = value
        return T
    if op == OP_TU:
        T[..., :3, 3] = value[..., None] * np.asarray(axis, dtype=float)
        return T
    if op == OP_RU:
        from ..transforms import rot_axis

        T[..., :3, :3] = rot_axis(np.asarray(axis, dtype=float), value)
        return T
    i = op - OP_RX
    j, k = (i + 1) % 3, (i + 2) % 3
    c, s = np.cos(value), np.sin(value)
    T[..., j, j] = c
    T[..., k, k] = c
    T[..., j, k] = -s
    T[..., k, j] = s
    return T


def frame_from_xyz_rpy(xyz, rpy) -> np.ndarray:
    """(4, 4) of the ``frame`` convention from a translation ``xyz`` (3,) [mm] and fixed-axis roll,
    pitch, yaw ``rpy`` (3,) [rad]: ``R = Rz(yaw) Ry(pitch) Rx(roll)`` (robot files, URDF origins)."""
    from ..transforms import rot_x, rot_y, rot_z, transforms_from

    r, p, y = rpy
    return transforms_from(rot_z(y) @ rot_y(p) @ rot_x(r), np.asarray(xyz, dtype=float))


def op_axis(op: int, axis=(0.0, 0.0, 1.0)) -> np.ndarray:
    """Unit axis (3,) of an operation in the frame where it acts."""
    if op in (OP_RU, OP_TU):
        return np.asarray(axis, dtype=float)
    e = np.zeros(3)
    e[(op - OP_RX) % 3] = 1.0
    return e
