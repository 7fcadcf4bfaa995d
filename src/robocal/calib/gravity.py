"""Gravity torques of a robot at given joint configurations, linear in its lumped mass parameters.

A rigid body ``b`` carried by link ``L_b`` has mass ``m_b`` [kg] and first moment
``h_b = m_b c_b`` [kg m] (``c_b`` its centre of mass in the link frame). Its weight ``m_b g`` acts
at ``p_b = o_b + R_b c_b`` (``o_b, R_b`` the link frame in the robot base frame). The generalised
gravity force on model joint ``j`` (unit twist ``(w_j, v_j)`` in the base frame, rows omega, v) is
the virtual power of every weight the joint carries:

    tau_j = sum_b A_jb [ m_b (w_j . (o_b x g) + v_j . g) + (R_b^T (g x w_j)) . h_b ]

(``A_jb`` = 1 when joint j moves body b). tau is **linear** in ``theta_b = (m_b, h_b)``:
``tau = sum_b T[:, :, b] theta_b + tau_payload``; :class:`GravityTorques` precomputes the basis
``T`` (N, n_joints, n_bodies, 4) once, at the commanded joints and a fixed (nominal) geometry: the
torques change with the identified geometry only at second order (mm in metres), so the
deflection model treats them as data. Units: revolute joints N m, prismatic joints N; ``g`` in the
base frame [m/s^2] (default (0, 0, -9.80665): base z up).

A payload is a body on an end effector: mass [kg] and centre of mass [mm] in that end
effector's frame, per pose (it may change between poses: that is what makes the absolute scale
of compliances identifiable without a mass model, see :mod:`robocal.calib.blocks.elastic`).
"""

from __future__ import annotations

import numpy as np

from .errors import ProblemError

__all__ = ["GravityTorques", "STANDARD_GRAVITY"]

STANDARD_GRAVITY = np.array([0.0, 0.0, -9.80665])


class GravityTorques:
    """The gravity-torque basis of ``model`` at joints ``q``.

    model: :class:`~robocal.kinematics.model.RobotModel` (geometry: its current parameter values;
    its base frame is ignored: everything is in the robot base frame); q (N, n_ctrl) controller
    joints; body_links (B,) link index carrying each body; payload: None or
    ``(end_effector, mass (N,) or scalar [kg], com (N, 3) or (3,) [mm] in the end-effector frame)``;
    g: (3,) or (N, 3) gravity in the base frame [m/s^2].

    Attributes: ``basis`` (N, n_model, B, 4) [N m per kg | per kg m], ``payload`` (N, n_model)
    [N m | N], ``revolute`` (n_model,) bool.

    With ``lateral``: the gravity moment about the two axes perpendicular to each joint axis (the
    bending moments), at the joint's bearing point ``o_j`` (the foot of the link frame's origin on
    the axis; a prismatic joint: the link frame's origin, its axis the direction of travel), the
    perpendicular axes ``e1`` (the first of the link frame's x, y, z axes at more than ~45 deg from
    the joint axis, made perpendicular: x for DH, modified DH and URDF frames) and ``e2 = a x e1``: ``lateral_basis`` (N, n_model, 2, B, 4) [N m per kg | per kg m],
    ``lateral_payload`` (N, n_model, 2), ``joint_origin`` (N, n_model, 3) [mm], ``lateral_axes``
    (N, n_model, 2, 3) -- all in the base frame.
    """

    def __init__(self, model, q, body_links, *, payload=None, g=None, lateral: bool = False):
        m0 = model.replace(T_world_base=np.eye(4))
        q = np.asarray(q, dtype=float)
        N = len(q)
        g = STANDARD_GRAVITY if g is None else np.asarray(g, dtype=float)
        g = np.broadcast_to(g, (N, 3))
        _, jtw, frames = m0.twists(q)  # jtw (N, 6, n_model); frames (N, n_links, 3, 4) in the base frame
        w, v = jtw[:, :3, :], jtw[:, 3:, :]  # (N, 3, n_model)
        self.revolute = np.array([model.links[k].joint_type == "revolute" for k in model.moving])
        body_links = np.asarray(body_links, dtype=int)
        carries = self._carries(model, body_links)  # (n_model, B)
        F = frames[:, body_links]  # (N, B, 3, 4)
        o, R = F[..., 3], F[..., :3]  # (N, B, 3) [mm], (N, B, 3, 3)
        # mass term: w_j . (o_b x g) / 1000 + v_j . g (/1000 for revolute: mm -> m)
        o_x_g = np.cross(o, g[:, None, :])  # (N, B, 3)
        lever = np.einsum("nij,nbi->njb", w, o_x_g)  # (N, n_model, B) [mm N/kg]
        lin = np.einsum("nij,ni->nj", v, g)[:, :, None]  # (N, n_model, 1)
        scale = np.where(self.revolute, 1e-3, 1.0)[None, :, None]
        mass_term = (lever + lin) * scale
        # first-moment term: (R_b^T (g x w_j)) . h_b [N m per kg m]; zero for prismatic joints (w = 0)
        g_x_w = np.cross(g[:, None, :], np.swapaxes(w, 1, 2))  # (N, n_model, 3)
        h_term = np.einsum("nbij,nmi->nmbj", R, g_x_w)  # (N, n_model, B, 3)
        basis = np.concatenate([mass_term[..., None], h_term], axis=-1) * carries[None, :, :, None]
        self.basis = basis
        self.payload = np.zeros((N, len(model.moving)))
        if payload is not None:
            self.payload = self._payload(model, frames, payload, w, v, g, scale[..., 0])
        if lateral:
            self._lateral(model, frames, w, v, g, o, R, carries, payload)

    def _lateral(self, model, frames, w, v, g, o, R, carries, payload):
        """Bending-moment bases (see the class docstring)."""
        wj, vj = np.swapaxes(w, 1, 2), np.swapaxes(v, 1, 2)  # (N, n_model, 3)
        axis = np.where(self.revolute[None, :, None], wj, vj)
        Fj = frames[:, model.moving]  # (N, n_model, 3, 4): the frame turning with each joint
        origin = Fj[..., 3]
        foot = np.where(self.revolute[None, :, None],
                        np.cross(wj, vj) + wj * np.einsum("nji,nji->nj", wj, origin)[..., None], origin)
        dots = np.abs(np.einsum("njik,nji->njk", Fj[..., :3], axis))  # |column . axis|
        col = np.argmax(dots < 0.7, axis=-1)  # the first of x, y, z clearly off the axis: a choice that
        # does not flip between nearly equal columns (DH and URDF frames: x)
        e1 = np.take_along_axis(Fj[..., :3], col[..., None, None], axis=-1)[..., 0]
        e1 = e1 - axis * np.einsum("nji,nji->nj", e1, axis)[..., None]
        e1 /= np.linalg.norm(e1, axis=-1, keepdims=True)
        e2 = np.cross(axis, e1)
        E = np.stack([e1, e2], axis=2)  # (N, n_model, 2, 3)
        # moment about o_j of body b: m_b ((o_b - o_j)/1000) x g + (R_b h_b) x g
        lever = (o[:, None, :, :] - foot[:, :, None, :]) / 1000.0  # (N, n_model, B, 3) [m]
        gN = g[:, None, None, :]
        m_part = np.cross(lever, gN)  # (N, n_model, B, 3)
        h_part = np.cross(np.swapaxes(R, 2, 3)[:, None], g[:, None, None, None, :])  # (N, 1, B, 3(v), 3)
        Lm = np.einsum("njai,njbi->njab", E, m_part)  # (N, n_model, 2, B)
        Lh = np.einsum("njai,nxbvi->njabv", E, h_part)  # (N, n_model, 2, B, 3)
        basis = np.concatenate([Lm[..., None], Lh], axis=-1) * carries[None, :, None, :, None]
        self.lateral_basis, self.joint_origin, self.lateral_axes = basis, foot, E
        self.lateral_payload = np.zeros(E.shape[:3])
        if payload is not None:
            ee_name, mass, com = payload
            N = len(g)
            e = model.end_effectors[model.end_effector_index(ee_name)]
            if e.link >= 0:
                mass = np.broadcast_to(np.asarray(mass, dtype=float), (N,))
                com = np.broadcast_to(np.asarray(com, dtype=float), (N, 3))
                F = frames[:, e.link]
                T = np.asarray(e.T_link_ee, dtype=float)
                p = np.einsum("nij,nj->ni", F[:, :, :3], com @ T[:3, :3].T + T[:3, 3]) + F[:, :, 3]
                mom = np.cross((p[:, None, :] - foot) / 1000.0, g[:, None, :]) * mass[:, None, None]
                c = self._carries(model, np.array([e.link]))[:, 0]
                self.lateral_payload = np.einsum("njai,nji->nja", E, mom) * c[None, :, None]

    def lateral_moments(self, theta) -> np.ndarray:
        """Bending moments (N, n_model, 2) [N m] about ``lateral_axes`` for body parameters (B, 4)."""
        L = self.lateral_basis  # (N, n_model, 2, B, 4): one matrix-vector product
        th = np.asarray(theta, dtype=float).reshape(-1)
        return (L.reshape(-1, th.size) @ th).reshape(L.shape[:3]) + self.lateral_payload

    @staticmethod
    def _carries(model, body_links) -> np.ndarray:
        """(n_model, B) bool: model joint j moves body b (its link is b's link or an ancestor)."""
        out = np.zeros((len(model.moving), len(body_links)), dtype=bool)
        for b, k in enumerate(body_links):
            while k >= 0:
                hit = np.flatnonzero(model.moving == k)
                if len(hit):
                    out[hit[0], b] = True
                k = model.links[k].parent
        return out

    def _payload(self, model, frames, payload, w, v, g, scale):
        ee_name, mass, com = payload
        N = len(g)
        e = model.end_effectors[model.end_effector_index(ee_name)]
        mass = np.broadcast_to(np.asarray(mass, dtype=float), (N,))
        com = np.broadcast_to(np.asarray(com, dtype=float), (N, 3))
        if not np.all(np.isfinite(mass)) or np.any(mass < 0):
            raise ProblemError("payload: mass must be a finite number >= 0 kg")
        if e.link < 0:
            return np.zeros((N, len(model.moving)))
        F = frames[:, e.link]  # (N, 3, 4)
        T = np.asarray(e.T_link_ee, dtype=float)
        p_link = com @ T[:3, :3].T + T[:3, 3]  # (N, 3) in the link frame
        p = np.einsum("nij,nj->ni", F[:, :, :3], p_link) + F[:, :, 3]  # base frame [mm]
        carries = self._carries(model, np.array([e.link]))[:, 0]
        p_x_g = np.cross(p, g)
        tau = (np.einsum("nij,ni->nj", w, p_x_g) + np.einsum("nij,ni->nj", v, g)) * scale
        return tau * mass[:, None] * carries[None, :]

    def torques(self, theta) -> np.ndarray:
        """tau (N, n_model) [N m | N] for lumped body parameters ``theta`` (B, 4) = (m [kg], h [kg m])."""
        th = np.asarray(theta, dtype=float).reshape(-1)  # one matrix-vector product over (N, n_model, B * 4)
        return (self.basis.reshape(-1, th.size) @ th).reshape(self.basis.shape[:2]) + self.payload
