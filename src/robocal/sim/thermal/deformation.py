"""Deformations of the realistic thermal cell that are not parameter changes: bent links, a base
and a sensor stand that move with the hall (see :mod:`robocal.sim.thermal.effects`).

Small motions are twists ``(omega, v)`` (rows 0-2 rotation [rad], 3-5 translation [mm]) acting on
points as ``dx = omega x x + v`` in the frame they are written in.

**Link bending** (:class:`LinkGeometry`, :func:`link_twists`): the arm's skeleton is the
polyline base origin -> every link frame's origin -> flange origin (the origins lie on the joint
axes in the DH and modified-DH conventions); each segment belongs to the link that carries both
its ends (found numerically; a segment fixed to the base is skipped). Link k's segment runs
from ``r_0`` to ``r_1`` (frame k), length L, direction e. Its temperature rise runs linearly
from ``T_p`` (the heat source of joint k) to ``T_d`` (joint k+1); the section's motor side is
warmer by ``g T(s)``, so the link curves about its bending axis ``b`` (perpendicular to e) at
``kappa(s) = alpha g T(s) / D``. Integrated (``dtheta/ds = kappa``, ``dy/ds = theta``) the
distal end turns by ``phi = alpha g L (T_p + T_d) / (2 D)`` about b and is deflected by
``w = alpha g L^2 (T_p / 3 + T_d / 6) / D`` along ``b x e``; the twist of everything beyond it,
in frame k, is ``omega = phi b``, ``v = w (b x e) - omega x r_1``.

This bending is a body-fixed change of each link, so it only moves the joint axes against each
other -- what the kinematic parameters describe; with the 24 free DH + beta parameters of the
KR150 almost all of it is in their span (measured in tests/test_thermal_realism.py). What is not:

**Gravity sag that changes with temperature** (:func:`sag_offsets`): each joint deflects under
the gravity torque of the arm beyond it, ``dq_j = c_j tau_j(q)``; calibrated cold, this sag is in
the robot's model, but a warm gearbox is softer (compliance up by ``sag_change_per_K`` per kelvin
of its motor's rise), and the change ``sag_j rate h_j tau_j(q) / tau_ref_j`` depends on the pose
-- no constant parameter can follow it. ``tau_j`` (:func:`gravity_torques`) comes from point
masses at the skeleton segments' midpoints (mass proportional to length) and a payload at the
flange; ``tau_ref_j`` is its bound with every lever at full length.

:func:`apply_link_twists` moves flange poses by the small motions of all links, each carried to
the world by its link frame at the pose (exact composition).
:func:`small_transform` builds the base and sensor-stand motions.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...kinematics.model import RobotModel
from ...transforms import invert_transforms, so3_exp
from ..robot import as_rng

#: point masses of the sag model: arm mass per mm of skeleton (~700 kg over 3.4 m for a KR150) and
#: what the flange carries while measuring (sphere, sensor) [kg]
KG_PER_MM = 0.2
PAYLOAD_KG = 10.0

__all__ = ["LinkGeometry", "link_geometry", "link_twists", "apply_link_twists", "small_transform", "gravity_torques",
           "sag_offsets"]


@dataclass(frozen=True)
class LinkGeometry:
    """The bending segments: link (B,): index of the owning moving link; start, end (B, 3): the
    segment's ends in that link's frame [mm]; axes (B, 3): bending axes (unit, perpendicular to
    the segment, link frame); source (B, 2): heat-source indices of the proximal and distal
    joint (-1: none); tau_ref (n_joints,): the gravity-torque bound of :func:`gravity_torques`
    [N m] (set by :func:`link_geometry`)."""

    link: np.ndarray
    start: np.ndarray
    end: np.ndarray
    axes: np.ndarray
    source: np.ndarray
    tau_ref: np.ndarray | None = None


def _skeleton(model: RobotModel, q) -> tuple:
    """Link frames (n, 4, 4) and skeleton points (n + 2, 3), base frame, at joints ``q`` (n_joints,)."""
    Tbw = invert_transforms(model.T_world_base)
    F = Tbw @ model.link_frames(q)
    # a batch of one: the batched FK kernel (the single-pose one would be compiled for these two calls)
    pts = np.concatenate([[np.zeros(3)], F[:, :3, 3], [(Tbw @ model.fk(np.asarray(q, dtype=float)[None])[0])[:3, 3]]])
    return F, pts


def link_geometry(model: RobotModel, rng, n_sources: int) -> LinkGeometry:
    """The bending segments of a serial ``model`` (module docstring) with a bending axis each,
    uniform in angle about the segment (``rng``: seed or Generator); heat source j belongs to
    controller joint j + 1."""
    rng = as_rng(rng)
    q0 = model.limits.mean(axis=1)
    q1 = q0 + 0.3 * (model.limits[:, 1] - model.limits[:, 0]) * np.array([0.37, -0.29, 0.23, -0.41, 0.31, -0.19,
                                                                         0.27, -0.33][:len(q0)])
    (F0, P0), (F1, P1) = _skeleton(model, q0), _skeleton(model, q1)
    inv0, inv1 = invert_transforms(F0), invert_transforms(F1)
    rows = []
    for j in range(len(P0) - 1):
        if np.linalg.norm(P0[j + 1] - P0[j]) < 1e-6:
            continue
        for k in range(len(F0) - 1, -1, -1):                             # the last link carrying both ends
            a0 = inv0[k, :3, :3] @ P0[j:j + 2].T + inv0[k, :3, 3:]
            a1 = inv1[k, :3, :3] @ P1[j:j + 2].T + inv1[k, :3, 3:]
            if np.allclose(a0, a1, atol=1e-6):
                rows.append((k, a0[:, 0], a0[:, 1]))
                break
    link = np.array([r[0] for r in rows], dtype=np.int64)
    start, end = np.array([r[1] for r in rows]), np.array([r[2] for r in rows])
    axes = np.zeros_like(start)
    for i, (a, b) in enumerate(zip(start, end)):
        e = (b - a) / np.linalg.norm(b - a)
        p = np.cross(e, [1.0, 0.0, 0.0] if abs(e[0]) < 0.9 else [0.0, 1.0, 0.0])
        p /= np.linalg.norm(p)
        g = rng.uniform(0.0, 2.0 * np.pi)
        axes[i] = np.cos(g) * p + np.sin(g) * np.cross(e, p)
    src = np.array([[k if k < n_sources else -1, k + 1 if k + 1 < n_sources else -1] for k in link],
                   dtype=np.int64).reshape(-1, 2)
    geom = LinkGeometry(link, start, end, axes, src)
    _, ref = _torques(model, q0[None], geom, KG_PER_MM, PAYLOAD_KG)
    return LinkGeometry(link, start, end, axes, src, np.maximum(ref[0], 1e-9))


def link_twists(geom: LinkGeometry, temperatures, deformation, n_links: int) -> np.ndarray:
    """Twists (C, n_links, 6) of every moving link in its own frame for source temperatures
    (C, S) [K] and a :class:`~robocal.sim.thermal.effects.LinkDeformation` (module docstring)."""
    T = np.asarray(temperatures, float)
    pad = np.concatenate([T, np.zeros((len(T), 1))], axis=1)            # index -1 -> 0 K
    Tp, Td = pad[:, geom.source[:, 0]], pad[:, geom.source[:, 1]]        # (C, B)
    d = geom.end - geom.start
    L = np.linalg.norm(d, axis=1)
    e = d / L[:, None]
    c = deformation.expansion_per_K * deformation.gradient_share / deformation.section_depth_mm
    phi = c * L * (Tp + Td) / 2.0
    w = c * L ** 2 * (Tp / 3.0 + Td / 6.0)
    omega = phi[..., None] * geom.axes                                   # (C, B, 3)
    v = w[..., None] * np.cross(geom.axes, e) - np.cross(omega, geom.end)
    out = np.zeros((len(T), n_links, 6))
    np.add.at(out, (slice(None), geom.link), np.concatenate([omega, v], axis=-1))
    return out


def apply_link_twists(model: RobotModel, q, T_base_flange, twists) -> np.ndarray:
    """Flange poses (N, 4, 4) [mm, base frame] of the chain with link k followed by the small
    motion ``E_k = (exp(omega_k), v_k)`` (twists (n, 6) or (N, n, 6), link frames) at the actual
    joints ``q`` (N, n_joints) of ``model``: exactly ``prod_k (F_k E_k F_k^-1) T`` with the
    undeformed link frames ``F_k`` (the product telescopes into the deformed chain)."""
    F = invert_transforms(model.T_world_base) @ model.link_frames(np.atleast_2d(q))   # (N, n, 4, 4)
    tw = np.broadcast_to(twists, (len(F),) + np.shape(twists)[-2:])
    R, p = F[..., :3, :3], F[..., :3, 3]
    Rw = so3_exp(np.einsum("nkij,nkj->nki", R, tw[..., :3]))                # (N, n, 3, 3)
    tw_ = np.einsum("nkij,nkj->nki", R, tw[..., 3:]) + p - np.einsum("nkij,nkj->nki", Rw, p)
    out = np.array(T_base_flange, float, copy=True)
    for k in range(F.shape[1] - 1, -1, -1):                                 # M_1 (M_2 (... (M_n T)))
        if not np.any(tw[:, k]):
            continue
        out[:, :3, 3] = np.einsum("nij,nj->ni", Rw[:, k], out[:, :3, 3]) + tw_[:, k]
        out[:, :3, :3] = Rw[:, k] @ out[:, :3, :3]
    return out


def small_transform(rotvec, shift_mm, about_mm=(0.0, 0.0, 0.0)) -> np.ndarray:
    """(4, 4) rigid motion: rotation ``rotvec`` [rad] about the point ``about_mm``, then a shift
    ``shift_mm`` [mm]."""
    R = so3_exp(np.asarray(rotvec, float))
    c = np.asarray(about_mm, float)
    T = np.eye(4)
    T[:3, :3] = R
    T[:3, 3] = c - R @ c + np.asarray(shift_mm, float)
    return T


def _torques(model: RobotModel, q, geom: LinkGeometry, kg_per_mm: float, payload_kg: float) -> tuple:
    """Gravity torques (N, n) [N m] about the controller joints at ``q`` (N, n) (model-joint
    torques through the coupling) and their bound (N, n): every point mass's weight times its
    distance from the joint axis."""
    Tbw = invert_transforms(model.T_world_base)
    F = Tbw @ model.link_frames(q)                                          # (N, n, 4, 4)
    mid = 0.5 * (geom.start + geom.end)                                     # (B, 3) link frames
    Fl = F[:, geom.link]                                                    # (N, B, 4, 4)
    c = np.einsum("nbij,bj->nbi", Fl[:, :, :3, :3], mid) + Fl[:, :, :3, 3]
    c = np.concatenate([c, (Tbw @ model.fk(q))[:, None, :3, 3]], axis=1)   # (N, B + 1, 3) + flange
    owner = np.concatenate([geom.link, [len(model.links) - 1]])
    mass = np.concatenate([kg_per_mm * np.linalg.norm(geom.end - geom.start, axis=1), [payload_kg]])
    force = mass[:, None] * np.array([0.0, 0.0, -9.81])                    # (B + 1, 3) [N]
    _, jt, _ = model.twists(q)                                              # (N, 6, n) world
    om = np.einsum("ij,njk->nik", Tbw[:3, :3], jt[:, :3])
    v = np.einsum("ij,njk->nik", Tbw[:3, :3], jt[:, 3:]) + np.cross(Tbw[:3, 3], om, axisa=0, axisb=1, axisc=1)
    on_axis = np.cross(om, v, axisa=1, axisb=1, axisc=1)                    # (N, 3, n): closest axis points
    moment = np.cross(c, force[None])                                       # (N, B + 1, 3) [N mm]
    tau = np.einsum("nbi,nij->nbj", moment, om) + np.einsum("bi,nij->nbj", force, v)
    lever = np.linalg.norm(c[:, :, :, None] - on_axis[:, None], axis=2)    # (N, B + 1, n)
    carried = (owner[:, None] >= np.arange(om.shape[2])[None])[None]        # mass beyond joint j
    bound = np.sum(carried * lever * (9.81 * mass)[None, :, None], axis=1)
    C = np.abs(model.coupling)                                              # model -> controller joints
    return np.sum(tau * carried, axis=1) @ model.coupling / 1000.0, bound @ C / 1000.0


def gravity_torques(model: RobotModel, q, geom: LinkGeometry) -> tuple:
    """``(tau (N, n_joints), tau_ref (n_joints,))`` [N m]: gravity torque about every joint axis at
    joints ``q`` (N, n_joints) from point masses :data:`KG_PER_MM` times each segment's length at
    its midpoint and :data:`PAYLOAD_KG` at the flange; ``tau_ref``: its bound (every weight at its
    full distance from the axis) at the middle of the joint ranges, the same for any ``q``."""
    tau, _ = _torques(model, np.atleast_2d(q), geom, KG_PER_MM, PAYLOAD_KG)
    return tau, geom.tau_ref


def sag_offsets(model: RobotModel, q, geom: LinkGeometry, temperatures, deformation) -> np.ndarray:
    """Joint offsets (N, n_joints) [rad] from the warm change of the gravity sag (module
    docstring) at joints ``q`` (N, n_joints) for source temperatures (S,) or one row per pose
    (N, S) [K]."""
    tau, ref = gravity_torques(model, q, geom)
    n = tau.shape[1]
    T = np.atleast_2d(np.asarray(temperatures, float))
    h = np.zeros((len(T), n))
    h[:, :min(n, T.shape[1])] = T[:, :n]
    sag = np.zeros(n)
    sag[:len(deformation.sag_rad)] = deformation.sag_rad[:n]
    return tau / ref * (sag * deformation.sag_change_per_K * h)
