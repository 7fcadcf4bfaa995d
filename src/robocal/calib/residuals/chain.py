"""The robot chain shared by residual blocks: target points in the instrument frame and their
Jacobians, computed once per evaluation.

``p_inst(n, k) = T_inst_base(station(n)) . T_base_ee(q_n; params) . P_k`` (METHODS.md (3-1)),
with its derivatives ((3-6), the identification Jacobian with ``k_qi``) w.r.t.

* the robot geometry block: from the compiled kernel (``RobotModel.target_points``);
* the station frames block (left perturbation): ``d p = w x p + v`` -> ``[-skew(p) | I]``;
* the target points block: ``R_inst_ee`` (a point moves with its end effector's orientation).

Point, distance and point-on-plane residuals read the same :class:`TargetChain`; each asks the
evaluation for it (``chain.evaluate(ev)``), so the kernel runs once however many kinds use it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import ProblemError

__all__ = ["TargetChain", "ChainPoints"]


@dataclass(frozen=True)
class ChainPoints:
    """points (N, K, 3) [mm] in the instrument frame; jac: {parameter block: (N, K, 3, size)}
    for the blocks whose Jacobian was wanted."""

    points: np.ndarray
    jac: dict


def _frame_jacobian(pts):
    """(..., 3, 6) derivative of points ``pts`` (..., 3) under a left perturbation (w, v) of their frame."""
    J = np.zeros(pts.shape + (6,))
    x, y, z = pts[..., 0], pts[..., 1], pts[..., 2]
    J[..., 0, 1], J[..., 0, 2] = z, -y
    J[..., 1, 0], J[..., 1, 2] = -z, x
    J[..., 2, 0], J[..., 2, 1] = y, -x
    J[..., 0, 3] = J[..., 1, 4] = J[..., 2, 5] = 1.0
    return J


class TargetChain:
    """Target points carried by a robot, seen from one instrument, at the poses ``q``.

    model: the :class:`~robocal.kinematics.model.RobotModel` (its parameter values come from
    ``geometry``); q (N, n_ctrl) [rad | mm]; stations (N,) station index per pose (default 0);
    geometry: a :class:`~robocal.calib.blocks.RobotGeometry`; frames: a
    :class:`~robocal.calib.blocks.StationFrames` (one frame per station); targets: a
    :class:`~robocal.calib.blocks.TargetPoints` (its end effectors resolved on ``model``);
    deflection: optional :class:`~robocal.calib.residuals.deflection.Deflection` (gravity-induced
    joint deflection; its compliance and gravity blocks join the chain's parameter blocks).
    """

    def __init__(self, model, q, geometry, frames, targets, stations=None, deflection=None):
        self.model = model
        self.deflection = deflection
        self.q = np.asarray(q, dtype=float)
        self._q_kernel = model.checked_joints(self.q)  # checked once here, not at every evaluation
        N = len(self.q)
        self.stations = np.zeros(N, dtype=int) if stations is None else np.asarray(stations, dtype=int)
        if self.stations.shape != (N,):
            raise ProblemError(f"stations: expected shape ({N},), got {self.stations.shape}")
        if frames.n_frames <= self.stations.max(initial=0):
            raise ProblemError(f"stations: index {self.stations.max()} but only {frames.n_frames} frame(s)")
        self.geometry, self.frames, self.targets = geometry, frames, targets
        self.ee_of_target = np.array([model.end_effector_index(e) for e in targets.end_effectors], dtype=int)
        self._no_columns = np.zeros(0, dtype=int)

    @property
    def parameter_blocks(self) -> tuple:
        base = (self.geometry, self.frames, self.targets)
        return base if self.deflection is None else base + self.deflection.blocks

    @property
    def n_points(self) -> int:
        return len(self.ee_of_target)

    def evaluate(self, ev) -> ChainPoints:
        """The chain at the evaluation's values, computed once per evaluation."""
        return ev.shared(self, self._evaluate)

    def _evaluate(self, ev) -> ChainPoints:
        blocks = self.parameter_blocks
        wants = tuple(ev.wants(b) for b in blocks)
        elastic = None if self.deflection is None else tuple(ev[b] for b in self.deflection.blocks)
        return self.predict(ev[self.geometry], ev[self.frames], ev[self.targets], self._q_kernel, self.stations,
                            wants if ev.jacobian else None, elastic=elastic, q_checked=True)

    def predict(self, params, bases, points_ee, q, stations, wants=None, *, elastic=None,
                payload="default", gravity=None, q_checked: bool = False) -> ChainPoints:
        """Target points (N, K, 3) at joints ``q`` (N, n_ctrl) and ``stations`` (N,), for block values
        ``params`` (P,), ``bases`` (G, 4, 4), ``points_ee`` (K, 3); ``wants``: None (no Jacobians)
        or one bool per parameter block (geometry, frames, targets[, compliance, gravity]).
        ``elastic``: the (compliance, gravity) block values of a chain with a deflection (default:
        the blocks' initial values); ``payload``: that of the deflection, or one for new poses;
        ``gravity``: (3,) or (N, 3) [m/s^2] in the base frame for new poses (default the deflection's);
        ``q_checked``: ``q`` is known C-contiguous and finite (the chain's own joints)."""
        if self.deflection is not None:
            if elastic is None:
                elastic = tuple(b.initial for b in self.deflection.blocks)
            return self._predict_elastic(params, bases, points_ee, q, stations, wants, elastic, payload, gravity)
        jacobian = wants is not None
        want_g, want_b, want_t = wants[:3] if jacobian else (False, False, False)
        index = self.geometry.index if want_g else self._no_columns
        model, ee = self.model, self.ee_of_target
        jac = {}
        if self.frames.n_frames == 1:  # one base frame: the kernel works in the instrument frame directly
            pts, R_inst_ee, Jg = model.target_points(q, params, points_ee, ee, index, jacobian, root=bases[0],
                                                     q_checked=q_checked)
            if want_g:
                jac[self.geometry] = Jg
        else:
            p_base, R_base_ee, Jg = model.target_points(q, params, points_ee, ee, index, jacobian, q_checked=q_checked)
            Rb = bases[stations, :3, :3]
            pts = np.einsum("nij,nkj->nki", Rb, p_base) + bases[stations, :3, 3][:, None]
            if want_g:
                jac[self.geometry] = np.einsum("nij,nkjf->nkif", Rb, Jg)
            if want_t:
                R_inst_ee = np.einsum("nij,nkjl->nkil", Rb, R_base_ee)
        return self._with_frame_and_target_jacobians(pts, jac, R_inst_ee if want_t else None, stations, want_b)

    def _predict_elastic(self, params, bases, points_ee, q, stations, wants, elastic, payload,
                         gravity=None) -> ChainPoints:
        """:meth:`predict` with joint deflections: FK at the deflected model joints (torsion), then
        the lateral rotations of the joints carrying each point (when the deflection has them)."""
        d = self.deflection
        blocks = self.parameter_blocks
        want = dict(zip(blocks, wants)) if wants is not None else {}
        values = dict(zip(d.blocks, (np.asarray(v, dtype=float) for v in elastic)))
        c, grav = values[d.compliance], values[d.gravity]
        jacobian = wants is not None
        want_g, want_b, want_t = (want.get(b, False) for b in (self.geometry, self.frames, self.targets))
        want_c, want_m = want.get(d.compliance, False), want.get(d.gravity, False)
        dq, gt, tau_sel = d.deflections(q, c, grav, payload, gravity)
        qm = np.asarray(q, dtype=float) @ self.model.coupling.T + dq
        need_joint = want_c or want_m
        g_index = self.geometry.index if want_g else self._no_columns
        j_index = d.motion_param if need_joint else self._no_columns
        union = np.unique(np.concatenate([g_index, j_index])).astype(np.int64)
        g_cols, j_cols = np.searchsorted(union, g_index), np.searchsorted(union, j_index)
        ee = self.ee_of_target
        in_base = self.frames.n_frames > 1 or d.lateral is not None
        pts, R_ee, J = d.model_joints.target_points(qm, params, points_ee, ee, union, jacobian,
                                                    root=None if in_base else bases[0])
        jac = {}
        if jacobian:
            if want_g:
                jac[self.geometry] = J[..., g_cols]
            if need_joint:
                jac.update(d.jacobians(J[..., j_cols], gt, tau_sel, c, want_c, want_m))
        Rb = bases[stations, :3, :3] if in_base else None
        if d.lateral is not None:  # it rotates the Jacobians into the instrument frame too
            pts, jac, R_ee = d.lateral_deflection(pts, jac, R_ee, gt, values, grav, ee, want, R_base=Rb)
        if in_base:
            pts = np.einsum("nij,nkj->nki", Rb, pts) + bases[stations, :3, 3][:, None]
            if d.lateral is None:
                Rb4 = Rb[:, None]  # (N, 1, 3, 3): a batched product (an einsum here cost ~1.4 ms an evaluation)
                jac = {b: Rb4 @ Jb for b, Jb in jac.items()}
            if want_t:
                R_ee = np.einsum("nij,nkjl->nkil", Rb, R_ee)
        return self._with_frame_and_target_jacobians(pts, jac, R_ee if want_t else None, stations, want_b)

    def _with_frame_and_target_jacobians(self, pts, jac, R_inst_ee, stations, want_b) -> ChainPoints:
        """The chain's output with the base-frame Jacobian (``want_b``) and the target-point one
        (``R_inst_ee`` (N, K, 3, 3) given: a point moves with its end effector's orientation)."""
        if want_b:
            jac[self.frames] = self._frames_jacobian(pts, stations)
        if R_inst_ee is not None:
            K = R_inst_ee.shape[1]
            Jt = np.zeros(pts.shape + (3 * K,))
            for k in range(K):
                Jt[:, k, :, 3 * k:3 * k + 3] = R_inst_ee[:, k]
            jac[self.targets] = Jt
        return ChainPoints(pts, jac)

    def _frames_jacobian(self, pts, stations):
        G = self.frames.n_frames
        Jf = _frame_jacobian(pts)
        if G == 1:
            return Jf
        N, K = pts.shape[:2]
        J = np.zeros((N, K, 3, G, 6))
        J[np.arange(N), :, :, stations] = Jf
        return J.reshape(N, K, 3, 6 * G)
