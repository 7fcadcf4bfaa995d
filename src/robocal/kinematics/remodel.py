"""A well-conditioned Craig MDH + beta model from a chain's exact joint axes (extended precision).

A controller's kinematic model can be numerically awkward: Universal Robots' factory calibration
adds DH deltas to nearly parallel axes, so the common normal of axes 2-3 and 3-4 slides far away
(``d`` of hundreds of metres, ``UniversalRobots/Universal_Robots_ROS2_Driver``,
``ur_calibration/doc/algorithm.rst``). The *same* kinematics has a well-conditioned description:
per pair of consecutive joint axes,

- axes that are perpendicular in the reference (nominal) model: the common normal, ``beta = 0``
  (classic MDH; well defined because the axes are far from parallel);
- axes that are parallel in the reference model: Hayati's choice -- the frame on axis ``i`` keeps
  the reference model's ``d`` and its x axis points to where the plane normal to axis ``i``
  cuts axis ``i + 1``; the small tilt between the axes is ``alpha`` and ``beta``.

:func:`well_conditioned_mdh` builds that model from the joint axis lines and the flange frame at
zero joints. Both are computed in ``numpy.longdouble`` (80-bit on x86-64 Linux: 64-bit mantissa,
so hundred-metre DH offsets cancel to ~1e-13 mm), and the parameters are rounded to float64 once at
the end; the caller checks the forward kinematics against the source model
(:func:`fk_longdouble`). Everything here is kinematics only (no files).
"""

from __future__ import annotations

import numpy as np

from ..errors import InputError
from .links import OP_RU, OP_RX, OP_RY, OP_RZ, OP_TU, OP_TX, OP_TY, OP_TZ, Link, link_operations, op_axis
from .model import EndEffector, RobotModel

__all__ = ["RemodelError", "dh_table_fk", "dh_table_axes", "model_axes", "fk_longdouble",
           "well_conditioned_mdh", "EXTENDED_PRECISION", "inverse_rigid"]

LD = np.longdouble
#: True when ``numpy.longdouble`` carries more than float64's 53 mantissa bits (x86-64 Linux: 64).
EXTENDED_PRECISION = bool(np.finfo(LD).eps < 1e-18)


#: Consecutive axes of the reference model count as parallel below this sine of their angle (0.05:
#: ~2.9 deg; nominal arms have 0 or 90 deg, a calibrated model a few hundredths of a degree off).
PARALLEL_SIN = 0.05


class RemodelError(InputError):
    """A chain cannot be described as a well-conditioned MDH + beta model (the message says why)."""


def _elementary(op: int, value, axis=(0.0, 0.0, 1.0)) -> np.ndarray:
    """(..., 4, 4) longdouble transform of one elementary operation, ``value`` (...,) [mm | rad]."""
    value = np.asarray(value, dtype=LD)
    T = np.zeros(value.shape + (4, 4), dtype=LD)
    for k in range(4):
        T[..., k, k] = 1
    if op in (OP_TX, OP_TY, OP_TZ):
        T[..., op - OP_TX, 3] = value
        return T
    u = np.asarray(axis, dtype=LD)
    if op == OP_TU:
        T[..., :3, 3] = value[..., None] * u
        return T
    c, s = np.cos(value), np.sin(value)
    if op == OP_RU:
        K = np.array([[0, -u[2], u[1]], [u[2], 0, -u[0]], [-u[1], u[0], 0]], dtype=LD)
        T[..., :3, :3] = (np.eye(3, dtype=LD) + s[..., None, None] * K
                          + (1 - c)[..., None, None] * (K @ K))
        return T
    i = op - OP_RX
    j, k = (i + 1) % 3, (i + 2) % 3
    T[..., j, j] = c
    T[..., k, k] = c
    T[..., j, k] = -s
    T[..., k, j] = s
    return T


def _check_serial_revolute(model: RobotModel) -> None:
    if not model.is_serial:
        raise RemodelError(f"{model.name}: only serial chains are supported, not trees")
    if any(L.joint_type != "revolute" for L in model.links):
        raise RemodelError(f"{model.name}: only chains of revolute joints are supported (no fixed or prismatic links)")


def fk_longdouble(model: RobotModel, q, end_effector=0) -> np.ndarray:
    """Base-to-end-effector poses in longdouble (no ``T_world_base``): controller joints ``q``
    (N, n_ctrl) [rad] -> (N, 4, 4) [mm].

    A reference for checking conversions of serial revolute chains (slow: plain numpy products).
    """
    _check_serial_revolute(model)
    q = np.atleast_2d(np.asarray(q, dtype=LD)) @ np.asarray(model.coupling, dtype=LD).T  # model joints
    T = np.broadcast_to(np.eye(4, dtype=LD), (len(q), 4, 4)).copy()
    for k, link in enumerate(model.links):
        for code, pname, moves in link_operations(link):
            value = LD(link.params[pname]) + (q[:, k] if moves else LD(0))
            T = T @ _elementary(code, np.broadcast_to(value, (len(q),)), op_axis(code, link.axis))
    ee = model.end_effectors[end_effector]
    return T @ np.asarray(ee.T_link_ee, dtype=LD)


def model_axes(model: RobotModel):
    """Joint axis lines and the end-effector frame of a serial revolute chain at zero joints.

    Returns ``points`` (n, 3) [mm], ``directions`` (n, 3) unit, ``T_base_ee`` (4, 4) [mm], all
    longdouble, in the robot base frame (without ``T_world_base``).
    """
    _check_serial_revolute(model)
    T = np.eye(4, dtype=LD)
    points, dirs = [], []
    for link in model.links:
        for code, pname, moves in link_operations(link):
            if moves:
                u = T[:3, :3] @ np.asarray(op_axis(code, link.axis), dtype=LD)
                if code not in (OP_RZ, OP_RU):
                    raise RemodelError(f"{model.name}: link {link.name!r} does not rotate about an axis")
                points.append(T[:3, 3].copy())
                dirs.append(u / np.sqrt(u @ u))
            T = T @ _elementary(code, LD(link.params[pname]), op_axis(code, link.axis))
    T = T @ np.asarray(model.end_effectors[0].T_link_ee, dtype=LD)
    return np.array(points), np.array(dirs), T


def dh_table_fk(theta, d, a, alpha, q) -> np.ndarray:
    """Forward kinematics of a standard DH table in longdouble.

    ``theta, d, a, alpha`` (n,) [rad | any length unit]; ``q`` (N, n) [rad]. Link i is
    ``Rz(theta_i + q_i) Tz(d_i) Tx(a_i) Rx(alpha_i)``. Returns (N, 4, 4) in the table's length unit.
    """
    q = np.atleast_2d(np.asarray(q, dtype=LD))
    T = np.broadcast_to(np.eye(4, dtype=LD), (len(q), 4, 4)).copy()
    for i in range(len(theta)):
        T = T @ _elementary(OP_RZ, LD(theta[i]) + q[:, i])
        T = T @ _elementary(OP_TZ, np.full(len(q), d[i], dtype=LD))
        T = T @ _elementary(OP_TX, np.full(len(q), a[i], dtype=LD))
        T = T @ _elementary(OP_RX, np.full(len(q), alpha[i], dtype=LD))
    return T


def dh_table_axes(theta, d, a, alpha):
    """Joint axis lines and the last DH frame of a standard DH table at zero joints (longdouble,
    the table's length unit): ``points`` (n, 3), ``directions`` (n, 3), ``T_base_last`` (4, 4)."""
    T = np.eye(4, dtype=LD)
    points, dirs = [], []
    for i in range(len(theta)):
        points.append(T[:3, 3].copy())
        dirs.append(T[:3, 2].copy())
        for op, v in ((OP_RZ, theta[i]), (OP_TZ, d[i]), (OP_TX, a[i]), (OP_RX, alpha[i])):
            T = T @ _elementary(op, LD(v))
    return np.array(points), np.array(dirs), T


def inverse_rigid(T) -> np.ndarray:
    """Inverse of a rigid transform (..., 4, 4) in its own dtype (numpy.linalg has no longdouble)."""
    T = np.asarray(T)
    out = np.zeros_like(T)
    Rt = np.swapaxes(T[..., :3, :3], -1, -2)
    out[..., :3, :3] = Rt
    out[..., :3, 3] = -(Rt @ T[..., :3, 3, None])[..., 0]
    out[..., 3, 3] = 1
    return out


def _unit(v):
    return v / np.sqrt(v @ v)


def _reference_frames(reference: RobotModel):
    """World frames (n, 4, 4) of the reference model's own MDH links at zero joints, and which
    consecutive axis pairs are parallel there (n - 1,) bool."""
    from .convert import dh_to_mdh

    ref = dh_to_mdh(reference) if reference.kind in ("dh", "dh_beta") else reference
    if ref.kind != "mdh":
        raise RemodelError(f"{reference.name}: the reference model must be dh, dh_beta or mdh, got {reference.kind}")
    T = np.eye(4, dtype=LD)
    frames = []
    for link in ref.links:
        for code, pname, _ in link_operations(link):
            T = T @ _elementary(code, LD(link.params[pname]))
        frames.append(T.copy())
    z = np.array([F[:3, 2] for F in frames])
    parallel = np.array([np.linalg.norm(np.cross(z[i], z[i + 1])) < PARALLEL_SIN for i in range(len(z) - 1)])
    return ref, np.array(frames), parallel


def _line_plane(p, u, o, n):
    """Point where the line ``p + t u`` meets the plane through ``o`` normal to ``n``."""
    denom = u @ n
    if abs(denom) < LD(1e-6):
        raise RemodelError("a joint axis is parallel to the plane it must cross (the axes are not near-parallel)")
    return p + ((o - p) @ n / denom) * u


def _common_normal_foot(p1, u1, p2, u2):
    """Point on line 1 closest to line 2 (lines not parallel)."""
    w = p1 - p2
    b = u1 @ u2
    denom = 1 - b * b
    t = (b * (u2 @ w) - (u1 @ w)) / denom
    return p1 + t * u1


def _first_entry(p, u):
    """Where the base x axis meets joint 1's axis (an MDH chain starts on it)."""
    x = np.array([1, 0, 0], dtype=LD)
    if np.linalg.norm(np.cross(u, x)) < 1e-9:
        raise RemodelError("joint 1's axis is parallel to the base x axis; an MDH chain cannot start there")
    foot = _common_normal_foot(p, u, np.zeros(3, dtype=LD), x)
    if np.sqrt(foot[1] ** 2 + foot[2] ** 2) > 1e-9:
        raise RemodelError("joint 1's axis does not meet the base x axis (the chain needs a base frame first)")
    return foot


def _frame(o, x, z):
    F = np.eye(4, dtype=LD)
    y = np.cross(z, x)
    F[:3, 0], F[:3, 1], F[:3, 2], F[:3, 3] = x, y, z, o
    return F


def _mdh_params(F_prev, F):
    """(alpha, a, beta, theta, d) with ``F_prev @ Rx(alpha) Tx(a) Ry(beta) Rz(theta) Tz(d) == F``."""
    G = inverse_rigid(F_prev) @ F
    z, p = G[:3, 2], G[:3, 3]
    beta = np.arcsin(np.clip(z[0], -1, 1))
    alpha = np.arctan2(-z[1], z[2])
    cb2 = z[1] * z[1] + z[2] * z[2]
    d = (p[1] * z[1] + p[2] * z[2]) / cb2
    a = p[0] - d * z[0]
    M = (_elementary(OP_RX, alpha) @ _elementary(OP_RY, beta))[:3, :3].T @ G[:3, :3]
    theta = np.arctan2(M[1, 0], M[0, 0])
    return alpha, a, beta, theta, d


def well_conditioned_mdh(points, directions, T_base_ee, reference: RobotModel, *, name=None, title=None,
                         source="") -> RobotModel:
    """The MDH + beta model (kind ``mdh``) of a serial revolute chain given by its joint axes.

    Parameters
    ----------
    points, directions : (n, 3) a point on each joint axis [mm] and its unit direction (the
        positive joint rotation), at zero joints, in the robot base frame (longdouble preferred).
    T_base_ee : (4, 4) the flange (end effector) frame at zero joints [mm].
    reference : the nominal model of the same robot (dh, dh_beta or mdh, n revolute joints): it
        decides which axis pairs are treated as parallel, the signs of the common normals and the
        ``d`` kept on parallel axes, so the result stays close to the nominal MDH parameters.
        Names, joint limits, controller joint names and the joint coupling (signs, FANUC's J2/J3)
        are taken from it; the base is identity. ``points``/``directions`` are the model joints'
        (positive direction = positive model joint) at zero controller joints.

    Returns
    -------
    RobotModel of kind ``mdh`` (every link with ``beta``) whose forward kinematics equal the
    chain's, joints measured from the same zero. The convention's redundant parameters are marked
    fixed (``beta`` after a non-parallel pair, ``d`` of a frame before a parallel axis), so a
    calibration that starts from the file identifies the others.
    """
    P = np.asarray(points, dtype=LD)
    U = np.array([_unit(u) for u in np.asarray(directions, dtype=LD)])
    Tee = np.asarray(T_base_ee, dtype=LD)
    ref, ref_frames, parallel = _reference_frames(reference)
    n = len(P)
    if n != len(ref.links):
        raise RemodelError(f"{reference.name}: the reference model has {len(ref.links)} joints, the chain {n}")
    F_prev = np.eye(4, dtype=LD)
    entry = _first_entry(P[0], U[0])  # where the previous frame's x axis meets this axis
    links = []
    for i in range(n):
        u, ref_F = U[i], ref_frames[i]
        if i + 1 < n and not parallel[i]:
            o = _common_normal_foot(P[i], u, P[i + 1], U[i + 1])
            x = _unit(np.cross(u, U[i + 1]))
            if x @ ref_F[:3, 0] < 0:
                x = -x
            next_entry = _common_normal_foot(P[i + 1], U[i + 1], P[i], u)
        elif i + 1 < n:
            o = entry + LD(ref.links[i].params["d"]) * u
            next_entry = _line_plane(P[i + 1], U[i + 1], o, u)
            v = next_entry - o
            if np.sqrt(v @ v) < 1e-6:
                raise RemodelError(f"joint axes {i + 1} and {i + 2} coincide: no frame direction between them")
            x = _unit(v)
            if x @ ref_F[:3, 0] < 0:
                x = -x
        else:
            o = P[i] + ((Tee[:3, 3] - P[i]) @ u) * u
            xe = Tee[:3, 0] - (Tee[:3, 0] @ u) * u
            x = _unit(xe) if np.sqrt(xe @ xe) > 1e-9 else _unit(ref_F[:3, 0] - (ref_F[:3, 0] @ u) * u)
            next_entry = None
        F = _frame(o, x, u)
        alpha, a, beta, theta, d = _mdh_params(F_prev, F)
        lk = reference.links[i]
        # the convention's held parameters: beta after a non-parallel pair (common normal), d of a frame
        # whose axis is parallel to the next (Hayati); a calibration of this file leaves them alone
        held = set()
        if i == 0 or not parallel[i - 1]:
            held.add("beta")
        if i + 1 < n and parallel[i]:
            held.add("d")
        # held values are the convention's exact ones; what the construction returns differs by rounding only
        if "beta" in held and abs(beta) < 1e-12:
            beta = LD(0)
        if "d" in held and abs(d - LD(ref.links[i].params["d"])) < 1e-12:
            d = LD(ref.links[i].params["d"])
        links.append(Link(lk.name, "revolute", "mdh",
                          {"alpha": float(alpha), "a": float(a), "beta": float(beta), "theta": float(theta),
                           "d": float(d)}, i - 1, (0.0, 0.0, 1.0), frozenset(held)))
        F_prev, entry = F, next_entry
    T_ee = inverse_rigid(F_prev) @ Tee
    T_ee = np.asarray(T_ee, dtype=float)
    if np.abs(T_ee - np.eye(4)).max() < 1e-13:
        T_ee = np.eye(4)
    ees = [EndEffector("flange", n - 1, T_ee)]
    return RobotModel(name=name or reference.name, kind="mdh", links=links,
                      controller_joints=reference.controller_joints, coupling=reference.coupling,
                      limits=reference.limits,
                      T_world_base=np.eye(4), end_effectors=ees, title=title if title is not None else reference.title,
                      source=source, extra={"length_unit": "mm", "angle_unit": "deg"})
