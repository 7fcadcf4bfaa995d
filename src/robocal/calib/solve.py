"""Solvers over any :class:`~robocal.calib.core.Problem` (parameter blocks + residual blocks, e.g.
a :class:`~robocal.calib.problem.CalibrationProblem`), and the result object.

* :func:`solve_lm` -- Levenberg-Marquardt with the analytic Jacobian, Jacobian column scaling
  (so millimetres and radians are comparable, like ``x_scale='jac'``), optional robust loss
  (Huber, Cauchy) by iteratively reweighted least squares per pose, and an outlier report;
* ``method="svd"`` -- Gauss-Newton steps solved by truncated SVD ((3-9), (3-10) of METHODS.md):
  singular values below ``rcond * s_max`` are dropped instead of damped.

Both re-linearize around the current state every iteration; frames are updated by the problem's
``retract`` so they stay valid rotations.
"""

from __future__ import annotations
from ..errors import RobocalWarning

import math
import warnings
from dataclasses import dataclass, field

import numpy as np
from scipy.linalg.lapack import dsyev

from ._cholesky import cholesky_factor, cholesky_inverse, cholesky_solve
from . import _lm_compiled, _normal
from ._iterate import DampedGaussNewton, pose_norms
from .core import Problem
from .identifiability import IdentifiabilityReport, analyse_identifiability

__all__ = ["CalibrationResult", "solve", "NotConvergedWarning", "not_converged_message"]


class NotConvergedWarning(RobocalWarning):
    """The solver stopped without meeting its convergence criteria (raised by :func:`solve`; the
    message names the reason, the iterations and the condition number)."""


def not_converged_message(result) -> str:
    """One line: why a solve did not converge, with the condition number of its Jacobian."""
    return (f"the solver did not converge: {result.reason} after {result.iterations} iterations; condition "
            f"number {result.condition_number:.3g}, rank {result.rank}/{len(result.names)}; the result may be "
            "far from the optimum (more iterations, better starting values or fewer free parameters)")


@dataclass
class CalibrationResult:
    """Outcome of a calibration.

    names, units: of the state variables (the free variables of the parameter blocks, e.g. free
    model parameters, base, targets, planes); values (n,) final values in those units (each block's
    ``local``: a frame as rotation vector and origin, targets the points); initial (n,) the same
    at the start; std (n,) standard deviations (NaN where not identifiable); covariance (n, n).
    state: final state (a :class:`~robocal.calib.problem.State` for a ``CalibrationProblem``, a
    tuple of block values otherwise; ``value(block)`` picks one); problem: the problem solved;
    model: the calibrated :class:`RobotModel` (problems with a robot geometry block).
    residuals_before / residuals_after: (M,) weighted residual vectors; rms_before / rms_after
    per measured point (mm, unweighted) where point measurements exist.
    iterations, converged, reason, rank, condition_number, identifiability, outliers (list of
    dicts: pose, residual_mm, weight, reason).
    """

    names: tuple
    units: tuple
    values: np.ndarray
    initial: np.ndarray
    std: np.ndarray
    covariance: np.ndarray
    state: object
    problem: object
    residuals_before: np.ndarray
    residuals_after: np.ndarray
    iterations: int
    converged: bool
    reason: str
    rank: int
    condition_number: float
    sigma0: float
    identifiability: IdentifiabilityReport
    outliers: list = field(default_factory=list)
    point_errors_before: np.ndarray | None = None
    point_errors_after: np.ndarray | None = None
    #: (M, n) final prediction Jacobian (unweighted by robust losses); see :attr:`jacobian`
    _jacobian: np.ndarray | None = field(default=None, repr=False)

    @property
    def jacobian(self) -> np.ndarray | None:
        """(M, n) final prediction Jacobian (unweighted by robust losses). A solve on normal equations
        (point-only problems, :mod:`robocal.calib._normal`) never forms it: it is evaluated here on
        first use (``problem.evaluate`` at the final state) and kept."""
        if self._jacobian is None and self.problem is not None and self.state is not None:
            self._jacobian = self.problem.evaluate(self.state)[1]
        return self._jacobian

    @jacobian.setter
    def jacobian(self, J) -> None:
        self._jacobian = J

    @property
    def model(self):
        """The calibrated :class:`RobotModel` (base = the first station's frame), built on demand."""
        return self.problem.model_at(self.state)

    def value(self, block):
        """The final value of a parameter block (object or name)."""
        return self.problem.value(self.state, block)

    @property
    def rms_before(self) -> float:
        e = self.point_errors_before
        return float(np.sqrt(np.mean(e**2))) if e is not None and e.size else float("nan")

    @property
    def rms_after(self) -> float:
        e = self.point_errors_after
        return float(np.sqrt(np.mean(e**2))) if e is not None and e.size else float("nan")

    def parameter_table(self) -> list[dict]:
        """One dict per variable: name, unit, initial, value, change, std, identifiable."""
        ident = set(self.identifiability.identifiable)
        rows = []
        for i, n in enumerate(self.names):
            rows.append({"name": n, "unit": self.units[i], "initial": float(self.initial[i]),
                         "value": float(self.values[i]), "change": float(self.values[i] - self.initial[i]),
                         "std": float(self.std[i]), "identifiable": n in ident})
        return rows

    def summary(self) -> str:
        lines = [f"{'converged' if self.converged else 'NOT CONVERGED'} after {self.iterations} iterations ({self.reason}); "
                 f"rank {self.rank}/{len(self.names)}, condition {self.condition_number:.3g}",
                 f"point RMS before {self.rms_before:.4f} mm, after {self.rms_after:.4f} mm"]
        if self.identifiability.dropped:
            lines.append("not identifiable from these data (held at their initial values):")
            lines += [f"  {d['name']}: {d['why']}" for d in self.identifiability.dropped]
        if self.outliers:
            lines.append(f"{len(self.outliers)} pose(s) down-weighted as outliers: "
                         + ", ".join(str(o["pose"]) for o in self.outliers))
        return "\n".join(lines)


def solve(problem: Problem, *, method: str = "lm", loss: str = "linear", f_scale: float | None = None,
          max_iterations: int = 50, ftol: float = 1e-9, xtol: float = 1e-10, rcond: float = 1e-8,
          auto_identifiable: bool = True, prior_weight: float = 0.0, outlier_threshold: float = 0.5,
          reject_outliers: bool = True, chi2_tol: float = 1e-3, state0=None,
          progress=None, warn: bool = True) -> CalibrationResult:
    """Identify the problem's free variables (see :func:`_solve_once` for the arguments).

    warn: a :class:`NotConvergedWarning` when the fit did not converge (``result.converged`` says
    it either way). Callers that report convergence themselves pass False instead of changing the
    process's warning filters, which ``warnings.catch_warnings`` does for every thread at once (two
    calibrations in two threads could leave a filter of one behind for the whole process).

    With ``auto_identifiable`` the identifiable set is chosen at the starting point, and chosen
    again at the solution: a start far from the truth (a tool point guessed on the joint-6 axis,
    say) can hide parameters that the data do determine. If the set changes, the solve continues
    from the solution with the new set (at most three rounds).
    """
    kw = dict(method=method, loss=loss, f_scale=f_scale, max_iterations=max_iterations, ftol=ftol, xtol=xtol,
              rcond=rcond, auto_identifiable=auto_identifiable, prior_weight=prior_weight,
              outlier_threshold=outlier_threshold, reject_outliers=reject_outliers, chi2_tol=chi2_tol,
              progress=progress)
    res = _solve_once(problem, state0=state0, **kw)
    if auto_identifiable:
        res = _refine_identifiable(problem, res, state0, kw)
    if warn and not res.converged:
        warnings.warn(NotConvergedWarning(not_converged_message(res)), stacklevel=2)
    return res


def _refine_identifiable(problem, res, state0, kw):
    """Solve again from ``res`` while the identifiable set changes at the solution."""
    start = problem.initial_state() if state0 is None else state0
    for _ in range(2):
        if not res.identifiability.dropped:
            break
        J = _identifiability_matrix(problem, res)
        if not _dropped_may_have_become_identifiable(J, problem.names, res.identifiability):
            break
        quick = analyse_identifiability(J, problem.names, problem.blocks, explain=False)
        if set(quick.identifiable) == set(res.identifiability.identifiable):
            break
        ident = analyse_identifiability(J, problem.names, problem.blocks, column_blocks=problem.column_blocks)
        iters = res.iterations
        before, err_before = res.residuals_before, res.point_errors_before
        center = problem.variable_values(start, "geometry") if kw.get("prior_weight") else None
        res = _solve_once(problem, state0=res.state, ident=ident, prior_center=center, **kw)
        res.iterations += iters
        res.residuals_before, res.point_errors_before = before, err_before
        res.initial = problem.initial_values() if state0 is None else _state_values(problem, start)
    return res


def _identifiability_matrix(problem, res):
    """What the identifiability analysis of ``res``'s final state reads: its Jacobian, or for a solve on
    normal equations the R factor of the Jacobian's QR built per block of poses (same verdicts,
    n x n memory; :meth:`robocal.calib._normal.PointNormalEquations.r_factor`)."""
    if res._jacobian is None and _normal.supports(problem):
        return _normal.PointNormalEquations(problem).r_factor(res.state)[2]
    return res.jacobian


def _dropped_may_have_become_identifiable(J, names, ident, screen: float = 1e-4) -> bool:
    """Cheap screen before re-running the identifiability analysis at the solution.

    Projects each held parameter's (unit) column on the kept columns through the Cholesky factor
    of their Gram matrix: if every held column stays a combination of kept ones to better than
    ``screen`` (far above the ~1e-8 this squared-conditioning shortcut can resolve), nothing
    changed; otherwise the full QR analysis decides.
    """
    if not ident.dropped:
        return False
    idx = {n: i for i, n in enumerate(names)}
    kept = [idx[n] for n in ident.identifiable]
    held = [idx[n] for n in ident.dropped_names]
    norms = np.linalg.norm(J[:, kept + held], axis=0)
    if np.any(norms == 0):
        return bool(np.any(norms[len(kept):] > 0))
    K = J[:, kept] / norms[:len(kept)]
    D = J[:, held] / norms[len(kept):]
    try:
        c = cholesky_factor(K.T @ K)
    except np.linalg.LinAlgError:
        return True
    coef = cholesky_solve(c, K.T @ D)
    independent2 = 1.0 - np.einsum("ij,ij->j", K.T @ D, coef)
    return bool(np.any(independent2 > screen**2))


def _state_values(problem: Problem, state) -> np.ndarray:
    return problem.variable_values(state)


def _solve_once(problem: Problem, *, method: str = "lm", loss: str = "linear", f_scale: float | None = None,
          max_iterations: int = 50, ftol: float = 1e-9, xtol: float = 1e-10, rcond: float = 1e-8,
          auto_identifiable: bool = True, prior_weight: float = 0.0, outlier_threshold: float = 0.5,
          reject_outliers: bool = True, chi2_tol: float = 1e-3, state0=None, progress=None, ident=None,
          prior_center=None) -> CalibrationResult:
    """Identify the problem's free variables.

    method: ``"lm"`` (Levenberg-Marquardt) or ``"svd"`` (truncated-SVD Gauss-Newton, (3-9, 3-10)).
    loss: ``"linear"``, ``"huber"`` or ``"cauchy"``; robust losses act per pose on the norm of the
        pose's weighted residuals with scale ``f_scale`` (default: 3 x the robust spread (MAD) of the
        first linear fit).
    auto_identifiable: analyse the Jacobian first and hold unidentifiable variables fixed
        (reported in ``result.identifiability``); otherwise all free variables are solved and rank
        deficiency shows in ``rank`` and ``condition_number``.
    prior_weight: optional Tikhonov weight pulling model parameters toward their initial values
        (per scaled unit); 0 disables it.
    outlier_threshold: poses whose robust weight ends below this are reported as outliers.
    reject_outliers: after the robust solve, drop the reported outliers and finish with plain
        least squares (their residuals are still reported; the covariance excludes them).
    chi2_tol: stop when an accepted step changes chi^2 by less than this many residual variances
        and so does the change still to come, estimated from the contraction of the last two steps
        (:func:`robocal.calib._iterate.remaining_decrease_bound`; the estimate is then within a
        few hundredths of a standard deviation of the optimum);
        ``ftol`` (relative cost change) and ``xtol`` (scaled step) stop it too.
    progress: optional callable ``progress(iteration, cost)``.
    ident: the identifiability verdicts to use (a later round); None: analysed at the start.
    prior_center: geometry values the prior pulls toward (a later round: the first round's start,
        so every round minimises the same cost).
    """
    if method not in ("lm", "svd"):
        raise ValueError(f"method must be 'lm' or 'svd', got {method!r}")
    state = problem.initial_state() if state0 is None else state0
    start_state = state
    # point-only problems: LM on normal equations summed per block of poses (J never formed)
    normal = method == "lm" and loss == "linear" and not prior_weight and _normal.supports(problem)
    evaluator = _normal.PointNormalEquations(problem) if normal else None
    # ... and, when its kernel is compiled (or worth compiling), the whole loop in compiled code
    # (the compiled loop has the default tenfold damping rule only)
    compiled = (normal and getattr(problem, "damping", "tenfold") == "tenfold"
                and _lm_compiled.use_compiled(problem, evaluator.m_rows // 3))
    labels = problem.labels
    J = None
    if compiled and (ident is not None or not auto_identifiable):
        r = None  # the compiled loop evaluates the start itself
    elif normal and (ident is not None or not auto_identifiable):
        r, ne = evaluator.evaluate(state)
    elif normal:  # the identifiability analysis reads the R factor of J's QR, built per block of poses
        r, ne, J = evaluator.r_factor(state)
    else:
        r, J, labels = problem.evaluate(state)
    M, n = (evaluator.m_rows if r is None else len(r)), problem.n_variables
    if M < n:
        raise ValueError(f"too few measurements: {M} residuals for {n} unknowns ({problem.n_poses} poses); "
                         f"add poses or fix parameters")
    first_round = ident is None
    if ident is None:
        ident = analyse_identifiability(J, problem.names, problem.blocks, column_blocks=problem.column_blocks) \
            if auto_identifiable else IdentifiabilityReport.trivial(problem.names)
    ident_set = set(ident.identifiable)
    active = np.array([nm in ident_set for nm in problem.names])
    r0 = None if r is None else r.copy()
    kw = dict(method=method, loss=loss, f_scale=f_scale, prior_weight=prior_weight, rcond=rcond, ftol=ftol,
              xtol=xtol, chi2_tol=chi2_tol, progress=progress)
    if compiled:
        J = None
        gn = _lm_compiled.CompiledPointLM(problem, state, labels, active, ftol=ftol, xtol=xtol, chi2_tol=chi2_tol,
                                          progress=progress)
    elif normal:
        J = None
        gn = _normal.NormalEquationsLM(problem, state, r, ne, labels, active, evaluator=evaluator, **kw)
    else:
        # the first round's growing column scales (robocal.calib._iterate: a lumped elastic model)
        growing = problem.growing_scale_columns() if first_round else None
        gn = DampedGaussNewton(problem, state, r, J, labels, active, prior_center=prior_center,
                               growing_scale=growing, **kw)
    gn.run_phase(1, max_iterations)
    if r0 is None:
        r0 = gn.r0
    if gn.robust and reject_outliers and gn.drop_outliers(outlier_threshold):
        # robust phase done: the down-weighted poses dropped, finish by plain least squares
        gn.run_phase(gn.it + 1, max_iterations)
    n_rows = len(gn.pose_of_row)
    weights = gn.weights if not gn.rejected.any() else np.where(gn.rejected, gn.robust_weights, 1.0)
    if compiled:
        state, r, J = gn.state, gn.r, None
        cov, std, rank, cond, sigma0 = _covariance_from_normal(problem, gn.J.JtJ, r, active, gn.col_scale, rcond,
                                                               gn.G, gn.G_inv)
    elif normal:
        state, r, J = gn.state, gn.r, None
        cov, std, rank, cond, sigma0 = _covariance_from_normal(problem, gn.J.JtJ, r, active, gn.col_scale, rcond)
    else:
        state, r, J = gn.state, gn.r[:n_rows], gn.J[:n_rows]
        cov, std, rank, cond, sigma0 = _covariance(problem, J, r, gn.weights[gn.pose_of_row], active, gn.col_scale,
                                                   rcond)
    outliers = _outlier_report(problem, gn, r, weights, outlier_threshold) if loss != "linear" else []
    r_before_pts = problem.point_errors(r0)
    r_after_pts = problem.point_errors(r)
    return CalibrationResult(
        names=problem.names, units=problem.units, values=_state_values(problem, state),
        initial=problem.initial_values() if state0 is None else _state_values(problem, start_state), std=std,
        covariance=cov, state=state, problem=problem, residuals_before=r0, residuals_after=r,
        iterations=gn.it, converged=gn.converged, reason=gn.reason, rank=rank, condition_number=cond, sigma0=sigma0,
        identifiability=ident, outliers=outliers, point_errors_before=r_before_pts, point_errors_after=r_after_pts,
        _jacobian=J)


def _covariance(problem: Problem, J, r, row_weights, active, col_scale, rcond):
    """Covariance (n, n) [NaN outside the identifiable set], std (n,), rank, condition number and
    the residual standard deviation sigma0, from the final weighted Jacobian J (M, n)."""
    n = J.shape[1]
    if np.all(row_weights == 1.0):  # multiplying by sqrt(1) = 1 changes no bit: skip it
        Ja, ra = (J if active.all() else J[:, active]), r
    else:
        sw = np.sqrt(row_weights)
        Ja = J[:, active] * sw[:, None]
        ra = r * sw
    dof = max(Ja.shape[0] - Ja.shape[1], 1)
    sigma0 = math.sqrt(float(ra @ ra) / dof)
    Js = Ja / col_scale[active]
    return _covariance_tail(problem, Js.T @ Js, sigma0, active, col_scale, rcond, n)


def _covariance_from_normal(problem: Problem, JtJ, r, active, col_scale, rcond, G=None, G_inv=None):
    """:func:`_covariance` from the unweighted-by-robust-loss normal matrix ``JtJ`` (n, n) = J^T J of
    the weighted Jacobian and the residuals r (M,) (all rows weight 1). ``G`` (n_a, n_a): its scaled
    active block if already formed, ``G_inv`` that block's inverse (the compiled LM loop gives both)."""
    n = len(JtJ)
    dof = max(len(r) - int(active.sum()), 1)
    sigma0 = math.sqrt(float(r @ r) / dof)
    if G is None:
        ca = col_scale[active]
        G = (JtJ if active.all() else JtJ[np.ix_(active, active)]) / np.outer(ca, ca)
    return _covariance_tail(problem, G, sigma0, active, col_scale, rcond, n, G_inv)


def _eigenvalues(G) -> np.ndarray:
    """Eigenvalues (n,) of the symmetric G (n, n), ascending (LAPACK ``dsyev`` directly: numpy's
    ``eigvalsh`` wraps the same work in ~40 us of checks on a ~1 ms solve)."""
    w, _, info = dsyev(G, compute_v=0)
    return w if info == 0 else np.linalg.eigvalsh(G)


def _covariance_tail(problem: Problem, G, sigma0, active, col_scale, rcond, n, G_inv=None):
    """Covariance, std, rank, condition and sigma0 from the scaled normal matrix G (n_a, n_a)
    (``G_inv``: its inverse when known)."""
    # singular values from the (small, scaled) normal matrix: s_i^2 are its eigenvalues
    s = np.sqrt(np.maximum(_eigenvalues(G)[::-1], 0.0))
    keep = s > max(rcond, 1e-7) * s[0] if s.size else s > 0  # squared: rcond below ~1e-8 is noise
    rank = int(np.sum(keep))
    cond = float(s[0] / s[-1]) if s.size and s[-1] > 0 else float("inf")
    if rank == len(s) and G_inv is not None:
        cov_s = G_inv
    elif rank == len(s):
        cov_s = cholesky_inverse(G)
    else:  # rank deficient (auto_identifiable off): pseudo-inverse on the resolvable directions
        ev, V = np.linalg.eigh(G)
        ev, V = ev[::-1], V[:, ::-1]
        cov_s = (V * np.where(keep, 1.0 / np.where(ev > 0, ev, 1.0), 0.0)) @ V.T
    scale_for_cov = 1.0 if problem.sigma_known else sigma0**2
    cov_a = cov_s / np.outer(col_scale[active], col_scale[active]) * scale_for_cov
    if len(cov_a) == n:  # every variable active: no NaN rows to place
        cov = cov_a
    else:
        cov = np.full((n, n), np.nan)
        cov[np.ix_(active, active)] = cov_a
    return cov, np.sqrt(np.diag(cov)), rank, cond, sigma0


def _outlier_report(problem: Problem, gn: DampedGaussNewton, r, weights, threshold) -> list:
    """One dict per pose whose robust weight ended below ``threshold``: pose, residual, weight, reason."""
    pose_norm = pose_norms(gn.pose_of_row, r, gn.n_slots)
    unit = problem.residual_scale
    out = []
    for p in np.flatnonzero(weights[:gn.n_poses] < threshold):
        out.append({"pose": int(p), "residual": float(pose_norm[p] * unit), "weight": float(weights[p]),
                    "reason": f"residual {pose_norm[p] * unit:.4g} is {pose_norm[p] / gn.f_scale:.1f} x the "
                              f"robust scale {gn.f_scale * unit:.4g} ({gn.loss} loss)"})
    return out
