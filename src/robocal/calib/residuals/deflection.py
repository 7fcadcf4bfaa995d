"""Gravity-induced joint deflection for the shared robot chain (docs/elastic.md).

``q_model_eff = coupling q + D dtheta``, ``dtheta_j = s_j c_j tau_j(q)`` with
``tau = GravityTorques(q).torques(theta)`` (:mod:`robocal.calib.gravity`): the deflected joints
enter forward kinematics *before* any measurement model, so every residual reading the
:class:`~robocal.calib.residuals.TargetChain` (points, several reflectors, distances, planes, the
6-D tool point) sees them. Derivatives:

* w.r.t. compliance: ``dp/dc_j = (dp/dq_j) s_j tau_j``;
* w.r.t. the lumped gravity parameters: ``dp/dtheta_b = sum_j (dp/dq_j) s_j c_j T[:, j, b]``;
* ``dp/dq_j`` is the identification Jacobian column of joint j's motion parameter (its offset),
  from the same kernel call as the geometry columns.

Torques are computed at the commanded joints on the chain model's own (nominal) geometry and
treated as data (a second-order approximation: a geometry change of a few mm changes a torque by
~1e-3 relative).
"""

from __future__ import annotations

import numpy as np

from ..errors import ProblemError
from ..gravity import GravityTorques

__all__ = ["Deflection"]


class Deflection:
    """The joint-deflection part of a chain.

    model: the robot model (nominal geometry for the torques); q (N, n_ctrl); compliance: a
    :class:`~robocal.calib.blocks.JointCompliance`; gravity: a
    :class:`~robocal.calib.blocks.GravityParameters` (fixed for a mass model, free for lumped
    parameters); payload: None or ``(end_effector, mass [kg], com (3,) [mm])`` (mass and com may be
    per pose, (N,) and (N, 3), for the chain's own poses); g: gravity in the base frame [m/s^2].
    """

    def __init__(self, model, q, compliance, gravity, *, payload=None, g=None):
        self.model, self.compliance, self.gravity = model, compliance, gravity
        self.payload, self.g = payload, g
        self.q = np.asarray(q, dtype=float)
        n_m = len(model.moving)
        if np.any(compliance.joints >= n_m) or np.any(compliance.joints < 0):
            raise ProblemError(f"compliance: joint index out of range 0..{n_m - 1}")
        self.motion_param = np.array([int(model._op_param[np.flatnonzero(model._op_joint == j)[0]])
                                      for j in compliance.joints], dtype=np.int64)
        names = tuple(model.links[int(k)].name for k in model.moving)
        self.model_joints = model.replace(controller_joints=names, coupling=np.eye(n_m),
                                          limits=np.tile([-np.inf, np.inf], (n_m, 1)))
        self._own = GravityTorques(model, self.q, gravity.body_links, payload=payload, g=g)

    @property
    def blocks(self) -> tuple:
        return (self.compliance, self.gravity)

    def torques_at(self, q, payload="default") -> GravityTorques:
        """The torque basis at the chain's poses (cached) or at other joints ``q``."""
        q = np.asarray(q, dtype=float)
        if q is self.q or (q.shape == self.q.shape and np.array_equal(q, self.q) and payload == "default"):
            return self._own
        if payload == "default":
            payload = self.payload
            if payload is not None and (np.ndim(payload[1]) or np.ndim(payload[2]) > 1):
                raise ProblemError("payload given per pose: pass the payload of the new poses")
        return GravityTorques(self.model, q, self.gravity.body_links, payload=payload, g=self.g)

    def deflections(self, q, c, grav, payload="default"):
        """``(dq (N, n_model) [rad | mm], gt, tau_sel (N, n_c))`` for compliance values ``c`` and
        gravity-block value ``grav``."""
        gt = self.torques_at(q, payload)
        tau = gt.torques(self.gravity.theta(grav))
        tau_sel = tau[:, self.compliance.joints]
        dq = np.zeros(tau.shape)
        dq[:, self.compliance.joints] = tau_sel * (self.compliance.scale * c)
        return dq, gt, tau_sel

    def jacobians(self, J_joint, gt, tau_sel, c, want_c, want_g) -> dict:
        """Chain Jacobians of the compliance and gravity blocks from ``J_joint`` (N, K, 3, n_c), the
        point derivatives w.r.t. the compliant joints."""
        jac = {}
        s = self.compliance.scale
        if want_c:
            jac[self.compliance] = J_joint * (tau_sel * s)[:, None, None, :]
        if want_g:
            D = gt.basis[:, self.compliance.joints] * (s * c)[None, :, None, None]  # (N, n_c, B, 4)
            N, n_c = D.shape[:2]
            Jt = J_joint @ D.reshape(N, 1, n_c, -1)  # (N, K, 3, B * 4)
            jac[self.gravity] = self.gravity.variable_jacobian(Jt.reshape(Jt.shape[:3] + D.shape[2:]))
        return jac
