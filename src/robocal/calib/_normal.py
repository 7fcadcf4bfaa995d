"""Levenberg-Marquardt on normal equations accumulated per block of poses: the point-measurement
calibration problem without the full Jacobian.

For the common robot calibration (a :class:`~robocal.calib.problem.CalibrationProblem` with point
measurements only, one station, no elastic model, no priors) the solver needs only ``J^T J`` (n, n)
and ``J^T r`` (n,) of the weighted Jacobian, never J (M, n) itself. :class:`PointNormalEquations`
computes them over blocks of :data:`POSE_BLOCK` poses: per block, one call of the
``target_points`` kernel (numpy or compiled: :mod:`robocal.kinematics._backend`), the block's
Jacobian rows (geometry from the kernel, base frame and target points in closed form) written into
one reused buffer, and its contribution added to
``J^T J`` by one matrix product. The per-evaluation memory is that buffer (a few MB), and the work
skips the per-block dictionaries, scatter copies and weighted copies of the general
:meth:`~robocal.calib.core.Problem.evaluate` and the scaled copy of J in every iteration.

:class:`NormalEquationsLM` is :class:`~robocal.calib._iterate.DampedGaussNewton` (the same damping,
line search, convergence policy and stop reasons) with the normal equations taken from those sums.
Internal module: :func:`robocal.calib.solve` uses it when :func:`supports` says the problem fits.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ..kinematics._numpy_kernels import reused_work
from ._iterate import DampedGaussNewton

__all__ = ["NormalEquations", "PointNormalEquations", "NormalEquationsLM", "supports", "POSE_BLOCK"]

#: Poses per block: the block's Jacobian rows (3 K POSE_BLOCK x n floats) stay ~3 MB; the numpy kernels'
#: per-call overhead is amortised (at 2 048 poses a UR10 block with its Jacobian took x1.3 the time per pose).
POSE_BLOCK = 4096
#: Rows of J added to the triangular factor per QR (:meth:`PointNormalEquations.r_factor`).
QR_ROWS = 6144


class NormalEquations(NamedTuple):
    """JtJ (n, n) = J^T J and Jtr (n,) = J^T r of the weighted prediction Jacobian J and residuals r."""

    JtJ: np.ndarray
    Jtr: np.ndarray


def supports(problem) -> bool:
    """True when ``problem`` is a point-only, one-station, rigid ``CalibrationProblem``: residual
    blocks = one :class:`~robocal.calib.residuals.PointResidual`, no prior rows, no deflection."""
    from .problem import CalibrationProblem
    from .residuals.points import PointResidual

    if type(problem) is not CalibrationProblem or "evaluate" in vars(problem):
        return False  # a subclass or an instance with its own evaluate: the general path reads it
    rbs = problem.residual_blocks
    if len(rbs) != 1 or type(rbs[0]) is not PointResidual or rbs[0].chain is not problem.chain:
        return False
    ch = problem.chain
    if ch.deflection is not None or ch.frames.n_frames != 1:
        return False
    # every column belongs to the chain's blocks (no free planes without plane rows)
    return set(problem._plan) <= {ch.geometry, ch.frames, ch.targets}


class PointNormalEquations:
    """``evaluate(state, jacobian)`` -> ``(r (M,), NormalEquations or None)`` of a problem that
    :func:`supports` accepts; r is the same as ``problem.evaluate(state)[0]`` and the sums those
    of its J (up to rounding: they are added block by block)."""

    def __init__(self, problem, pose_block: int = POSE_BLOCK):
        self.problem = problem
        self.block = int(pose_block)
        res = problem.residual_blocks[0]
        ch = problem.chain
        self.chain, self.model = ch, ch.model
        self.q = ch._q_kernel
        self.measured, self.mask, self.all = res.measured, res.mask, res._all
        self.w = res.weight
        self.ee = ch.ee_of_target
        self.n = problem.n_variables
        self.K = ch.n_points
        self.geom = problem._plan.get(ch.geometry)
        self.frames = problem._plan.get(ch.frames)
        self.targets = problem._plan.get(ch.targets)
        self.g_index = ch.geometry.index if self.geom is not None else ch._no_columns
        self.m_rows = int(self.mask.sum()) * 3
        self._buf = None
        # every entry of a block's rows is written (one target, every column a whole block's): no zeroing
        plans = [p for p in (self.geom, self.frames, self.targets) if p is not None]
        self._covers = (self.K == 1 and all(p[2] is None for p in plans)
                        and sum(p[1] - p[0] for p in plans) == self.n)

    def r_factor(self, state):
        """``(r (M,), NormalEquations, R (k, n))`` with R the triangular factor of a QR factorization
        of the weighted Jacobian J (M, n), k = min(M, n), built block by block (R of [R; J_block]).

        ``J = Q R`` with orthonormal Q, so R has J's column norms, its QR in any column order gives
        the same |R_jj|, and least squares on its columns the same coefficients: the identifiability
        analysis of R is that of J (without squaring the conditioning as J^T J would), in n x n memory."""
        return self.evaluate(state, True, want_r=True)

    def evaluate(self, state, jacobian: bool = True, *, want_r: bool = False):
        params, bases, pts_ee = state.params, state.bases, state.targets
        N, K, n, w = len(self.q), self.K, self.n, self.w
        r = np.empty(self.m_rows)
        JtJ = np.zeros((n, n)) if jacobian else None
        Jtr = np.zeros(n) if jacobian else None
        Rf = np.zeros((0, n))
        root = bases[0]
        row = 0
        with reused_work():  # the numpy kernels keep their working arrays from block to block
            for i0 in range(0, N, self.block):
                i1 = min(i0 + self.block, N)
                pts, R, Jg = self.model.target_points(self.q[i0:i1], params, pts_ee, self.ee, self.g_index, jacobian,
                                                      root=root, q_checked=True)
                diff = self.measured[i0:i1] - pts
                if self.all:
                    rb = diff.ravel()
                else:
                    m = self.mask[i0:i1]
                    rb = diff[m].ravel()
                rb *= w
                r[row:row + len(rb)] = rb
                row += len(rb)
                if not jacobian:
                    continue
                Jb = self._block_jacobian(pts, R, Jg, i1 - i0)
                if not self.all:
                    Jb = Jb.reshape(i1 - i0, K, 3, n)[self.mask[i0:i1]].reshape(-1, n)
                JtJ += Jb.T @ Jb
                Jtr += Jb.T @ rb
                if want_r:  # R of [R; w Jb], in parts of QR_ROWS rows (the QR's copies stay ~1-2 MB)
                    for c0 in range(0, Jb.shape[0], QR_ROWS):
                        part = Jb[c0:c0 + QR_ROWS]
                        stacked = np.empty((Rf.shape[0] + part.shape[0], n))
                        stacked[:Rf.shape[0]] = Rf
                        np.multiply(part, w, out=stacked[Rf.shape[0]:])
                        Rf = np.linalg.qr(stacked, mode="r")
        if not jacobian:
            return r, None
        # the rows above are unweighted: J = w * Jb, and rb already carries w
        JtJ *= w * w
        Jtr *= w
        if want_r:
            return r, NormalEquations(JtJ, Jtr), Rf
        return r, NormalEquations(JtJ, Jtr)

    def _block_jacobian(self, pts, R, Jg, B):
        """Unweighted prediction Jacobian rows (B K 3, n) of one block of B poses (a reused buffer)."""
        K, n = self.K, self.n
        rows = B * K * 3
        if self._buf is None or self._buf.shape[0] < rows:
            self._buf = np.zeros((max(rows, min(self.block, len(self.q)) * K * 3), n))
        Jb = self._buf[:rows]
        if not self._covers:
            Jb[:] = 0.0
        J4 = Jb.reshape(B, K, 3, n)
        if self.geom is not None:
            c0, c1, loc = self.geom
            J4[..., c0:c1] = Jg if loc is None else Jg[..., loc]
        if self.frames is not None:  # left perturbation (w, v) of the base frame: dp = w x p + v
            c0, c1, loc = self.frames
            Jf = J4[..., c0:c1] if loc is None else np.zeros((B, K, 3, 6))
            x, y, z = pts[..., 0], pts[..., 1], pts[..., 2]
            Jf[..., 0, 0] = Jf[..., 1, 1] = Jf[..., 2, 2] = 0.0
            Jf[..., 0, 1], Jf[..., 0, 2] = z, -y
            Jf[..., 1, 0], Jf[..., 1, 2] = -z, x
            Jf[..., 2, 0], Jf[..., 2, 1] = y, -x
            Jf[..., 3:] = 0.0
            Jf[..., 0, 3] = Jf[..., 1, 4] = Jf[..., 2, 5] = 1.0
            if loc is not None:
                J4[..., c0:c1] = Jf[..., loc]
        if self.targets is not None:  # a point moves with its end effector's orientation
            c0, c1, loc = self.targets
            if loc is None:
                for k in range(K):
                    J4[:, k, :, c0 + 3 * k:c0 + 3 * k + 3] = R[:, k]
            else:
                Jt = np.zeros((B, K, 3, 3 * K))
                for k in range(K):
                    Jt[:, k, :, 3 * k:3 * k + 3] = R[:, k]
                J4[..., c0:c1] = Jt[..., loc]
        return Jb


class NormalEquationsLM(DampedGaussNewton):
    """:class:`DampedGaussNewton` (method ``"lm"``, linear loss, no prior) whose "Jacobian" is the
    :class:`NormalEquations` of a :class:`PointNormalEquations`: the same iteration, line search and
    convergence policy; the scaled normal matrix is ``JtJ / (s s^T)`` instead of ``(J / s)^T (J / s)``."""

    def __init__(self, problem, state, r, ne, labels, active, *, evaluator, **kw):
        self.evaluator = evaluator
        super().__init__(problem, state, r, ne, labels, active, **kw)

    def _column_norms(self, J):
        return np.sqrt(np.maximum(np.diag(J.JtJ), 0.0))

    def _n_columns(self, J):
        return J.JtJ.shape[0]

    def augmented(self, st, with_jac=True):
        return self.evaluator.evaluate(st, with_jac)

    def _normal_system(self):
        a, cs = self.active, self.col_scale
        if self.all_active:
            return self.J.JtJ / np.outer(cs, cs), self.J.Jtr / cs
        ca = cs[a]
        return self.J.JtJ[np.ix_(a, a)] / np.outer(ca, ca), self.J.Jtr[a] / ca
