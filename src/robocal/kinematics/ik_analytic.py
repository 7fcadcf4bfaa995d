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

import numpy as np

from ..transforms import invert_transforms, rot_y, rot_z
from ._opw_extract import opw_from_model
from ._opw_model import TWO_PI, NotAnalyticError, OPWParameters, opw_fk, wrap
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
    R03 = rot_z(t1b) @ rot_y(t2 + t3)                           # (N, 2, 2, 3, 3)
    M = np.swapaxes(R03, -1, -2) @ R[:, None, None]
    s5 = np.hypot(M[..., 0, 2], M[..., 1, 2])
    t5 = np.arctan2(s5, M[..., 2, 2])
    singular = s5 < 1e-12
    t4 = np.where(singular, P.offsets[3], np.arctan2(M[..., 1, 2], M[..., 0, 2]))
    t4 = np.stack([t4, t4 + np.pi], axis=-1)                   # (N, 2, 2, 2) wrist noflip / flip
    t5 = np.stack([t5, -t5], axis=-1)
    Nr = np.swapaxes(rot_z(t4) @ rot_y(t5), -1, -2) @ M[..., None, :, :]
    t6 = np.arctan2(Nr[..., 1, 0], Nr[..., 0, 0])
    return t4, t5, t6


def _controller_joints(P: OPWParameters, theta, valid, within_limits: bool, limit_tol: float):
    """OPW angles (N, 8, 6) -> controller joints (N, 8, 6) wrapped into the limits; invalid
    branches NaN; with ``within_limits`` solutions outside the limits are marked invalid."""
    qm = wrap((theta - P.offsets) * P.signs)
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
    ks = np.arange(-3, 4) * TWO_PI
    for j in np.flatnonzero(P.integer_columns):
        base = wrap(q[..., j])
        cand = base[..., None] + ks                              # (..., 7)
        lo, hi = P.limits[j]
        inside = (cand >= lo) & (cand <= hi)
        score = np.where(inside, np.abs(cand), np.inf)
        best = np.take_along_axis(cand, np.argmin(score, axis=-1)[..., None], axis=-1)[..., 0]
        out[..., j] = np.where(np.any(inside, axis=-1), best, base)
    return out
