"""Levenberg-Marquardt with per-frame unknowns eliminated by a Schur complement (issue 34 item 1).

A camera calibration from N images has a few global unknowns (intrinsics, distortion, maybe a
board shape: ``g`` columns) and one 6-dof target pose per image; each image's rows depend on the
global unknowns and its own pose only. The normal matrix is then an arrow::

    | A     B_1 .. B_N |        A (g, g) = Jg^T Jg,  B_i (g, 6) = Jg_i^T Jl_i,
    | B_i^T D_i        |        D_i (6, 6) = Jl_i^T Jl_i   (rows of image i)

and a damped step solves ``(D_i + mu I)`` per image and the reduced (Schur complement) system
``S = A + mu I - sum B_i (D_i + mu I)^-1 B_i^T`` of size g: O(N) work and memory instead of the
O(N^3) of the dense (g + 6N) system; J is never materialised beyond its (M, g) and (M, 6) blocks.

The iteration, damping, step acceptance and every stop rule are those of
:class:`robocal.calib._iterate.DampedGaussNewton` (this class only replaces its linear algebra),
so a solve takes the same steps as the dense one up to rounding. Identifiability is decided on the
reduced system: the global columns projected off the pose columns (the poses first in priority,
as in the dense analysis), so the verdicts match the dense QR's. The covariance is the exact
inverse of the normal matrix, assembled from ``S^-1`` and the ``D_i^-1``. Levenberg-Marquardt only
(no ``method="svd"``), no Tikhonov prior.
"""

from __future__ import annotations

import math
import warnings

import numpy as np

from dataclasses import dataclass

from ._cholesky import cholesky_factor, cholesky_inverse, cholesky_solve
from ._iterate import DampedGaussNewton
from .identifiability import IDENTIFIABILITY_TOL, IdentifiabilityReport, analyse_identifiability
from .residuals.base import Evaluation
from .solve import CalibrationResult

__all__ = ["solve_schur", "StructureError", "SchurResult"]


class StructureError(ValueError):
    """The problem does not have the structure this solver needs (the caller uses the dense solve)."""


def _compact_frames(residual, local_block):
    """The frame of each row (M,) of a residual block whose Jacobian by ``local_block`` is compact
    ((M, 6), each row's derivative by its own frame), or None."""
    if getattr(residual, "compact_targets", False) and residual.target_poses is local_block:
        return residual.target_frame_of_row
    if getattr(residual, "compact_corrections", False) and residual.corrections is local_block:
        return residual.correction_frame_of_row
    return None


class _Segment:
    """Consecutive rows [r0, r1) sorted by their frame, each frame seen: per-frame products in a
    zero-padded (n_frames, most rows of a frame) layout, one batched matrix product."""

    def __init__(self, frame, n_frames, r0):
        frame = np.asarray(frame, dtype=int)
        if len(frame) and np.any(np.diff(frame) < 0):
            raise StructureError("rows must be grouped by target frame, every frame seen")
        counts = np.bincount(frame, minlength=n_frames)
        if len(counts) != n_frames or np.any(counts == 0):
            raise StructureError("rows must be grouped by target frame, every frame seen")
        self.r0, self.r1, self.n_frames = r0, r0 + len(frame), n_frames
        self.starts = np.flatnonzero(np.r_[True, np.diff(frame) != 0])
        self.rows_max = int(counts.max(initial=0))
        self.slot = frame * self.rows_max + (np.arange(len(frame)) - self.starts[frame])
        self.dense_slots = bool(np.all(counts == self.rows_max))

    def padded(self, Z):
        """Z (rows, k) in the zero-padded (n_frames, rows_max, k) layout."""
        k = Z.shape[1]
        if not self.dense_slots:
            Zp = np.zeros((self.n_frames * self.rows_max, k))
            Zp[self.slot] = Z
            Z = Zp
        return Z.reshape(self.n_frames, self.rows_max, k)

    def product(self, X, C):
        if self.dense_slots:
            return (X.reshape(self.n_frames, self.rows_max, -1) @ C).reshape(len(X), -1)
        return (self.padded(X) @ C).reshape(-1, C.shape[2])[self.slot]


class _Layout:
    """Columns of a problem with one block of per-frame (6-dof) unknowns: one reprojection residual
    block whose Jacobian by those frames is compact, and optionally Gaussian priors on the frames
    (:class:`~robocal.calib.residuals.PosePriorResidual`: 6 rows per frame, each frame's rows
    depending on that frame only, e.g. the hand-eye flange corrections). The rows of each block are
    one segment sorted by frame (the per-frame products are sums over the segments)."""

    def __init__(self, problem, local_block):
        from .residuals.prior import PriorResidual

        blocks = problem.residual_blocks
        frame = _compact_frames(blocks[0], local_block) if blocks else None
        if frame is None:
            raise StructureError("a first reprojection residual block with a compact Jacobian (compact_targets or "
                                 "compact_corrections) is needed")
        self.problem, self.residual, self.local = problem, blocks[0], local_block
        plan = problem._plan.get(local_block)
        if plan is None or plan[2] is not None:
            raise StructureError("every pose of the eliminated block must be free")
        self.l0, self.l1 = plan[0], plan[1]
        self.n_frames = (self.l1 - self.l0) // 6
        self.priors = []
        for rb in blocks[1:]:
            if not isinstance(rb, PriorResidual) or rb.parameter_blocks != (local_block,):
                raise StructureError("besides the reprojection rows only priors on the eliminated frames are allowed")
            self.priors.append(rb)
        self.n_rows0 = blocks[0].n_rows
        self.gcols = np.r_[0:self.l0, self.l1:problem.n_variables]  # problem columns of the global unknowns
        self.global_plan = []  # (block, offset in Jg, local columns or None, width)
        for blk, (c0, c1, loc) in problem._plan.items():
            if blk is not local_block:
                self.global_plan.append((blk, int(np.searchsorted(self.gcols, c0)), loc, c1 - c0))
        self.segments = [_Segment(frame, self.n_frames, 0)]
        prior_frames = np.arange(6 * self.n_frames) // 6
        for _ in self.priors:
            self.segments.append(_Segment(prior_frames, self.n_frames, self.segments[-1].r1))
        self.frame_of_row = np.concatenate([np.asarray(frame, dtype=int)] + [prior_frames for _ in self.priors])

    def _prior(self, rb, ev, jacobian):
        """``(r (6N,), J (6N, 6) or None)`` of a prior on the frames: each row's derivative by its own
        frame (the diagonal blocks of its (6N, 6N) Jacobian)."""
        from ..transforms import skew, so3_log
        from .blocks.manifolds import FramesBlock, so3_right_jacobian_inverse

        N = self.n_frames
        if isinstance(self.local, FramesBlock):  # FramesBlock.prior_error, its diagonal blocks only
            value, mean = ev[self.local], rb.mean
            R, t = value[:, :3, :3], value[:, :3, 3]
            e_rot = so3_log(mean[:, :3, :3] @ np.swapaxes(R, 1, 2))
            r = np.concatenate([e_rot, mean[:, :3, 3] - t], axis=1).ravel() * rb.row_weight
            if not jacobian:
                return r, None
            D = np.zeros((N, 6, 6))
            D[:, :3, :3] = so3_right_jacobian_inverse(e_rot)
            D[:, 3:, :3] = -skew(t)
            D[:, 3:, 3:] = np.eye(3)
            return r, D.reshape(6 * N, 6) * rb.row_weight[:, None]
        r, jac = rb.evaluate(ev, jacobian)
        if not jacobian:
            return r, None
        idx = np.arange(N)
        return r, jac[self.local].reshape(N, 6, N, 6)[idx, :, idx, :].reshape(6 * N, 6)

    def evaluate(self, state, jacobian=True):
        """``(r (M,), (Jg (M, g), Jl (M, 6)) or None)``."""
        p = self.problem
        ev = Evaluation(dict(zip(p.parameter_blocks, state)), jacobian, p._wanted)
        r, jac = self.residual.evaluate(ev, jacobian)
        parts = [self._prior(rb, ev, jacobian) for rb in self.priors]
        if parts:
            r = np.concatenate([r] + [rp for rp, _ in parts])
        if not jacobian:
            return r, None
        Jg = np.zeros((len(r), len(self.gcols))) if parts else np.empty((len(r), len(self.gcols)))
        m0 = self.n_rows0
        for blk, o, loc, w in self.global_plan:
            Jb = jac[blk]
            Jg[:m0, o:o + w] = Jb if loc is None else Jb[:, loc]
        if not parts:
            return r, (Jg, jac[self.local])
        return r, (Jg, np.concatenate([jac[self.local]] + [jp for _, jp in parts]))

    def frame_gram(self, *columns):
        """Per frame ``Z_i^T Z_i`` (n_frames, k, k) of the row-wise concatenation Z (M, k) of
        ``columns`` (each (M,) or (M, j)), rows of frame i only."""
        cols = [c[:, None] if c.ndim == 1 else c for c in columns]
        return self.gram_rows(np.concatenate(cols, axis=1))

    def gram_rows(self, Z):
        """Per frame ``Z_i^T Z_i`` (n_frames, k, k) of Z (M, k), rows of frame i only."""
        out = None
        for seg in self.segments:
            Zs = seg.padded(Z[seg.r0:seg.r1])
            G = np.swapaxes(Zs, 1, 2) @ Zs
            out = G if out is None else out + G
        return out

    def frame_product(self, X, C):
        """Rows ``X_r C_{frame(r)}`` (M, j) of X (M, k) times per-frame matrices C (n_frames, k, j)."""
        if len(self.segments) == 1:
            return self.segments[0].product(X, C)
        return np.concatenate([seg.product(X[seg.r0:seg.r1], C) for seg in self.segments])

    def per_frame(self, X):
        """Sums of the rows of X (M, ...) per frame: (n_frames, ...)."""
        out = None
        for seg in self.segments:
            S = np.add.reduceat(X[seg.r0:seg.r1], seg.starts, axis=0)
            out = S if out is None else out + S
        return out


def _pose_blocks_sound(D, tol=IDENTIFIABILITY_TOL):
    """Every frame's 6 pose columns independent (unit columns, |R_jj| > tol): else StructureError."""
    d = np.sqrt(np.maximum(np.einsum("nii->ni", D), 1e-300))
    try:
        L = np.linalg.cholesky(D / d[:, :, None] / d[:, None, :])
    except np.linalg.LinAlgError:
        raise StructureError("a target pose is not determined by its image") from None
    if np.any(np.einsum("nii->ni", L) <= tol):
        raise StructureError("a target pose is not determined by its image")
    return D


def _reduced_columns(lay, Jg, Jl):
    """The global columns projected off the per-frame pose columns (M, g) (poses checked independent)."""
    Q = lay.frame_gram(Jl, Jg)
    D = _pose_blocks_sound(Q[:, :6, :6])
    B = Q[:, :6, 6:]  # (N, 6, g) = Jl_i^T Jg_i
    C = np.linalg.solve(D, B)  # D_i^-1 Jl_i^T Jg_i
    return Jg - lay.frame_product(Jl, C)


def reduced_identifiability(lay, Jg, Jl, frames_last: bool = False) -> IdentifiabilityReport:
    """Identifiability of every column from the reduced system: the per-frame poses (always kept,
    checked independent) first, the global columns projected off them (module docstring).

    ``frames_last``: the verdicts of the dense analysis with the per-frame columns *last* in
    priority (as the dense solve orders the hand-eye flange corrections): the global columns are
    analysed alone, and the kept ones, projected off the per-frame columns, must stay independent
    (else the dense analysis would hold some per-frame columns: :class:`StructureError`, the caller
    solves densely)."""
    p = lay.problem
    gnames = [p.names[i] for i in lay.gcols]
    if frames_last:
        rep = analyse_identifiability(Jg, gnames, p.blocks[lay.gcols], column_blocks=p.column_blocks[lay.gcols])
        kept = [gnames.index(n) for n in rep.identifiable]
        Jperp = _reduced_columns(lay, Jg[:, kept], Jl)
        check = analyse_identifiability(Jperp, [gnames[i] for i in kept], explain=False,
                                        column_norms=np.linalg.norm(Jg[:, kept], axis=0))
        if check.dropped:
            raise StructureError("the per-image frames trade off against the global unknowns")
        local = set(p.names[lay.l0:lay.l1])
        kept_names = set(rep.identifiable)
        rep.identifiable = [n for n in p.names if n in kept_names or n in local]
        rep.rank = len(rep.identifiable)
        rep.block_of = {n: str(b) for n, b in zip(p.names, p.column_blocks)}
        return rep
    Jperp = _reduced_columns(lay, Jg, Jl)
    rep = analyse_identifiability(Jperp, gnames, p.blocks[lay.gcols], column_blocks=p.column_blocks[lay.gcols],
                                  column_norms=np.linalg.norm(Jg, axis=0))
    for d in rep.dropped:
        if (d["why"] or "").endswith("(its effect =  in scaled units)") or not d["trades_off_with"]:
            if "zero Jacobian column" not in d["why"]:
                d["why"] = "trades off against the per-image target poses"
    kept = set(rep.identifiable)
    local = set(p.names[lay.l0:lay.l1])
    rep.identifiable = [n for n in p.names if n in kept or n in local]
    rep.rank = len(rep.identifiable)
    rep.block_of = {n: str(b) for n, b in zip(p.names, p.column_blocks)}
    return rep


class SchurGaussNewton(DampedGaussNewton):
    """:class:`DampedGaussNewton` with J kept as (Jg (M, g), Jl (M, 6)) and the poses eliminated."""

    def __init__(self, layout, state, r, J, labels, active, **kw):
        self.lay = layout
        g_active = active[layout.gcols]
        self.g_act = np.flatnonzero(g_active)
        act_cols = np.flatnonzero(active)
        self.pos_g = np.searchsorted(act_cols, layout.gcols[self.g_act])  # in the active step vector
        self.pos_l = np.searchsorted(act_cols, np.arange(layout.l0, layout.l1))
        super().__init__(layout.problem, state, r, J, labels, active, **kw)

    def _column_norms(self, J):
        Jg, Jl = J
        lay = self.lay
        cs = np.empty(self.lay.problem.n_variables)
        cs[lay.gcols] = np.sqrt(np.einsum("ij,ij->j", Jg, Jg))
        cs[lay.l0:lay.l1] = np.sqrt(lay.per_frame(Jl * Jl)).ravel()
        return cs

    def augmented(self, st, with_jac=True):
        return self.lay.evaluate(st, with_jac)

    def _scaled(self, J, r, w_rows):
        """Scaled, weighted active global (M, g) and pose (M, 6) Jacobians and residuals (M,)."""
        lay, cs = self.lay, self.col_scale
        Jg, Jl = J
        ga = Jg[:, self.g_act] / cs[lay.gcols[self.g_act]]
        la = Jl / cs[lay.l0:lay.l1].reshape(-1, 6)[lay.frame_of_row]
        if w_rows is not None:
            sw = np.sqrt(w_rows)
            ga, la, r = ga * sw[:, None], la * sw[:, None], r * sw
        return ga, la, r

    def _blocks(self, J, r, w_rows):
        """(A, B, D, gA, gl) of the scaled, weighted active system."""
        lay, cs = self.lay, self.col_scale
        Jg, Jl = J
        g = len(self.g_act)
        if getattr(self, "_inv_rows", None) is None:  # the column scaling is fixed for the solve
            self._inv_g = 1.0 / cs[lay.gcols[self.g_act]]
            self._inv_rows = 1.0 / cs[lay.l0:lay.l1].reshape(-1, 6)[lay.frame_of_row]
            self._all_g = len(self.g_act) == Jg.shape[1]
        Z = np.empty((len(r), g + 7))  # [scaled Jg, scaled Jl, r] written in place
        np.multiply(Jg if self._all_g else Jg[:, self.g_act], self._inv_g, out=Z[:, :g])
        np.multiply(Jl, self._inv_rows, out=Z[:, g:g + 6])
        Z[:, -1] = r
        if w_rows is not None:
            Z *= np.sqrt(w_rows)[:, None]
        Q = lay.gram_rows(Z)  # (N, g + 7, g + 7): every block of the normal equations per frame
        A = Q[:, :g, :g].sum(0)
        B = Q[:, :g, g:g + 6]  # (N, g, 6)
        D = Q[:, g:g + 6, g:g + 6]  # (N, 6, 6)
        return A, B, D, Q[:, :g, -1].sum(0), Q[:, g:g + 6, -1]

    def _normal_equations(self):
        A, B, D, gA, gl = self._blocks(self.J, self.r, self.w_rows if self.weighted else None)
        g = np.empty(len(self.pos_g) + len(self.pos_l))
        g[self.pos_g], g[self.pos_l] = gA, gl.ravel()
        g_max = max(float(A.diagonal().max(initial=0.0)), float(np.einsum("nii->ni", D).max()))
        return (A, B, D), g, g_max

    def _damped_solve(self, G, shift, g):
        A, B, D = G
        eye6 = np.eye(6)
        Dd = D + shift * eye6
        np.linalg.cholesky(Dd)  # LinAlgError when a pose block is not positive definite
        Dinv = np.linalg.inv(Dd)
        gA, gl = g[self.pos_g], g[self.pos_l].reshape(-1, 6)
        BDinv = B @ Dinv  # (N, g, 6)
        S = A - np.einsum("nij,nkj->ik", BDinv, B)
        S.ravel()[::len(S) + 1] += shift
        xg = cholesky_solve(cholesky_factor(S, overwrite=True), gA - np.einsum("nij,nj->i", BDinv, gl)) \
            if len(S) else np.zeros(0)
        xl = np.einsum("nij,nj->ni", Dinv, gl - np.einsum("nji,j->ni", B, xg))
        out = np.empty(len(g))
        out[self.pos_g], out[self.pos_l] = xg, xl.ravel()
        return out


@dataclass
class SchurResult(CalibrationResult):
    """:class:`~robocal.calib.solve.CalibrationResult` of :func:`solve_schur`, with the leverage
    (M,) of every residual row: the diagonal of the hat matrix ``J Cov J^T`` (J the final weighted
    Jacobian unweighted by robust weights, Cov the result's covariance), which a variance-component
    estimate needs and which the dense J (never formed here) would otherwise give."""

    leverage: np.ndarray | None = None


def _covariance(gn, row_weights, scale_known):
    """Covariance (n, n) [NaN outside the identifiable set], std, rank, condition (of the reduced
    system S), sigma0 and the leverage of every row (M,), from the final blocks: inverse of the
    arrow normal matrix.

    The leverage of row r (the hat matrix's diagonal ``J_r Cov J_r^T``, J unweighted by robust
    weights, Cov the covariance) is, with the row's global part x, pose part y in frame i and
    ``W_i = D_i^-1 B_i^T``: ``(x - y W_i) S^-1 (x - y W_i)^T + y D_i^-1 y^T``."""
    lay, n = gn.lay, gn.n
    w = None if np.all(row_weights == 1.0) else row_weights
    ga, la, _ = gn._scaled(gn.J, gn.r, w)
    g = ga.shape[1]
    Q = lay.frame_gram(ga, la)
    B, D = Q[:, :g, g:].copy(), Q[:, g:, g:].copy()
    # a frame of weight 0 (an image dropped as an outlier) carries no information: no covariance
    dead = np.einsum("nii->n", D) == 0.0
    D[dead], B[dead] = np.eye(6), 0.0
    rr = float(gn.r @ gn.r) if w is None else float(np.sum(w * gn.r**2))
    n_act = len(gn.g_act) + 6 * lay.n_frames
    sigma0 = math.sqrt(rr / max(len(gn.r) - n_act, 1))
    Dinv = np.linalg.inv(D)
    Dinv[dead] = np.nan
    W = Dinv @ np.swapaxes(B, 1, 2)  # (N, 6, g) = D_i^-1 B_i^T
    W[dead] = 0.0
    # S as the Gram matrix of the global columns projected off the poses (no cancellation, PSD)
    Jperp = ga - lay.frame_product(la, W)
    S = Jperp.T @ Jperp
    ev, V = np.linalg.eigh(S)
    ev, V = ev[::-1], V[:, ::-1]
    s = np.sqrt(np.maximum(ev, 0.0))
    cond = float(s[0] / s[-1]) if s.size and s[-1] > 0 else float("inf")
    try:
        Sinv = cholesky_inverse(S) if len(S) else np.zeros((0, 0))
    except np.linalg.LinAlgError:  # numerically singular: pseudo-inverse on the resolvable directions
        keep = s > 1e-7 * s[0]
        Sinv = (V * np.where(keep, 1.0 / np.where(ev > 0, ev, 1.0), 0.0)) @ V.T
    Wf = W.reshape(-1, W.shape[2])  # (6N, g)
    cov_gl = -Sinv @ Wf.T
    cov_ll = Wf @ Sinv @ Wf.T
    idx = np.arange(lay.n_frames)
    cov_ll.reshape(lay.n_frames, 6, lay.n_frames, 6)[idx, :, idx, :] += Dinv
    cols = np.r_[lay.gcols[gn.g_act], np.arange(lay.l0, lay.l1)]
    cs = gn.col_scale[cols]
    ng = len(Sinv)
    cov_s = np.empty((ng + len(cov_ll),) * 2)
    cov_s[:ng, :ng], cov_s[:ng, ng:], cov_s[ng:, :ng], cov_s[ng:, ng:] = Sinv, cov_gl, cov_gl.T, cov_ll
    cov_s /= np.outer(cs, cs)
    cov_a = cov_s if scale_known else cov_s * sigma0**2
    if w is not None:  # the leverage reads the rows unweighted by the robust weights
        ga, la, _ = gn._scaled(gn.J, gn.r, None)
        Jperp = ga - lay.frame_product(la, W)
    Dl = np.where(dead[:, None, None], 0.0, Dinv)
    leverage = np.einsum("ij,ij->i", Jperp @ Sinv, Jperp) + np.einsum("ij,ij->i", lay.frame_product(la, Dl), la)
    if not scale_known:
        leverage *= sigma0**2
    if len(cols) == n and np.array_equal(cols, np.arange(n)):  # every column active, in this order
        cov = cov_a
    else:
        cov = np.full((n, n), np.nan)
        cov[np.ix_(cols, cols)] = cov_a
    return cov, np.sqrt(np.diag(cov)), n_act, cond, sigma0, leverage


def _solve_once(lay, state0, ident, kw, frames_last=False):
    from .solve import _outlier_report

    p = lay.problem
    r, J = lay.evaluate(state0)
    if len(r) < p.n_variables:
        raise ValueError(f"too few measurements: {len(r)} residuals for {p.n_variables} unknowns")
    if ident is None:
        ident = reduced_identifiability(lay, *J, frames_last)
    ident_set = set(ident.identifiable)
    active = np.array([nm in ident_set for nm in p.names])
    r0 = r.copy()
    gn = SchurGaussNewton(lay, state0, r, J, p.labels, active, method="lm", loss=kw["loss"],
                          f_scale=kw["f_scale"], prior_weight=0.0, rcond=1e-8, ftol=kw["ftol"], xtol=kw["xtol"],
                          chi2_tol=kw["chi2_tol"], progress=None)
    gn.run_phase(1, kw["max_iterations"])
    if gn.robust and kw["reject_outliers"] and gn.drop_outliers(kw["outlier_threshold"]):
        gn.run_phase(gn.it + 1, kw["max_iterations"])
    weights = gn.weights if not gn.rejected.any() else np.where(gn.rejected, gn.robust_weights, 1.0)
    cov, std, rank, cond, sigma0, leverage = _covariance(gn, gn.weights[gn.pose_of_row], p.sigma_known)
    outliers = _outlier_report(p, gn, gn.r, weights, kw["outlier_threshold"]) if kw["loss"] != "linear" else []
    return SchurResult(
        names=p.names, units=p.units, values=p.variable_values(gn.state), initial=p.variable_values(state0),
        std=std, covariance=cov, state=gn.state, problem=p, residuals_before=r0, residuals_after=gn.r,
        iterations=gn.it, converged=gn.converged, reason=gn.reason, rank=rank, condition_number=cond,
        sigma0=sigma0, identifiability=ident, outliers=outliers, _jacobian=None, leverage=leverage), gn


def _held_may_have_become_identifiable(lay, J, ident) -> bool:
    """The dense solve's cheap screen (:func:`robocal.calib.solve._dropped_may_have_become_identifiable`)
    on the reduced columns: a held global column independent of the kept ones, both projected off
    the per-frame poses, is independent of every kept column of the full Jacobian."""
    from .solve import _dropped_may_have_become_identifiable

    p = lay.problem
    gnames = [p.names[i] for i in lay.gcols]
    kept = set(ident.identifiable)
    sub = IdentifiabilityReport([n for n in gnames if n in kept],
                                [d for d in ident.dropped if d["name"] in set(gnames)])
    try:
        Jperp = _reduced_columns(lay, *J)
    except StructureError:
        return True
    return _dropped_may_have_become_identifiable(Jperp, gnames, sub)


def solve_schur(problem, local_block, *, loss: str = "linear", f_scale: float | None = None,
                max_iterations: int = 50, ftol: float = 1e-9, xtol: float = 1e-10, chi2_tol: float = 1e-3,
                outlier_threshold: float = 0.5, reject_outliers: bool = True, state0=None,
                auto_identifiable: bool = True, frames_last: bool = False):
    """:func:`robocal.calib.solve` (Levenberg-Marquardt, ``auto_identifiable``) of a problem whose
    single residual block is a :class:`~robocal.calib.residuals.ReprojectionResidual` built with
    ``compact_targets=True``, the 6-dof frames of ``local_block`` (its target poses, all free)
    eliminated per frame (module docstring). Same arguments and result as ``solve``, except
    ``result.jacobian`` is None and ``condition_number`` is that of the reduced (global) system;
    ``result.leverage`` (M,) the hat matrix's diagonal. ``state0``: the start (default the
    problem's initial state); ``auto_identifiable=False``: every column is solved (no analysis);
    ``frames_last``: identifiability verdicts as the dense solve's with the per-frame columns last in
    priority (:func:`reduced_identifiability`; hand-eye), and, as the dense solve, the analysis at the
    solution runs only when a held column has moved off the kept ones by more than its screen (1e-4
    of its norm); False: the per-frame poses first, re-analysed whenever something is held (camera
    calibration).

    Raises :class:`StructureError` when the problem lacks the structure (a pose its image does not
    determine, rows not grouped by frame): the caller then solves densely.
    """
    from .solve import NotConvergedWarning, not_converged_message

    lay = _Layout(problem, local_block)
    kw = dict(loss=loss, f_scale=f_scale, max_iterations=max_iterations, ftol=ftol, xtol=xtol, chi2_tol=chi2_tol,
              outlier_threshold=outlier_threshold, reject_outliers=reject_outliers)
    start = problem.initial_state() if state0 is None else state0
    ident0 = None if auto_identifiable else IdentifiabilityReport.trivial(problem.names)
    res, gn = _solve_once(lay, start, ident0, kw, frames_last)
    for _ in range(2):  # the identifiable set again at the solution (as solve's auto_identifiable)
        if not res.identifiability.dropped:
            break
        if frames_last and not _held_may_have_become_identifiable(lay, gn.J, res.identifiability):
            break
        ident = reduced_identifiability(lay, *gn.J, frames_last)
        if set(ident.identifiable) == set(res.identifiability.identifiable):
            break
        iters, before = res.iterations, res.residuals_before
        res, gn = _solve_once(lay, res.state, ident, kw, frames_last)
        res.iterations += iters
        res.residuals_before, res.initial = before, problem.variable_values(start)
    if not res.converged:
        warnings.warn(NotConvergedWarning(not_converged_message(res)), stacklevel=2)
    return res
