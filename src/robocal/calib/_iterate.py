"""The damped Gauss-Newton iteration behind :func:`robocal.calib.solve` (Levenberg-Marquardt or
truncated SVD, METHODS.md (3-9, 3-10)), with per-pose robust weights, an optional Tikhonov prior
on the geometry and a second, plain phase after dropping outliers.

Columns are scaled by the norms of the initial Jacobian's columns; the step is solved on the
identifiable (``active``) columns only. Internal module: the public entry is ``solve``.

Damping (LM): ``problem.damping`` (:class:`robocal.calib.core.Problem`) chooses its update:
``"tenfold"`` divides it by 10 after a taken step and multiplies it by 10 after a refused one;
``"gain"`` is Nielsen's rule (Madsen, Nielsen & Tingleff, *Methods for non-linear least squares
problems*, 2004, sec. 3.2): after a taken step ``lam *= max(1/3, 1 - (2 rho - 1)^3)`` with ``rho``
the actual over the predicted cost reduction, after a refused one ``lam *= nu, nu *= 2`` (``nu``
reset to 2 by a taken step). The stop rules below are the same for both.

Convergence policy (the one of every solver in robocal): a solve has converged when one stated
criterion was met after an accepted step -- relative cost change below ``ftol``, chi-square change
*and the estimated chi-square change still to come* below ``chi2_tol`` residual variances (below),
scaled step below ``xtol`` -- or at a first-order stationary
point: the largest scaled gradient component ``|J_j^T r|`` at most ``GTOL`` times
``max_j |J_j| * |r|`` (the cosine between the residuals and the Jacobian's columns), or a
Gauss-Newton step predicting a cost reduction of at most ``STALL_RTOL`` of the cost. "No step
reduces the cost" is convergence only at such a stationary point (numerical precision reached);
anywhere else it is reported as NOT converged, as is reaching the iteration cap. A trial step must
lower the cost strictly, and the cost-change and step-size criteria count only for steps whose
damping is below 1 (a heavily damped step is short wherever it is).

Growing column scales: a problem can name columns (``Problem.growing_scale_columns``) whose norm at
the start says nothing about their size later on -- a lumped elastic model starts with every first
moment zero and every compliance equal, so its compliance columns are the torques of point masses
and its gravity columns scale with compliances still far from their values. For those columns, in
the first round of :func:`robocal.calib.solve` only, the scale is raised after each accepted step
to the column's current norm where that is larger (Moré 1978, the rule of MINPACK's ``lmder``):
with the start's scaling the damping held them back and the first round crawled along the
lumped model's scale symmetry to the iteration cap (DLR Justin elastic-full: 1000 iterations
against 68). Later rounds start from the first round's solution, where the columns are
representative, and keep their start's scaling: raising it there amplifies the lumped model's
near-symmetric directions (a compliance growing while its body's first moment shrinks) and the
iteration follows them for hundreds of steps. Only the damping changes; the cost and the stop
rules do not.

The chi-square criterion: with ``d_k``, ``d_{k-1}``, ``d_{k-2}`` the cost decreases of the last
three accepted steps of the phase (however damped), ``q = max(d_k / d_{k-1}, d_{k-1} / d_{k-2})`` and the remaining
decrease ``R_k = d_k q / (1 - q)`` (the geometric tail of steps that keep contracting at ``q``;
infinite before a phase's third step or when ``q >= 1``, :func:`remaining_decrease_bound`), the solve
stops when ``2 max(d_k, R_k) <= chi2_tol * s^2`` with ``s^2 = 2 cost / (M - n_active)`` and the
damping at most 1e-3. Where Gauss-Newton converges quadratically the ratios are small and
``R_k <= d_k`` once ``q <= 1/2``: the rule is the plain "last change below chi2_tol" then (a phase
takes at least three steps to stop by it). Where it converges only linearly -- large residuals with strong curvature, the
lumped elastic fits of docs/elastic.md, whose dropped second-order term is far larger than J^T J in
some directions -- the last change can be tiny while the cost is still many tolerances above the
minimum; ``R_k`` then keeps the iteration going (or to the cap, reported as not converged). The
Gauss-Newton model's own prediction at the accepted point (½ g^T (J^T J)^-1 g) is no such bound: it
underestimates the remaining decrease by the same factor ``1 - q`` as the last change does.
"""

from __future__ import annotations

import math

import numpy as np

from ._cholesky import cholesky_factor, cholesky_solve

MAX_ITERATIONS_REASON = "maximum iterations reached"

#: First-order optimality tolerance: largest |J_j^T r| over max_j |J_j| * |r| (scaled, weighted).
#: Where the line search stalls at a true minimum this is ~sqrt(2 eps) * s_min / s_max < 2e-8.
GTOL = 1e-6
#: ... or the Gauss-Newton step predicts a cost reduction of at most this fraction of the cost (the
#: residuals themselves at their rounding level, e.g. exact data, make the gradient test too strict).
STALL_RTOL = 1e-6


def no_step_reason(optimality: float, rel: float) -> tuple[str, bool]:
    """(reason, converged) when no trial step lowers the cost: converged only at a stationary point
    (scaled gradient ``optimality`` <= GTOL or predicted relative reduction ``rel`` <= STALL_RTOL)."""
    what = f"gradient {optimality:.1e} of |J| |r|, the Gauss-Newton step would lower the cost by {rel:.1e} of it"
    if optimality <= GTOL or rel <= STALL_RTOL:
        return f"no step reduces the cost at a stationary point ({what}: numerical precision reached)", True
    return (f"no step reduces the cost, but not at a minimum ({what}; limits {GTOL:g} and {STALL_RTOL:g}): "
            "inconsistent Jacobian or discontinuous cost", False)


def chi2_reason(chi2_tol: float) -> str:
    """The stop reason of the chi-square criterion (module docstring)."""
    return f"chi-square change and its estimated remainder below {chi2_tol:g} residual variances"


def remaining_decrease_bound(dcost: float, dcost_prev: float | None, dcost_prev2: float | None) -> float:
    """Estimated cost decrease still to come after an accepted step (the chi-square stop's bound).

    ``dcost``, ``dcost_prev``, ``dcost_prev2``: the cost decreases of the last three accepted steps
    of the phase, newest first (``None`` where the phase has had fewer). With the contraction ratio
    ``q = max(dcost / dcost_prev, dcost_prev / dcost_prev2)`` (the slower of the last two: one short
    step in a slow valley is no contraction), steps that keep contracting at ``q`` lower the cost by
    ``dcost (q + q^2 + ...) = dcost q / (1 - q)`` more; ``inf`` when the phase has had fewer than
    three steps or ``q >= 1`` (no contraction seen). Same units as the cost.
    """
    if dcost_prev is None or dcost_prev2 is None or not (dcost_prev > 0.0 and dcost_prev2 > 0.0):
        return math.inf
    q = max(dcost / dcost_prev, dcost_prev / dcost_prev2)
    if q >= 1.0:
        return math.inf
    return dcost * q / (1.0 - q)


def robust_weights(r_pose, loss, f_scale):
    """Per-pose IRLS weights (N,) for ``huber`` / ``cauchy`` from pose residual norms (N,)."""
    z = r_pose / f_scale
    if loss == "linear":
        return np.ones_like(z)
    if loss == "huber":
        return np.where(z <= 1.0, 1.0, 1.0 / np.maximum(z, 1e-300))
    if loss == "cauchy":
        return 1.0 / (1.0 + z**2)
    raise ValueError(f"loss must be 'linear', 'huber' or 'cauchy', got {loss!r}")


def pose_norms(pose_of_row, r, n_slots):
    """Norm of each pose's residual rows (n_slots,); rows of no pose are counted in the last slot."""
    return np.sqrt(np.bincount(pose_of_row, weights=r**2, minlength=n_slots))


class DampedGaussNewton:
    """One solve's iteration state: the current estimate, residuals r (M,), Jacobian J (M, n),
    weights per pose slot, cost, damping ``lam``, iteration count and stop reason."""

    def __init__(self, problem, state, r, J, labels, active, *, method, loss, f_scale, prior_weight, rcond,
                 ftol, xtol, chi2_tol, progress, prior_center=None, growing_scale=None):
        self.problem, self.method, self.loss, self.rcond = problem, method, loss, rcond
        self.ftol, self.xtol, self.chi2_tol, self.progress = ftol, xtol, chi2_tol, progress
        self.prior_weight = prior_weight
        self.active = active
        self.n = problem.n_variables
        self.n_poses = problem.n_poses
        # robust weights act per pose; rows of no pose (priors, label -1) share one extra slot of weight 1
        self.pose_of_row = np.where(labels[:, 0] < 0, self.n_poses, labels[:, 0])
        self.n_slots = self.n_poses + 1
        self.col_scale = self._column_norms(J)
        self.col_scale[self.col_scale == 0] = 1.0
        # columns whose scale follows their norm upward (module docstring, "Growing column scales")
        self.growing_scale = None if growing_scale is None or not np.any(growing_scale) \
            else np.asarray(growing_scale, dtype=bool)
        self.geom = problem.blocks == "geometry"
        # the prior pulls toward the solve's start (``prior_center``: the geometry values of the first
        # round's start when a later round or an early identifiability look continues from elsewhere)
        self.p_start = None if not prior_weight else (
            problem.variable_values(state, "geometry") if prior_center is None else np.asarray(prior_center, dtype=float))
        self.weights = np.ones(self.n_slots)
        self.f_scale = f_scale
        if loss != "linear":
            self._initial_robust_weights(r)
        if prior_weight:
            r, J = self.augmented(state)
        self.state, self.r, self.J = state, r, J
        self.w_rows = self.row_weights()
        self.robust = loss != "linear"
        self.weighted = self.robust or bool(prior_weight)
        self.cost = self._cost(r)
        self.lam = 1e-3
        damping = getattr(problem, "damping", "tenfold")
        if damping not in ("tenfold", "gain"):
            raise ValueError(f"problem.damping must be 'tenfold' or 'gain', got {damping!r}")
        self.gain_damping = damping == "gain"
        self._nu, self._gain = 2.0, None  # Nielsen's growth factor; the gain ratio of the step taken
        self.reason, self.converged, self.it = MAX_ITERATIONS_REASON, False, 0
        self.all_active = bool(active.all())
        self.n_active = int(active.sum())
        self.rejected = np.zeros(self.n_slots, dtype=bool)
        self.robust_weights = None
        # after a line search that refused a step, trial points are evaluated without the Jacobian
        # first (the Jacobian then only at the step taken): a refused trial then costs its residuals
        # only. Same trials, same decisions, same numbers; only when the Jacobian is computed changes.
        self._refused_last = False
        self._dcost_prev = (None, None)  # the two previous accepted steps' cost decreases in this phase

    # ------------------------------------------------------------------ pieces
    # The linear algebra goes through hooks (_column_norms, augmented, _normal_system /
    # _normal_equations, _damped_solve) so a structured subclass can keep J in blocks and eliminate
    # per-image unknowns (robocal.calib.schur) or accumulate J^T J per block of poses without J
    # (robocal.calib._normal) while the iteration and its stop rules stay these.
    def _column_norms(self, J) -> np.ndarray:
        """Norms (n,) of the Jacobian's columns (the column scaling)."""
        return np.sqrt(np.einsum("ij,ij->j", J, J))

    def _n_columns(self, J) -> int:
        return J.shape[1]

    def _normal_equations(self):
        """(G, g, max(diag G)) of the scaled, weighted active system: G = Ja^T Ja, g = Ja^T ra."""
        G, g = self._normal_system()
        return G, g, float(G.diagonal().max())

    @staticmethod
    def _damped_solve(G, shift, g) -> np.ndarray:
        """``(G + shift I)^-1 g`` by Cholesky; numpy.linalg.LinAlgError when not positive definite."""
        A = G.copy()
        A.ravel()[::len(A) + 1] += shift  # a view of the copy's diagonal
        return cholesky_solve(cholesky_factor(A, overwrite=True), g)

    def _initial_robust_weights(self, r):
        pose_norm = pose_norms(self.pose_of_row, r, self.n_slots)[:self.n_poses]
        if self.f_scale is None:
            med = np.median(pose_norm)
            self.f_scale = med + 3.0 * max(1.4826 * np.median(np.abs(pose_norm - med)), 1e-12)
        self.weights[:self.n_poses] = robust_weights(pose_norm, self.loss, self.f_scale)

    def augmented(self, st, with_jac=True):
        """Residuals (and Jacobian) with the optional prior rows on the model parameters."""
        rr, JJ, _ = self.problem.evaluate(st, jacobian=with_jac)
        if not self.prior_weight:
            return rr, JJ
        geom, cs = self.geom, self.col_scale
        pr = self.prior_weight * cs[geom] * (self.p_start - self.problem.variable_values(st, "geometry"))
        rr = np.concatenate([rr, pr])
        if with_jac:
            Jp = np.zeros((int(geom.sum()), self.n))
            Jp[:, np.flatnonzero(geom)] = np.diag(self.prior_weight * cs[geom])
            JJ = np.vstack([JJ, Jp])
        return rr, JJ

    def _cost(self, r) -> float:
        """0.5 * sum(w r^2) over the rows (the weights are all 1 unless robust, prior or dropped poses)."""
        if self.weighted:
            return 0.5 * float(np.sum(self.w_rows * r**2))
        return 0.5 * float(r @ r)

    def row_weights(self):
        w = self.weights[self.pose_of_row]
        return np.concatenate([w, np.ones(int(self.geom.sum()))]) if self.prior_weight else w

    def _scaled_system(self):
        """Scaled, weighted active Jacobian Ja and residuals ra."""
        active, cs = self.active, self.col_scale
        if self.weighted and not np.all(self.w_rows == 1.0):
            sw = np.sqrt(self.w_rows)
            return (self.J[:, active] * sw[:, None]) / cs[active], self.r * sw
        # every row of weight 1 (e.g. only a prior made the problem "weighted"): multiplying by 1 changes
        # no bit, so skip it; the column selection is a copy already, scaled in place
        if self.all_active:
            return self.J / cs, self.r
        Ja = self.J[:, active]
        Ja /= cs[active]
        return Ja, self.r

    def _normal_system(self):
        """Scaled, weighted normal matrix G = Ja^T Ja (n_a, n_a) and gradient g = Ja^T ra (n_a,)."""
        Ja, ra = self._scaled_system()
        return Ja.T @ Ja, Ja.T @ ra

    # ------------------------------------------------------------------ iteration
    def run_phase(self, first_iteration: int, max_iterations: int) -> None:
        """Iterate until a stop rule fires or ``max_iterations`` steps are taken."""
        for it in range(first_iteration, first_iteration + max_iterations):
            self.it = it
            if self._iteration(it):
                break

    def _iteration(self, it) -> bool:
        """One accepted step (True when a stop rule fired)."""
        G = g_max = step_s = None
        if self.method == "svd":
            Ja, ra = self._scaled_system()
            g = Ja.T @ ra
            U, s, Vt = np.linalg.svd(Ja, full_matrices=False)
            keep = s > self.rcond * s[0]
            step_s = Vt.T @ np.where(keep, (U.T @ ra) / np.where(keep, s, 1.0), 0.0)
            s_max = s[0]
        else:
            # damped normal equations (G + lam * max(diag G) I) step = g, by Cholesky
            # (the scaled copy of J is not kept while the line search evaluates trial Jacobians)
            G, g, g_max = self._normal_equations()
            s_max = math.sqrt(g_max)
        g_inf = float(np.abs(g).max()) if g.size else 0.0
        if g_inf <= 1e-14 * max(1.0, s_max * math.sqrt(2 * self.cost)):
            return self._stop("gradient is zero")
        found = self._line_search(G, g, g_max, step_s)
        if found is None:
            if self.method == "svd":  # only the kept directions can be stepped along
                Ur = np.where(keep, U.T @ ra, 0.0)
                g_inf = float(np.abs(Vt.T @ (s * Ur)).max())
                predicted = 0.5 * float(Ur @ Ur)
            else:
                predicted = self._predicted_reduction(G, g, g_max)
            optimality = g_inf / max(s_max * math.sqrt(2 * self.cost), 1e-300)
            rel = predicted / max(self.cost, 1e-300)
            return self._stop(*no_step_reason(optimality, rel))
        trial, r_t, J_t, step_s = found
        self.state, self.r, self.J = trial, r_t, J_t
        if self.robust:
            pose_norm = pose_norms(self.pose_of_row, self.r[:len(self.pose_of_row)], self.n_slots)[:self.n_poses]
            self.weights[:self.n_poses] = robust_weights(pose_norm, self.loss, self.f_scale)
            self.w_rows = self.row_weights()
        new_cost = self._cost(self.r)
        if self.growing_scale is not None:
            self._raise_column_scales()
        self._lower_damping()
        if self.progress:
            self.progress(it, new_cost)
        dcost, self.cost = self.cost - new_cost, new_cost
        return self._converged_after_step(dcost, step_s)

    def _raise_column_scales(self) -> None:
        """Raise the scale of each :attr:`growing_scale` column to its current norm where that is
        larger (Moré's rule, MINPACK's ``lmder``; module docstring)."""
        m = self.growing_scale
        self.col_scale[m] = np.maximum(self.col_scale[m], self._column_norms(self.J)[m])

    def _lower_damping(self) -> None:
        """After a taken step: /10 (``tenfold``) or Nielsen's factor of its gain ratio (``gain``)."""
        if self.gain_damping and self._gain is not None:
            self.lam = max(self.lam * max(1.0 / 3.0, 1.0 - (2.0 * self._gain - 1.0) ** 3), 1e-12)
            self._nu = 2.0
        else:
            self.lam = max(self.lam / 10.0, 1e-12)

    def _raise_damping(self) -> None:
        """After a refused trial (or a matrix that is not positive definite): x10, or x nu (nu doubles)."""
        if self.gain_damping:
            self.lam *= self._nu
            self._nu *= 2.0
        else:
            self.lam *= 10.0

    def _predicted_reduction(self, G, g, g_max) -> float:
        """Cost reduction 0.5 g^T G^-1 g the (barely damped) Gauss-Newton step predicts (inf if singular)."""
        try:
            return 0.5 * float(g @ self._damped_solve(G, 1e-12 * g_max, g))
        except np.linalg.LinAlgError:
            return math.inf

    def _line_search(self, G, g, g_max, step_s):
        """A step that does not raise the cost: LM raises the damping, SVD halves the step (30 tries).
        Returns (trial state, its r, its J, scaled step) or None."""
        for attempt in range(30):
            if self.method == "lm":
                try:  # G + lam * max(diag G) * I: only the diagonal changes
                    step_s = self._damped_solve(G, self.lam * g_max, g)
                except np.linalg.LinAlgError:
                    self._raise_damping()
                    continue
            if self.all_active:
                step = step_s / self.col_scale
            else:
                step = np.zeros(self.n)
                step[self.active] = step_s / self.col_scale[self.active]
            trial = self.problem.retract(self.state, step)
            lazy = self._refused_last or attempt > 0
            # with the Jacobian unless steps are being refused: an accepted step needs it next
            r_t, J_t = self.augmented(trial, with_jac=not lazy)
            c_t = self._cost(r_t)
            if c_t < self.cost:  # a step that changes nothing is no step: the stationarity check decides
                if lazy:
                    r_t, J_t = self.augmented(trial)
                self._refused_last = attempt > 0
                if self.gain_damping and self.method == "lm":
                    # the LM step solves (G + mu I) s = g: its model predicts 0.5 s^T (g + mu s)
                    predicted = 0.5 * float(step_s @ (g + (self.lam * g_max) * step_s))
                    self._gain = (self.cost - c_t) / predicted if predicted > 0 else None
                return trial, r_t, J_t, step_s
            if self.method == "svd":
                step_s = 0.5 * step_s  # backtracking
            else:
                self._raise_damping()
        return None

    def _converged_after_step(self, dcost, step_s) -> bool:
        cost = self.cost
        dcost_prev, dcost_prev2 = self._dcost_prev
        self._dcost_prev = (dcost, dcost_prev)
        if self.lam >= 1.0:
            # a heavily damped step (a short gradient step) is small however far the minimum is:
            # its size and cost change say nothing about convergence
            return False
        if abs(dcost) <= self.ftol * max(cost, 1e-300):
            return self._stop("relative cost reduction below ftol")
        # statistical criterion: the last step changed chi^2 by less than chi2_tol residual
        # variances AND the changes still to come (the geometric tail at the observed contraction
        # ratio) add up to less than that, so the estimate is within a small fraction of a standard
        # deviation of the optimum also where Gauss-Newton converges only linearly (module docstring)
        s2 = 2.0 * cost / max(len(self.r) - self.n_active, 1)
        if self.lam <= 1e-3 and 2.0 * max(abs(dcost), remaining_decrease_bound(dcost, dcost_prev, dcost_prev2)) \
                <= self.chi2_tol * max(s2, 1e-300):
            return self._stop(chi2_reason(self.chi2_tol))
        if math.sqrt(float(step_s @ step_s)) <= self.xtol * (1.0 + math.sqrt(2.0 * cost)):
            return self._stop("step below xtol")
        return False

    def _stop(self, reason, converged: bool = True) -> bool:
        self.reason, self.converged = reason, converged
        return True

    def drop_outliers(self, threshold) -> bool:
        """After a robust phase: give the poses weighted below ``threshold`` weight 0 and the rest 1
        (plain least squares follows). False when there is none to drop."""
        self.rejected = self.weights < threshold
        if not self.rejected.any():
            return False
        self.robust_weights, self.robust, self.weighted = self.weights.copy(), False, True
        self.weights = (~self.rejected).astype(float)
        self.w_rows = self.row_weights()
        self.cost = self._cost(self.r)
        self.lam, self._nu = 1e-3, 2.0
        self._dcost_prev = (None, None)
        self.reason, self.converged = MAX_ITERATIONS_REASON, False
        return True
