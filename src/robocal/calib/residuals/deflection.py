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
    per pose, (N,) and (N, 3), for the chain's own poses); g: gravity in the base frame [m/s^2];
    lateral: optional :class:`~robocal.calib.blocks.elastic.LateralCompliance` (bending of the
    joints under the gravity moment about the axes perpendicular to theirs, first order).
    """

    def __init__(self, model, q, compliance, gravity, *, payload=None, g=None, lateral=None):
        self.model, self.compliance, self.gravity, self.lateral = model, compliance, gravity, lateral
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
        self._own = GravityTorques(model, self.q, gravity.body_links, payload=payload, g=g,
                                   lateral=lateral is not None)
        if lateral is not None:
            anc = model._ee_ancestors  # (n_ee, n_links)
            self._carries_ee = anc[:, model.moving[lateral.joints]]  # (n_ee, n_lateral)
        self._own_bases = {}  # the bases of the chain's own poses in the product layout, built on first use

    def _torsion_basis(self, gt) -> np.ndarray:
        """(N, n_c, V): torque of each compliant joint per gravity variable (the block's variable
        order), contiguous: the gravity Jacobian is then one batched product per pose."""
        if gt is self._own and "torsion" in self._own_bases:
            return self._own_bases["torsion"]
        b = gt.basis[:, self.compliance.joints]  # (N, n_c, B, 4)
        out = np.ascontiguousarray(self.gravity.variable_jacobian(b))
        if gt is self._own:
            self._own_bases["torsion"] = out
        return out

    def _lateral_basis(self, gt) -> np.ndarray:
        """(N, 2 n_l, V): bending moment of each lateral axis per gravity variable (variable order)."""
        if gt is self._own and "lateral" in self._own_bases:
            return self._own_bases["lateral"]
        lb = gt.lateral_basis[:, self.lateral.joints]  # (N, n_l, 2, B, 4)
        out = np.ascontiguousarray(self.gravity.variable_jacobian(lb).reshape(len(lb), -1, self.gravity.size))
        if gt is self._own:
            self._own_bases["lateral"] = out
        return out

    @property
    def blocks(self) -> tuple:
        """(compliance, gravity[, lateral]): the parameter blocks the deflection reads."""
        return (self.compliance, self.gravity) + (() if self.lateral is None else (self.lateral,))

    def torques_at(self, q, payload="default", gravity=None) -> GravityTorques:
        """The torque basis at the chain's poses (cached) or at other joints ``q`` (with another
        ``payload`` or ``gravity`` (3,) or (N, 3) [m/s^2] in the base frame, if given)."""
        q = np.asarray(q, dtype=float)
        if gravity is None and (q is self.q or (q.shape == self.q.shape and np.array_equal(q, self.q)
                                                and isinstance(payload, str))):
            return self._own
        if isinstance(payload, str):
            payload = self.payload
            if payload is not None and (np.ndim(payload[1]) or np.ndim(payload[2]) > 1):
                raise ProblemError("payload given per pose: pass the payload of the new poses")
        g = self.g if gravity is None else gravity
        if gravity is None and np.ndim(g) == 2 and len(g) != len(q):
            raise ProblemError("gravity given per pose: pass the gravity of the new poses")
        return GravityTorques(self.model, q, self.gravity.body_links, payload=payload, g=g,
                              lateral=self.lateral is not None)

    def deflections(self, q, c, grav, payload="default", gravity=None):
        """``(dq (N, n_model) [rad | mm], gt, tau_sel (N, n_c))`` for compliance values ``c`` and
        gravity-block value ``grav``."""
        gt = self.torques_at(q, payload, gravity)
        joints = self.compliance.joints
        if gt is self._own:  # the compliant joints' rows only, from the basis the Jacobian reads too
            Tv = self._torsion_basis(gt)  # (N, n_c, V)
            tau_sel = (Tv.reshape(-1, Tv.shape[-1]) @ np.asarray(grav, dtype=float)).reshape(Tv.shape[:2])
            tau_sel += gt.payload[:, joints]
        else:
            tau_sel = gt.torques(self.gravity.theta(grav))[:, joints]
        dq = np.zeros(gt.payload.shape)
        dq[:, joints] = tau_sel * (self.compliance.scale * c)
        return dq, gt, tau_sel

    def jacobians(self, J_joint, gt, tau_sel, c, want_c, want_g) -> dict:
        """Chain Jacobians of the compliance and gravity blocks from ``J_joint`` (N, K, 3, n_c), the
        point derivatives w.r.t. the compliant joints."""
        jac = {}
        s = self.compliance.scale
        if want_c:
            jac[self.compliance] = J_joint * (tau_sel * s)[:, None, None, :]
        if want_g:
            # dp/dtheta = sum_j (dp/dq_j s_j c_j) T[:, j, :]: the compliances on the smaller factor,
            # one batched product per pose with the (cached) basis in the variable order
            N, n_c = J_joint.shape[0], J_joint.shape[-1]
            Js = (J_joint * (s * c)).reshape(N, -1, n_c)  # (N, K * 3, n_c)
            Jt = Js @ self._torsion_basis(gt)  # (N, K * 3, V)
            jac[self.gravity] = Jt.reshape(J_joint.shape[:-1] + (Jt.shape[-1],))
        return jac

    def lateral_deflection(self, pts, jac, R_ee, gt, values, grav, ee_of_target, want, R_base=None):
        """Points (N, K, 3) in the base frame moved by the joints' lateral rotations
        ``dphi_j = 1e-6 sum_a c_ja M_ja e_ja`` about their bearing points ``o_j`` (first order:
        ``dp = sum_j dphi_j x (p - o_j)`` over the joints carrying the point), the Jacobians of the
        blocks moving ``p`` carried along (``(I + [Phi]x) J``), and those of the lateral compliances
        and the gravity parameters added. ``R_base`` (N, 3, 3): optionally rotate the points' Jacobians
        (not the points) by it in the same pass (the station frames' rotations: one 3 x 3 product per
        point and block instead of two). Returns (points, jac, R_ee)."""
        lat = self.lateral
        c_lat = values[lat].reshape(-1, 2)  # (n_l, 2)
        jl = lat.joints
        if gt is self._own:  # the lateral joints' rows only, from the basis the Jacobian reads too
            Lv = self._lateral_basis(gt)  # (N, 2 n_l, V)
            M = (Lv.reshape(-1, Lv.shape[-1]) @ np.asarray(grav, dtype=float)).reshape(len(Lv), -1, 2)
            M += gt.lateral_payload[:, jl]  # (N, n_l, 2) [N m]
        else:
            M = gt.lateral_moments(self.gravity.theta(grav))[:, jl]  # (N, n_l, 2) [N m]
        E = gt.lateral_axes[:, jl]  # (N, n_l, 2, 3)
        o = gt.joint_origin[:, jl]  # (N, n_l, 3) [mm]
        A = self._carries_ee[ee_of_target].T.astype(float)  # (n_l, K)
        phi = np.einsum("nja,njai->nji", 1e-6 * c_lat[None] * M, E)  # (N, n_l, 3) [rad]
        r = pts[:, None, :, :] - o[:, :, None, :]  # (N, n_l, K, 3)
        dp = np.einsum("jk,njki->nki", A, np.cross(phi[:, :, None, :], r))
        Phi = np.einsum("jk,nji->nki", A, phi)  # (N, K, 3) total small rotation of each point
        S = np.zeros(Phi.shape + (3,))
        S[..., 0, 1], S[..., 0, 2] = -Phi[..., 2], Phi[..., 1]
        S[..., 1, 0], S[..., 1, 2] = Phi[..., 2], -Phi[..., 0]
        S[..., 2, 0], S[..., 2, 1] = -Phi[..., 1], Phi[..., 0]
        S[..., 0, 0] = S[..., 1, 1] = S[..., 2, 2] = 1.0  # I + [Phi]x
        R_ee = S @ R_ee
        Q = S if R_base is None else R_base[:, None] @ S
        jac = {b: Q @ Jb for b, Jb in jac.items()}
        if want.get(lat, False) or want.get(self.gravity, False):
            ExR = np.cross(E[:, :, :, None, :], r[:, :, None, :, :])  # (N, n_l, 2, K, 3)
            ExR *= A[None, :, None, :, None]
            Rb4 = None if R_base is None else R_base[:, None]  # (N, 1, 3, 3)
            if want.get(lat, False):
                Jl = 1e-6 * M[:, :, :, None, None] * ExR  # (N, n_l, 2, K, 3)
                Jl = np.moveaxis(Jl.reshape(Jl.shape[0], -1, *Jl.shape[3:]), 1, -1)  # (N, K, 3, 2 n_l)
                jac[lat] = Jl if Rb4 is None else Rb4 @ Jl
            if want.get(self.gravity, False):
                # Jg[n,k,i,b,v] = sum_{j,a} 1e-6 c_ja ExR[n,j,a,k,i] L[n,j,a,b,v] (L = the lateral basis
                # (N, n_l, 2, B, 4)): one batched matrix product per pose, the compliances applied to the
                # smaller factor, the basis (cached for the chain's poses) in the variable order (an einsum
                # over a scaled copy of the basis was ~50 % of an elastic-full evaluation on DLR Justin)
                N_, nj, na, K_, _ = ExR.shape
                ExRc = (ExR * (1e-6 * c_lat)[None, :, :, None, None]).reshape(N_, nj * na, K_ * 3)
                Jg = np.matmul(ExRc.transpose(0, 2, 1), self._lateral_basis(gt))  # (N, K * 3, V)
                Jg = Jg.reshape(N_, K_, 3, -1)
                if Rb4 is not None:
                    Jg = Rb4 @ Jg
                jac[self.gravity] = jac[self.gravity] + Jg if self.gravity in jac else Jg
        return pts + dp, jac, R_ee
