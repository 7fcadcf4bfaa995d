"""Batched numerical inverse kinematics: damped least squares with adaptive damping.

Works for any chain (serial or a branch of a tree, redundant or not, revolute and prismatic
joints, coupled joints) through :meth:`RobotModel.jacobian`. All poses are solved together:
each iteration is one batched FK and one batched Jacobian over the poses still running.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..transforms import so3_log
from .model import RobotModel

__all__ = ["IKResult", "ik_numeric", "pose_errors"]


@dataclass(frozen=True)
class IKResult:
    """Per-target outcome of :func:`ik_numeric`.

    q (N, n_ctrl) [rad | mm]; converged (N,) bool; iterations (N,); position_error_mm (N,);
    rotation_error_rad (N,); status (N,) strings: ``converged``, ``max_iterations``,
    ``stalled`` (no step reduced the error: unreachable or at a joint limit).
    """

    q: np.ndarray
    converged: np.ndarray
    iterations: np.ndarray
    position_error_mm: np.ndarray
    rotation_error_rad: np.ndarray
    status: np.ndarray

    @property
    def all_converged(self) -> bool:
        return bool(np.all(self.converged))

    def summary(self) -> str:
        n = len(self.converged)
        ok = int(self.converged.sum())
        worst = float(self.position_error_mm.max(initial=0.0))
        return f"{ok}/{n} targets converged; worst position error {worst:.3g} mm"


def pose_errors(T_actual, T_target):
    """Position error (N, 3) [mm] and rotation error vector (N, 3) [rad] (world frame) target - actual."""
    dp = T_target[..., :3, 3] - T_actual[..., :3, 3]
    dr = so3_log(T_target[..., :3, :3] @ np.swapaxes(T_actual[..., :3, :3], -1, -2))
    return dp, dr


def ik_numeric(model: RobotModel, T_target, q0, *, end_effector=None, position_only: bool = False,
               tol_mm: float = 1e-6, tol_rad: float = 1e-9, max_iterations: int = 100,
               rotation_scale_mm: float = 1000.0, damping: float = 1e-3,
               respect_limits: bool = True) -> IKResult:
    """Solve ``fk(q) = T_target`` for every target, starting from ``q0``.

    T_target (N, 4, 4) or (4, 4) [mm]; q0 (N, n_ctrl) or (n_ctrl,) starting joints (e.g. the
    taught joints, or a closed-form branch). Rotation errors are weighted as
    ``rotation_scale_mm`` mm per rad. Levenberg-Marquardt damping ``damping`` (relative to the
    largest singular value squared) grows when a step fails and shrinks when it succeeds.
    With ``respect_limits`` joints are clipped into ``model.limits`` after every step.
    """
    T = np.asarray(T_target, dtype=float)
    single = T.ndim == 2
    T = T.reshape(-1, 4, 4)
    N = len(T)
    q = np.array(np.broadcast_to(np.asarray(q0, dtype=float), (N, model.n_joints)), copy=True)
    lo, hi = model.limits[:, 0], model.limits[:, 1]
    if respect_limits:
        q = np.clip(q, lo, hi)
    rows = slice(0, 3) if position_only else slice(0, 6)
    w = np.ones(6)
    w[3:] = rotation_scale_mm

    def residual(qa, Ta):
        dp, dr = pose_errors(model.fk(qa, end_effector), Ta)
        return np.concatenate([dp, dr * rotation_scale_mm], axis=-1)[:, rows], dp, dr

    r, dp, dr = residual(q, T)
    cost = np.einsum("ij,ij->i", r, r)
    lam = np.full(N, damping)
    iters = np.zeros(N, dtype=int)
    done = _converged(dp, dr, tol_mm, tol_rad, position_only)
    stalled = np.zeros(N, dtype=bool)
    for _ in range(max_iterations):
        act = np.flatnonzero(~done & ~stalled)
        if act.size == 0:
            break
        iters[act] += 1
        J = model.jacobian(q[act], end_effector) * w[:, None]
        q_new = _limited_step(J[:, rows], r[act], lam[act], q[act], lo, hi, respect_limits)
        r_new, dp_new, dr_new = residual(q_new, T[act])
        c_new = np.einsum("ij,ij->i", r_new, r_new)
        better = c_new < cost[act]
        good = act[better]
        q[good], r[good], dp[good], dr[good], cost[good] = q_new[better], r_new[better], dp_new[better], \
            dr_new[better], c_new[better]
        lam[good] = np.maximum(lam[good] / 3.0, 1e-12)
        bad = act[~better]
        lam[bad] *= 10.0
        stalled[bad[lam[bad] > 1e6]] = True
        done = _converged(dp, dr, tol_mm, tol_rad, position_only)
    return _result(q, done, stalled, iters, dp, dr, position_only, single)


def _limited_step(J, r, lam, qa, lo, hi, respect_limits: bool):
    """New joints (n, n_ctrl) after one damped least-squares step from ``qa``. With
    ``respect_limits``, joints resting on a limit that the step pushes outward are frozen (active
    set) and the result is clipped into ``[lo, hi]``."""
    dq = _dls_step(J, r, lam)
    if respect_limits:
        blocked = ((qa <= lo + 1e-12) & (dq < 0)) | ((qa >= hi - 1e-12) & (dq > 0))
        if blocked.any():
            dq = _dls_step(J * ~blocked[:, None, :], r, lam)
    q_new = qa + dq
    if respect_limits:
        q_new = np.clip(q_new, lo, hi)
    return q_new


def _result(q, done, stalled, iters, dp, dr, position_only: bool, single: bool) -> IKResult:
    """The :class:`IKResult` (per target, or of the one target when ``single``)."""
    N = len(q)
    pos_err = np.linalg.norm(dp, axis=-1)
    rot_err = np.zeros(N) if position_only else np.linalg.norm(dr, axis=-1)
    status = np.where(done, "converged", np.where(stalled, "stalled", "max_iterations"))
    res = IKResult(q, done, iters, pos_err, rot_err, status)
    if single:
        res = IKResult(q[0], done[0], iters[0], pos_err[0], rot_err[0], status[0])
    return res


def _dls_step(J, r, lam):
    """Damped least-squares steps ``J^T (J J^T + lam s I)^-1 r`` for stacks J (N, m, n), r (N, m)."""
    JJt = J @ np.swapaxes(J, 1, 2)
    scale = np.maximum(np.trace(JJt, axis1=1, axis2=2) / JJt.shape[1], 1e-12)  # all joints blocked: no step
    A = JJt + (lam * scale)[:, None, None] * np.eye(JJt.shape[1])
    return (np.swapaxes(J, 1, 2) @ np.linalg.solve(A, r[..., None]))[..., 0]


def _converged(dp, dr, tol_mm, tol_rad, position_only):
    ok = np.linalg.norm(dp, axis=-1) <= tol_mm
    if not position_only:
        ok &= np.linalg.norm(dr, axis=-1) <= tol_rad
    return ok
