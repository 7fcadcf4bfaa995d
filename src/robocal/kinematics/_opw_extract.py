"""Deriving the OPW parameters of a robot model from its joint axes (:func:`opw_from_model`).

The axes are read from the joint twists at ``q = 0``; each OPW condition is checked with its
size, the canonical frames are built step by step (base, arm plane, wrist), and the result is
verified against the model's own forward kinematics. Lengths in mm, angles in rad.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ..transforms import invert_transforms
from ._opw_model import NotAnalyticError, OPWParameters, opw_fk, wrap
from .model import RobotModel

__all__ = ["opw_from_model"]


def _unit(v):
    return v / np.linalg.norm(v)


def _closest(p1, w1, p2, w2):
    """Closest points of two non-parallel lines (unit directions): (point on 1, point on 2, s on 2)."""
    r = p2 - p1
    b = w1 @ w2
    den = 1.0 - b * b
    s = (r @ w1 - b * (r @ w2)) / den
    t = (b * (r @ w1) - r @ w2) / den
    return p1 + s * w1, p2 + t * w2, t


def _angle_off(cos_or_sin) -> float:
    return float(np.arcsin(min(1.0, abs(cos_or_sin))))


def _perp_in(v, n):
    """``v`` projected onto the plane normal to unit ``n``."""
    return v - (v @ n) * n


class _BaseFrame(NamedTuple):
    """The OPW base frame in the world: origin ``o`` on axis 1, axes ``x, y, z`` (3,) each;
    ``sign1`` = direction of the model's joint 1 about ``z``."""

    o: np.ndarray
    x: np.ndarray
    y: np.ndarray
    z: np.ndarray
    sign1: float


class _Arm(NamedTuple):
    """Arm-plane geometry at ``q_model = 0``: frame axes ``x1, y1`` (arm plane), ``z4, x4``
    (forearm), the lengths [mm], the OPW angles of joints 1-3 at zero [rad] and joint signs."""

    x1: np.ndarray
    y1: np.ndarray
    z4: np.ndarray
    x4: np.ndarray
    a1: float
    a2: float
    b: float
    c1: float
    c2: float
    c3: float
    off1: float
    t2_0: float
    t23_0: float
    sign2: float
    sign3: float
    sign4: float


class _Wrist(NamedTuple):
    """Wrist geometry at ``q_model = 0``: flange distance ``c4`` [mm], the OPW angles of joints
    4-6 at zero [rad], signs of joints 5 and 6."""

    c4: float
    t4_0: float
    t5_0: float
    t6_0: float
    sign5: float
    sign6: float


def _check_chain(model, name: str) -> np.ndarray:
    """The coupling matrix (6, 6) of a serial 6R model; :class:`NotAnalyticError` otherwise."""
    if model.n_joints != 6 or model.n_model_joints != 6:
        raise NotAnalyticError(f"{name}: needs 6 joints, has {model.n_joints} controller / "
                               f"{model.n_model_joints} model joints")
    if not model.is_serial:
        raise NotAnalyticError(f"{name}: not a serial chain")
    moving = [model.links[k] for k in model.moving]
    pris = [L.name for L in moving if L.joint_type != "revolute"]
    if pris:
        raise NotAnalyticError(f"{name}: joints {pris} are not revolute")
    C = np.asarray(model.coupling, dtype=float)
    cond = np.linalg.cond(C)
    if not np.isfinite(cond) or cond > 1e12:
        raise NotAnalyticError(f"{name}: coupling matrix is singular (condition number {cond:.3g})")
    return C


def _joint_axes(model):
    """Unit directions ``w`` (6, 3) (positive model joint rotation) and a point ``p`` (6, 3) [mm]
    on each joint axis at ``q = 0``, from the joint twists."""
    _, jt, _ = model.twists(np.zeros((1, 6)))
    w = jt[0, :3, :].T.copy()
    v = jt[0, 3:, :].T
    norms = np.linalg.norm(w, axis=1)
    w /= norms[:, None]
    p = np.cross(w, v) / norms[:, None]
    return w, p


def _opw_class_failures(w, p, tol_angle: float, tol_length: float):
    """The OPW conditions on the joint axes: ``(failures, wrist centre)``, failures a list of texts
    (each with the size of its deviation), the wrist centre (3,) [mm] or None."""
    w1, w2, w3, w4, w5, w6 = w
    _, _, _, p4, p5, p6 = p
    deg = 180.0 / np.pi
    failures = []

    def need(cond_ok, text):
        if not cond_ok:
            failures.append(text)

    e = _angle_off(w1 @ w2)
    need(e <= tol_angle, f"axes 1 and 2 are not perpendicular (off by {e:.3g} rad = {e * deg:.3g} deg)")
    e = _angle_off(np.linalg.norm(np.cross(w2, w3)))
    need(e <= tol_angle, f"axes 2 and 3 are not parallel (angle {e:.3g} rad = {e * deg:.3g} deg)")
    e = _angle_off(w3 @ w4)
    need(e <= tol_angle, f"axes 3 and 4 are not perpendicular (off by {e:.3g} rad = {e * deg:.3g} deg)")
    e = _angle_off(w4 @ w5)
    need(e <= tol_angle, f"axes 4 and 5 are not perpendicular (off by {e:.3g} rad = {e * deg:.3g} deg)")
    e = _angle_off(w5 @ w6)
    need(e <= tol_angle, f"axes 5 and 6 are not perpendicular (off by {e:.3g} rad = {e * deg:.3g} deg)")
    wc = None
    if abs(w4 @ w5) < 0.5 and abs(w5 @ w6) < 0.5:
        a45, b45, _ = _closest(p4, w4, p5, w5)
        a56, b56, _ = _closest(p6, w6, p5, w5)
        d45 = np.linalg.norm(a45 - b45)
        d56 = np.linalg.norm(a56 - b56)
        d5 = np.linalg.norm(b45 - b56)
        need(d45 <= tol_length, f"axes 4 and 5 do not intersect (distance {d45:.3g} mm)")
        need(d56 <= tol_length, f"axes 5 and 6 do not intersect (distance {d56:.3g} mm)")
        need(d5 <= tol_length, f"axes 4 and 6 meet axis 5 at different points ({d5:.3g} mm apart): "
                               f"the wrist is not spherical")
        wc = (a45 + b45 + a56 + b56) / 4.0
    else:
        failures.append("wrist axes 4-5-6 are far from perpendicular: no spherical wrist")
    return failures, wc


def _base_frame(w1, p1, T_wb_model) -> _BaseFrame:
    """OPW base frame: z along axis 1 on the side of the model base's z, origin level with the
    model base's origin, x the model base's x (else y, world x, world y) projected."""
    z0 = w1 if w1 @ T_wb_model[:3, 2] >= 0 else -w1
    sign1 = float(np.sign(w1 @ z0))
    o0 = p1 + ((T_wb_model[:3, 3] - p1) @ z0) * z0
    x0 = None
    for cand in (T_wb_model[:3, 0], T_wb_model[:3, 1], np.eye(3)[0], np.eye(3)[1]):
        xp = _perp_in(cand, z0)
        if np.linalg.norm(xp) > 1e-6:
            x0 = _unit(xp)
            break
    y0 = np.cross(z0, x0)
    return _BaseFrame(o0, x0, y0, z0, sign1)


def _arm(name: str, w, p, wc, base: _BaseFrame, tol_length: float) -> _Arm:
    """Shoulder (a1, c1, joint 1 offset), upper arm (c2, joint 2 offset) and forearm (a2, b, c3,
    joint 3 offset) from the axes 1-4 and the wrist centre ``wc``."""
    _, w2, w3, w4, _, _ = w
    _, p2, p3, _, _, _ = p
    o0, x0, y0, z0 = base.o, base.x, base.y, base.z
    x1 = _unit(np.cross(w2, z0))
    a1 = float((p2 - o0) @ x1)
    if a1 < 0.0:
        x1, a1 = -x1, -a1
    y1 = np.cross(z0, x1)
    sign2 = float(np.sign(w2 @ y1))
    c1 = float((p2 - o0) @ z0)
    off1 = float(np.arctan2(x1 @ y0, x1 @ x0))

    d23 = p3 - p2
    dx, dz = float(d23 @ x1), float(d23 @ z0)
    c2 = float(np.hypot(dx, dz))
    if c2 <= tol_length:
        raise NotAnalyticError(f"{name}: axes 2 and 3 coincide (distance {c2:.3g} mm)")
    t2_0 = float(np.arctan2(dx, dz))
    sign3 = float(np.sign(w3 @ y1))

    z4 = w4.copy()
    c3 = float((wc - p3) @ z4)
    if c3 < 0.0:
        z4, c3 = -z4, -c3
    sign4 = float(np.sign(w4 @ z4))
    t23_0 = float(np.arctan2(z4 @ x1, z4 @ z0))
    x4 = np.cross(y1, z4)
    a2 = float((wc - p3) @ x4)
    b = float((wc - o0) @ y1)
    if np.hypot(a2, c3) <= tol_length:
        raise NotAnalyticError(f"{name}: axis 3 passes through the wrist centre (distance "
                               f"{np.hypot(a2, c3):.3g} mm)")
    return _Arm(x1, y1, z4, x4, a1, a2, b, c1, c2, c3, off1, t2_0, t23_0, sign2, sign3, sign4)


def _wrist(w, wc, arm: _Arm, T_ee0) -> _Wrist:
    """Joints 4-6 from axes 5 and 6, the wrist centre and the end effector pose ``T_ee0`` (4, 4)
    at ``q = 0``: axis 5 is +y of the frame after Rz(t4); c4 along axis 6 to the end effector."""
    w5, w6 = w[4], w[5]
    x4, y1, z4 = arm.x4, arm.y1, arm.z4
    t4_0 = float(np.arctan2(-(w5 @ x4), w5 @ y1))
    x4p = np.cos(t4_0) * x4 + np.sin(t4_0) * y1
    sign5 = 1.0
    z6 = w6.copy()
    c4 = float((T_ee0[:3, 3] - wc) @ z6)
    if c4 < 0.0:
        z6, c4 = -z6, -c4
    sign6 = float(np.sign(w6 @ z6))
    t5_0 = float(np.arctan2(z6 @ x4p, z6 @ z4))
    x5 = np.cos(t5_0) * x4p - np.sin(t5_0) * z4
    y5 = np.cross(z6, x5)
    xL = None
    for cand in (T_ee0[:3, 0], T_ee0[:3, 1], T_ee0[:3, 2], x5):
        xp = _perp_in(cand, z6)
        if np.linalg.norm(xp) > 1e-6:
            xL = xp
            break
    t6_0 = float(np.arctan2(xL @ y5, xL @ x5))
    return _Wrist(c4, t4_0, t5_0, t6_0, sign5, sign6)


def _assemble(model, name: str, C, base: _BaseFrame, arm: _Arm, wrist: _Wrist, T_ee0,
              tol_length: float) -> OPWParameters:
    """The read-only :class:`OPWParameters`; lengths at rounding-noise level snap to 0, and the
    end effector frame follows from FK of the OPW model at the offsets."""
    # Lengths at rounding-noise level are exactly zero (the verification covers the snap).
    a1, a2, b, c1, c3, c4 = (0.0 if abs(x) <= tol_length else x
                             for x in (arm.a1, arm.a2, arm.b, arm.c1, arm.c3, wrist.c4))
    c2 = arm.c2
    T_world_obase = np.eye(4)
    T_world_obase[:3, :3] = np.stack([base.x, base.y, base.z], axis=1)
    T_world_obase[:3, 3] = base.o
    offsets = wrap(np.array([arm.off1, arm.t2_0, arm.t23_0 - arm.t2_0, wrist.t4_0, wrist.t5_0, wrist.t6_0]))
    signs = np.array([base.sign1, arm.sign2, arm.sign3, arm.sign4, wrist.sign5, wrist.sign6])
    limits = np.asarray(model.limits, dtype=float)
    proto = OPWParameters(a1, a2, b, c1, c2, c3, c4, offsets, signs, T_world_obase, np.eye(4), C, limits, name)
    T_oflange0 = opw_fk(proto, offsets)
    T_flange_ee = invert_transforms(T_world_obase @ T_oflange0) @ T_ee0
    T_flange_ee[3] = (0.0, 0.0, 0.0, 1.0)
    params = OPWParameters(a1, a2, b, c1, c2, c3, c4, offsets, signs, T_world_obase, T_flange_ee, C,
                           np.asarray(model.limits, dtype=float), name)
    for arr in (params.offsets, params.signs, params.T_world_base, params.T_flange_ee, params.coupling,
                params.limits):
        arr.setflags(write=False)
    return params


def _verify(model, params: OPWParameters, name: str, verify_tol: float, n_verify: int) -> None:
    """FK of the model and of the OPW model agree at zero and ``n_verify`` seeded random model
    joints within ``verify_tol`` [mm] and ``verify_tol * 1e-2`` [rad]; else NotAnalyticError."""
    rng = np.random.default_rng(12345)
    qm = np.vstack([np.zeros(6), rng.uniform(-np.pi, np.pi, size=(n_verify, 6))])
    q = qm @ params.coupling_inv.T
    T_model = model.fk(q)
    T_opw = params.fk(q)
    dp = float(np.max(np.linalg.norm(T_model[:, :3, 3] - T_opw[:, :3, 3], axis=-1)))
    dr = float(np.max(_rotation_error(T_model[:, :3, :3], T_opw[:, :3, :3])))
    rot_tol = verify_tol * 1e-2
    if not (dp <= verify_tol and dr <= rot_tol):
        raise NotAnalyticError(
            f"{name}: the OPW model derived from the joint axes does not reproduce the model's FK "
            f"(max position error {dp:.3g} mm, tolerance {verify_tol:.3g}; max rotation error {dr:.3g} rad, "
            f"tolerance {rot_tol:.3g})")


def opw_from_model(model: RobotModel, *, tol_angle: float = 1e-12, tol_length: float = 1e-9,
                   verify_tol: float = 1e-9, n_verify: int = 200) -> OPWParameters:
    """Derive the OPW parameters of ``model`` numerically from its joint axes.

    The joint axes (world lines) are taken from the joint twists at ``q = 0``, so every model kind
    (dh, dh_beta, mdh, urdf, with fixed frames, base and tool) and any invertible 6x6 coupling
    are handled alike. Checks, each against ``tol_angle`` [rad] or ``tol_length`` [mm]:
    axis 1 perpendicular to axis 2, axes 2 and 3 parallel, axis 3 perpendicular to axis 4,
    axes 4-5 and 5-6 perpendicular and intersecting in one point. The result is then verified:
    FK of the model equals FK of the OPW model at ``n_verify`` random joint vectors (and zero)
    within ``verify_tol`` mm in position and ``verify_tol * 1e-2`` rad in rotation.

    Raises :class:`NotAnalyticError` naming each failed condition and its size.
    """
    name = getattr(model, "name", "model")
    C = _check_chain(model, name)
    w, p = _joint_axes(model)
    failures, wc = _opw_class_failures(w, p, tol_angle, tol_length)
    if failures:
        raise NotAnalyticError(f"{name}: not an ortho-parallel arm with spherical wrist (OPW class): "
                               + "; ".join(failures))
    base = _base_frame(w[0], p[0], np.asarray(model.T_world_base, dtype=float))
    arm = _arm(name, w, p, wc, base, tol_length)
    T_ee0 = model.fk(np.zeros((1, 6)))[0]
    wrist = _wrist(w, wc, arm, T_ee0)
    params = _assemble(model, name, C, base, arm, wrist, T_ee0, tol_length)
    _verify(model, params, name, verify_tol, n_verify)
    return params


def _rotation_error(R1, R2):
    """Rotation angle [rad] between rotation stacks, accurate for small angles."""
    D = np.swapaxes(R1, -1, -2) @ R2
    v = np.stack([D[..., 2, 1] - D[..., 1, 2], D[..., 0, 2] - D[..., 2, 0], D[..., 1, 0] - D[..., 0, 1]], -1)
    tr = D[..., 0, 0] + D[..., 1, 1] + D[..., 2, 2]
    return np.arctan2(0.5 * np.linalg.norm(v, axis=-1), 0.5 * (tr - 1.0))
