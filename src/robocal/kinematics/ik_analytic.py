"""Closed-form inverse kinematics of 6R arms with an ortho-parallel basis and a spherical wrist.

This is the "OPW" class of Brandstötter, Kubus and Raatz (2014), "An analytical solution of the
inverse kinematics problem of industrial serial manipulators with an ortho-parallel basis and a
spherical wrist": axis 1 is perpendicular to axis 2, axes 2 and 3 are parallel, axis 4 is
perpendicular to axis 3, and axes 4, 5, 6 are mutually perpendicular and meet in one point (the
wrist centre). Most 6-axis industrial arms (KUKA, ABB, FANUC, Kawasaki, Yaskawa, Stäubli...) are of
this class with their *nominal* parameters; a calibrated model (non-zero betas, wrist offsets)
usually is not, and then :func:`opw_from_model` raises :class:`NotAnalyticError`.

The implementation is written from the geometry (not ported from another code base).

Canonical OPW model (our own frames, lengths in mm, angles in rad)
------------------------------------------------------------------
With OPW angles ``theta`` (6,), the pose of the OPW flange in the OPW base frame is::

    T_obase_oflange = Rz(t1) Tr(a1, 0, c1) Ry(t2) Tr(0, 0, c2) Ry(t3) Tr(a2, b, c3)
                      Rz(t4) Ry(t5) Rz(t6) Tr(0, 0, c4)

i.e. at ``theta = 0`` the arm stands upright in the x-z plane: axis 1 is the z axis, axes 2, 3 and 5
are parallel to y, axes 4 and 6 are parallel to z, the wrist centre is at ``(a1 + a2, b, c1 + c2 + c3)``
and the flange ``c4`` above it. ``c2 > 0``, ``c3 >= 0`` and ``c4 >= 0``; ``a1 >= 0`` (the x axis of the
arm plane points from axis 1 towards axis 2).

A robot model is related to this by (``q`` controller joints, ``q_model = coupling @ q``)::

    theta = signs * q_model + offsets
    T_world_ee(q) = T_world_base @ T_obase_oflange(theta) @ T_flange_ee

``T_world_base`` is the OPW base frame in the world: origin on axis 1 level with the model's base
origin, z along axis 1 pointing to the side of the model base's z, x the model base's x projected
onto the plane normal to axis 1. The OPW flange frame has its z along axis 6 (away from the wrist
centre) and its x along the projection of the x axis of the model's end effector frame at
``q_model = 0``. ``c4`` is the distance from the wrist centre along axis 6 to the foot of the end
effector's origin on axis 6 (for a robot file without tool: the flange distance). So for a robot
without tool ``T_flange_ee`` is the identity or a half turn about x; with a tool it holds the tool's
rotation and its offset *across* axis 6, while the tool length along axis 6 is part of ``c4``.

Branches
--------
:func:`ik_analytic` returns 8 solutions per pose, indexed ``4 * shoulder + 2 * elbow + wrist``
(names in :data:`BRANCHES`):

- shoulder ``front`` (0): the wrist centre lies in front of axis 1 (on the side of the shoulder
  offset a1, seen in the arm plane); ``back`` (1): the arm reaches over backwards (J1 turned by
  about half a turn).
- elbow ``up`` (0) / ``down`` (1): the elbow (axis 3) lies above / below the line from axis 2 to the
  wrist centre, with "above" along OPW +z (the model base's z side). For poses whose wrist centre
  lies between axis 1 and axis 2 horizontally the labels are nominal.
- wrist ``noflip`` (0): OPW ``theta5 >= 0``; ``flip`` (1): ``theta5 <= 0`` (theta4, theta6 turned by pi).
  Whether a branch's controller ``q5`` is positive depends on the robot's sign convention.

Wrist singularity (``|sin theta5| < 1e-12``, axes 4 and 6 in line): only ``theta4 + theta6``
(``theta4 - theta6`` at theta5 = pi) is determined. Then the model joint 4 is set to 0 in the ``noflip`` branch (controller ``q4 = 0`` for the usual
diagonal coupling; OPW ``theta4 = offsets[3]``) and to pi in the ``flip`` branch, and joint 6 takes
the rest of the rotation. Both solutions are valid.

Shoulder singularity (``b = 0`` and the wrist centre on axis 1 within 1e-9 mm): joint 1 is free;
the model joint 1 is set to 0 in the ``front`` branches (pi in the ``back`` ones).

Joint values: each controller joint whose coupling column is integer (so that adding 2 pi to it is a
symmetry of the kinematics: every shipped robot) is wrapped to ``[-pi, pi)`` and then, if that is
outside the joint's limits, shifted by a multiple of 2 pi into the limits when one exists (the
in-limit value of smallest magnitude). For joint ranges wider than 2 pi the other representatives
``q +- 2 pi`` are also solutions; they are not enumerated.
"""

from __future__ import annotations

import weakref
from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np

from ..transforms import invert_transforms
from .model import RobotModel

__all__ = [
    "BRANCHES",
    "NotAnalyticError",
    "OPWParameters",
    "opw_from_model",
    "opw_fk",
    "is_analytic",
    "ik_analytic",
]

BRANCHES = tuple(
    (shoulder, elbow, wrist)
    for shoulder in ("front", "back")
    for elbow in ("up", "down")
    for wrist in ("noflip", "flip")
)
"""Names ``(shoulder, elbow, wrist)`` of the 8 solution branches, in the order of :func:`ik_analytic`."""

_TWO_PI = 2.0 * np.pi


class NotAnalyticError(ValueError):
    """The robot model is not exactly of the OPW class; the message says which condition failed."""


@dataclass(frozen=True)
class OPWParameters:
    """OPW parameters of a robot model (see the module docstring for the frames).

    Lengths in mm, angles in rad. ``theta_opw = signs * q_model + offsets`` with
    ``q_model = coupling @ q`` (controller joints ``q``).
    """

    a1: float
    a2: float
    b: float
    c1: float
    c2: float
    c3: float
    c4: float
    offsets: np.ndarray          # (6,) OPW angle at q_model = 0
    signs: np.ndarray            # (6,) +-1
    T_world_base: np.ndarray     # (4, 4) OPW base frame in the world
    T_flange_ee: np.ndarray      # (4, 4) end effector (model's first) in the OPW flange frame
    coupling: np.ndarray         # (6, 6) q_model = coupling @ q
    limits: np.ndarray           # (6, 2) controller joint limits
    name: str = ""
    coupling_inv: np.ndarray = field(init=False, repr=False)
    integer_columns: np.ndarray = field(init=False, repr=False)  # (6,) adding 2 pi to q_j is a symmetry

    def __post_init__(self):
        C = np.asarray(self.coupling, dtype=float)
        object.__setattr__(self, "coupling_inv", np.linalg.inv(C))
        object.__setattr__(self, "integer_columns", np.all(np.abs(C - np.round(C)) < 1e-12, axis=0))

    def opw_angles(self, q) -> np.ndarray:
        """OPW angles (..., 6) from controller joints (..., 6)."""
        qm = np.asarray(q, dtype=float) @ self.coupling.T
        return self.signs * qm + self.offsets

    def controller_joints(self, theta) -> np.ndarray:
        """Controller joints (..., 6) from OPW angles (..., 6) (no wrapping)."""
        qm = (np.asarray(theta, dtype=float) - self.offsets) * self.signs
        return qm @ self.coupling_inv.T

    def fk(self, q) -> np.ndarray:
        """``T_world_ee`` (..., 4, 4) from controller joints (..., 6) through the OPW model."""
        return self.T_world_base @ opw_fk(self, self.opw_angles(q)) @ self.T_flange_ee


def _rz(t):
    c, s = np.cos(t), np.sin(t)
    R = np.zeros(np.shape(t) + (3, 3))
    R[..., 0, 0] = c
    R[..., 0, 1] = -s
    R[..., 1, 0] = s
    R[..., 1, 1] = c
    R[..., 2, 2] = 1.0
    return R


def _ry(t):
    c, s = np.cos(t), np.sin(t)
    R = np.zeros(np.shape(t) + (3, 3))
    R[..., 0, 0] = c
    R[..., 0, 2] = s
    R[..., 2, 0] = -s
    R[..., 2, 2] = c
    R[..., 1, 1] = 1.0
    return R


def opw_fk(params: OPWParameters, theta) -> np.ndarray:
    """Pose of the OPW flange in the OPW base frame, (..., 4, 4), from OPW angles (..., 6)."""
    t = np.asarray(theta, dtype=float)
    P = params
    R1 = _rz(t[..., 0])
    R13 = _ry(t[..., 1] + t[..., 2])
    R03 = R1 @ R13
    # Points in the arm plane frame (after Rz(t1)).
    s2, c2_ = np.sin(t[..., 1]), np.cos(t[..., 1])
    elbow = np.stack([P.a1 + P.c2 * s2, np.zeros_like(s2), P.c1 + P.c2 * c2_], axis=-1)
    wc1 = elbow + (R13 @ np.array([P.a2, P.b, P.c3]))
    R36 = _rz(t[..., 3]) @ _ry(t[..., 4]) @ _rz(t[..., 5])
    R = R03 @ R36
    p = (R1 @ wc1[..., None])[..., 0] + P.c4 * R[..., :, 2]
    T = np.zeros(t.shape[:-1] + (4, 4))
    T[..., :3, :3] = R
    T[..., :3, 3] = p
    T[..., 3, 3] = 1.0
    return T


# ---------------------------------------------------------------------- parameter extraction
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


def _wrap(x):
    return (np.asarray(x) + np.pi) % _TWO_PI - np.pi


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
    offsets = _wrap(np.array([arm.off1, arm.t2_0, arm.t23_0 - arm.t2_0, wrist.t4_0, wrist.t5_0, wrist.t6_0]))
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


_CACHE: "weakref.WeakKeyDictionary[RobotModel, OPWParameters]" = weakref.WeakKeyDictionary()


def _params_of(model) -> OPWParameters:
    if isinstance(model, OPWParameters):
        return model
    try:
        return _CACHE[model]
    except (KeyError, TypeError):
        pass
    params = opw_from_model(model)
    try:
        _CACHE[model] = params
    except TypeError:
        pass
    return params


def is_analytic(model: RobotModel) -> bool:
    """Whether ``model`` is exactly of the OPW class (so :func:`ik_analytic` applies)."""
    try:
        _params_of(model)
    except NotAnalyticError:
        return False
    return True


# ---------------------------------------------------------------------- inverse kinematics
def _shoulder(P: OPWParameters, c):
    """Joint 1 from the wrist centres ``c`` (N, 3) in the OPW base frame: the wrist centre's y in
    the arm plane frame must be b. Returns ``t1`` (N, 2) (shoulder front / back), ``xs`` (N, 2)
    the wrist centre's x in the arm plane [mm], and ``ok1`` (N,) reachable."""
    rho2 = c[:, 0] ** 2 + c[:, 1] ** 2
    r2 = rho2 - P.b ** 2
    ok1 = r2 >= -1e-9 * (P.b ** 2 + 1.0)
    r = np.sqrt(np.maximum(r2, 0.0))
    xs = np.stack([r, -r], axis=1)                             # (N, 2) shoulder front / back
    # Shoulder singularity (b = 0 and the wrist centre on axis 1): joint 1 is free; take model q1 = 0.
    on_axis = (rho2 <= 1e-18) & (abs(P.b) <= 1e-9)
    psi = np.where(on_axis, P.offsets[0], np.arctan2(c[:, 1], c[:, 0]))
    t1 = psi[:, None] - np.arctan2(P.b, xs)
    return t1, xs, ok1


def _elbow(P: OPWParameters, c, xs, ok1):
    """Joints 2 and 3: a planar two-link arm from axis 2 to the wrist centre. Returns ``t2``,
    ``t3`` (N, 2, 2) (shoulder, elbow up / down) and ``ok2`` (N, 2) reachable."""
    k = np.hypot(P.a2, P.c3)
    phi = np.arctan2(P.a2, P.c3)
    u = xs - P.a1
    vz = np.broadcast_to((c[:, 2] - P.c1)[:, None], u.shape)
    D = (u ** 2 + vz ** 2 - P.c2 ** 2 - k ** 2) / (2.0 * P.c2 * k)
    ok2 = ok1[:, None] & (np.abs(D) <= 1.0 + 1e-12)            # (N, 2)
    g = np.arccos(np.clip(D, -1.0, 1.0))
    # gamma = t3 + phi; elbow "up" is gamma > 0 in front, gamma < 0 at the back.
    gamma = np.stack([g, -g], axis=2) * np.array([1.0, -1.0])[None, :, None]   # (N, 2, 2)
    t3 = gamma - phi
    A = P.c2 + k * np.cos(gamma)
    B = k * np.sin(gamma)
    t2 = np.arctan2(u, vz)[:, :, None] - np.arctan2(B, A)
    return t2, t3, ok2


def _wrist_joints(P: OPWParameters, R, t1b, t2, t3):
    """Joints 4-6 from ``R36 = (Rz(t1) Ry(t2 + t3))^T R = Rz(t4) Ry(t5) Rz(t6)``; ``R`` (N, 3, 3)
    the flange rotations, ``t1b, t2, t3`` (N, 2, 2). Returns ``t4, t5, t6`` (N, 2, 2, 2) (wrist
    noflip / flip last); theta6 from the remaining rotation, exact even near the singularity."""
    R03 = _rz(t1b) @ _ry(t2 + t3)                               # (N, 2, 2, 3, 3)
    M = np.swapaxes(R03, -1, -2) @ R[:, None, None]
    s5 = np.hypot(M[..., 0, 2], M[..., 1, 2])
    t5 = np.arctan2(s5, M[..., 2, 2])
    singular = s5 < 1e-12
    t4 = np.where(singular, P.offsets[3], np.arctan2(M[..., 1, 2], M[..., 0, 2]))
    t4 = np.stack([t4, t4 + np.pi], axis=-1)                   # (N, 2, 2, 2) wrist noflip / flip
    t5 = np.stack([t5, -t5], axis=-1)
    Nr = np.swapaxes(_rz(t4) @ _ry(t5), -1, -2) @ M[..., None, :, :]
    t6 = np.arctan2(Nr[..., 1, 0], Nr[..., 0, 0])
    return t4, t5, t6


def _controller_joints(P: OPWParameters, theta, valid, within_limits: bool, limit_tol: float):
    """OPW angles (N, 8, 6) -> controller joints (N, 8, 6) wrapped into the limits; invalid
    branches NaN; with ``within_limits`` solutions outside the limits are marked invalid."""
    qm = _wrap((theta - P.offsets) * P.signs)
    q = qm @ P.coupling_inv.T
    q = _wrap_into_limits(q, P)
    q[~valid] = np.nan
    if within_limits:
        lo, hi = P.limits[:, 0], P.limits[:, 1]
        inside = np.all((q >= lo - limit_tol) & (q <= hi + limit_tol), axis=-1)
        valid &= inside
    return q, valid


def ik_analytic(model, T_world_ee, *, within_limits: bool = False, limit_tol: float = 1e-9):
    """All 8 closed-form IK solutions of an OPW-class robot.

    model: a :class:`RobotModel` (its OPW parameters are derived once and cached) or
        :class:`OPWParameters`.
    T_world_ee: (N, 4, 4) or (4, 4) target poses of the model's (first) end effector [mm].
    within_limits: also mark solutions outside the controller joint limits (``limit_tol`` rad) invalid;
        their joint values are kept (only unreachable branches are NaN).

    Returns ``q`` (N, 8, 6) controller joints [rad] and ``valid`` (N, 8) bool (or (8, 6) and (8,)
    for a single pose). Branch order: :data:`BRANCHES`. Unreachable branches are NaN and invalid.
    Wrist-singular poses and joint wrapping: see the module docstring.
    """
    P = _params_of(model)
    T = np.asarray(T_world_ee, dtype=float)
    single = T.ndim == 2
    if T.shape[-2:] != (4, 4) or T.ndim not in (2, 3):
        raise ValueError(f"T_world_ee must have shape (N, 4, 4) or (4, 4), got {T.shape}")
    T = T.reshape(-1, 4, 4)
    N = len(T)
    Tb = invert_transforms(P.T_world_base) @ T @ invert_transforms(P.T_flange_ee)
    R = Tb[:, :3, :3]
    c = Tb[:, :3, 3] - P.c4 * R[:, :, 2]                      # wrist centre (N, 3)
    t1, xs, ok1 = _shoulder(P, c)
    t2, t3, ok2 = _elbow(P, c, xs, ok1)
    t1b = np.broadcast_to(t1[:, :, None], t2.shape)
    t4, t5, t6 = _wrist_joints(P, R, t1b, t2, t3)

    def b8(x):
        return np.broadcast_to(x[..., None] if x.ndim == 3 else x, (N, 2, 2, 2)).reshape(N, 8)

    theta = np.stack([b8(t1b), b8(t2), b8(t3), t4.reshape(N, 8), t5.reshape(N, 8), t6.reshape(N, 8)], axis=-1)
    valid = np.broadcast_to(ok2[:, :, None, None], (N, 2, 2, 2)).reshape(N, 8).copy()
    q, valid = _controller_joints(P, theta, valid, within_limits, limit_tol)
    if single:
        return q[0], valid[0]
    return q, valid


def _wrap_into_limits(q, P: OPWParameters):
    """Wrap controller joints with integer coupling columns to [-pi, pi), then into the limits."""
    out = q.copy()
    ks = np.arange(-3, 4) * _TWO_PI
    for j in np.flatnonzero(P.integer_columns):
        base = _wrap(q[..., j])
        cand = base[..., None] + ks                              # (..., 7)
        lo, hi = P.limits[j]
        inside = (cand >= lo) & (cand <= hi)
        score = np.where(inside, np.abs(cand), np.inf)
        best = np.take_along_axis(cand, np.argmin(score, axis=-1)[..., None], axis=-1)[..., 0]
        out[..., j] = np.where(np.any(inside, axis=-1), best, base)
    return out
