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
from ..calib.gravity import STANDARD_GRAVITY, GravityTorques

__all__ = ["ElasticTruth", "deflected_model_joints"]


@dataclass(frozen=True)
class ElasticTruth:
    """compliance: {model joint name: c [mrad/kNm | mm/kN]}; masses: {link name: (mass kg, com (3,) mm
    in the link frame)}; payload: None or (end effector, mass kg, com (3,) mm); g: gravity in the
    base frame [m/s^2]; hardening: relative stiffening at ``tau_ref`` [N m] (0 = linear);
    equilibrium_iterations: fixed-point iterations of the deflected torque (0 = commanded pose)."""

    compliance: dict
    masses: dict
    payload: tuple | None = None
    g: tuple = tuple(STANDARD_GRAVITY)
    hardening: float = 0.03
    tau_ref: float = 1000.0
    equilibrium_iterations: int = 2


def deflected_model_joints(model, q, truth: ElasticTruth, payload="default") -> np.ndarray:
    """Model joints (N, n_model) the robot really reaches at controller joints ``q`` (N, n_ctrl)."""
    names = [L.name for L in model.links]
    moving = [model.links[int(k)].name for k in model.moving]
    body_links = np.array([names.index(n) for n in truth.masses], dtype=int)
    theta = np.array([[m, *(np.asarray(c, dtype=float) * m / 1000.0)] for m, c in truth.masses.values()])
    c = np.zeros(len(moving))
    scale = np.array([COMPLIANCE_UNITS[model.links[int(k)].joint_type == "revolute"][1] for k in model.moving])
    for n, v in truth.compliance.items():
        c[moving.index(n)] = v
    payload = truth.payload if payload == "default" else payload
    m_joints = model.replace(controller_joints=tuple(moving), coupling=np.eye(len(moving)),
                             limits=np.tile([-np.inf, np.inf], (len(moving), 1)))
    qm = np.atleast_2d(np.asarray(q, dtype=float)) @ model.coupling.T
    q_eff = qm
    for _ in range(int(truth.equilibrium_iterations) + 1):
        tau = GravityTorques(m_joints, q_eff, body_links, payload=payload, g=np.asarray(truth.g)).torques(theta)
        dq = scale * c * tau * (1.0 - truth.hardening * np.abs(tau) / truth.tau_ref)
        q_eff = qm + dq
    return q_eff
