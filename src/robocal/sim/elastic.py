"""An elastic virtual robot: the true robot deflects under gravity and payload.

:class:`ElasticTruth` holds the hidden compliances and the true mass model;
:func:`deflected_model_joints` gives the joints the robot really reaches. The truth contains
effects the identified model (:mod:`robocal.calib.residuals.deflection`) does not have:

* the torques are taken at the **deflected** configuration (equilibrium by fixed-point iteration),
  where the model evaluates them at the commanded joints;
* a **hardening** term: ``dtheta = s c tau (1 - hardening |tau| / tau_ref)`` (the model is linear).

Used by :class:`~robocal.sim.robot.VirtualRobot` (``elastic=``): ``reach`` and ``true_poses``
then run the true model at the deflected joints. Lengths mm, angles rad, compliances mrad/kNm.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..calib.blocks.elastic import COMPLIANCE_UNITS
from ..calib.elastic import bodies_from_masses, joint_torques
from ..calib.gravity import STANDARD_GRAVITY

__all__ = ["ElasticTruth", "deflected_model_joints", "lateral_bending"]


@dataclass(frozen=True)
class ElasticTruth:
    """compliance: {model joint name: c [mrad/kNm | mm/kN]}; masses: {link name: (mass kg, com (3,) mm
    in the link frame)}; payload: None or (end effector, mass kg, com (3,) mm); g: gravity in the
    base frame [m/s^2]; hardening: relative stiffening at ``tau_ref`` [N m] (0 = linear);
    equilibrium_iterations: fixed-point iterations of the deflected torque (0 = commanded pose);
    lateral: optional lateral (bending) compliances, applied as exact rotations about each joint's
    bearing, distal joints first (the model superposes them to first order)."""

    compliance: dict
    masses: dict
    payload: tuple | None = None
    g: tuple = tuple(STANDARD_GRAVITY)
    hardening: float = 0.03
    tau_ref: float = 1000.0
    equilibrium_iterations: int = 2
    lateral: dict | None = None  # {joint: (c1, c2)} [mrad/kNm]: bending about the axes e1, e2


def deflected_model_joints(model, q, truth: ElasticTruth, payload="default") -> np.ndarray:
    """Model joints (N, n_model) the robot really reaches at controller joints ``q`` (N, n_ctrl)."""
    moving = [model.links[int(k)].name for k in model.moving]
    bodies = bodies_from_masses(truth.masses)
    c = np.array([float(truth.compliance.get(n, 0.0)) for n in moving])
    scale = np.array([COMPLIANCE_UNITS[model.links[int(k)].joint_type == "revolute"][1] for k in model.moving])
    payload = truth.payload if payload == "default" else payload
    qm = np.atleast_2d(np.asarray(q, dtype=float)) @ model.coupling.T
    q_eff = qm
    for _ in range(int(truth.equilibrium_iterations) + 1):
        tau = joint_torques(model, q_eff, bodies, payload=payload, g=np.asarray(truth.g))
        q_eff = qm + scale * c * tau * (1.0 - truth.hardening * np.abs(tau) / truth.tau_ref)
    return q_eff


def lateral_bending(model, q_model, truth: ElasticTruth, end_effector, T, payload="default") -> np.ndarray:
    """Poses ``T`` (N, 4, 4) in the base frame of ``end_effector`` at the deflected model joints
    ``q_model`` (N, n_model), bent by the lateral compliances: each joint carrying it turns the
    part beyond it by ``phi_j`` about its bearing point (exact rotations, distal joints first)."""
    from ..calib.elastic import _joints_model
    from ..calib.gravity import GravityTorques
    from ..transforms import so3_exp

    if not truth.lateral:
        return T
    bodies = bodies_from_masses(truth.masses)
    names = [L.name for L in model.links]
    moving = [model.links[int(k)].name for k in model.moving]
    links = np.array([names.index(n) for n in bodies], dtype=int)
    theta = np.array(list(bodies.values()), dtype=float).reshape(-1, 4)
    payload = truth.payload if payload == "default" else payload
    gt = GravityTorques(_joints_model(model), q_model, links, payload=payload, g=np.asarray(truth.g), lateral=True)
    M = gt.lateral_moments(theta)
    ee = model.end_effector_index(end_effector)
    out = np.array(T, dtype=float, copy=True)
    for j in reversed(range(len(moving))):
        c = truth.lateral.get(moving[j])
        if c is None or not model._ee_ancestors[ee][model.moving[j]]:
            continue
        phi = np.einsum("na,nai->ni", 1e-6 * np.asarray(c, dtype=float)[None] * M[:, j], gt.lateral_axes[:, j])
        R = so3_exp(phi)
        o = gt.joint_origin[:, j]
        out[:, :3, 3] = np.einsum("nij,nj->ni", R, out[:, :3, 3] - o) + o
        out[:, :3, :3] = R @ out[:, :3, :3]
    return out
