"""The LM loop's chi-square stop on a problem where Gauss-Newton converges only linearly (a large
residual with strong curvature, issue 25 item 2): a small last step must not be read as "within a
small fraction of a residual variance of the minimum" when the steps shrink slowly.

The problem (Nocedal & Wright, *Numerical Optimization*, 2nd ed., sec. 10.3, the large-residual
example): per pose, the rows ``x + 1`` and ``c x^2 + x - 1``. For ``c < 1`` the minimum is x = 0
(gradient ``(x + 1) + (c x^2 + x - 1)(2 c x + 1)`` vanishes there, curvature ``2 - 2c`` per pose)
with cost ``n_poses`` (each pose leaves 1 + 1 squared); near it the Gauss-Newton iteration
contracts as ``x -> c x`` (the dropped term ``r2 r2'' = -2c`` is c times ``J^T J = 2``).
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from robocal.calib import solve
from robocal.calib._iterate import remaining_decrease_bound
from robocal.sim.solver_problems import C, N_POSES, X0, excess_in_variances, large_residual_problem

_problem = large_residual_problem
_excess_in_variances = excess_in_variances


def test_the_minimum_is_where_the_docstring_says():
    from scipy.optimize import least_squares

    def fun(p):
        return np.tile([p[0] + 1.0, C * p[0] ** 2 + p[0] - 1.0], N_POSES)

    sol = least_squares(fun, [X0], method="lm", xtol=1e-15, ftol=1e-15, gtol=1e-15, max_nfev=100000)
    assert abs(sol.x[0]) < 1e-4 and abs(sol.cost - N_POSES) < 1e-8


def test_chi_square_stop_needs_the_remaining_decrease_not_the_last_step():
    """Stopped by the chi-square rule, the fit must be within chi2_tol residual variances (x2 for the
    asymptotic estimate) of the minimum. The old rule (last change below chi2_tol) stopped after 44
    iterations at x = 0.0120, 0.0128 residual variances above it (13 x chi2_tol); the rule on the
    estimated remainder after 90 at x = 0.0046, 0.0012 above it (sigma of x: 0.158)."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        res = solve(_problem(), max_iterations=1000, auto_identifiable=False)
    excess, x = _excess_in_variances(res)
    assert res.converged, res.reason
    assert "chi-square" in res.reason, res.reason
    assert excess <= 2e-3, (excess, x, res.iterations, res.reason)
    sigma_x = 1.0 / np.sqrt(N_POSES * (2 - 2 * C))   # 1/sqrt(curvature) at the minimum (unit s^2)
    assert abs(x) <= 0.05 * sigma_x, (x, sigma_x)


def test_the_default_cap_reports_the_slow_fit_as_not_converged():
    with pytest.warns(Warning, match="did not converge"):
        res = solve(_problem(), auto_identifiable=False)   # 50 iterations: x ~ 0.98^50 ~ 0.36 left
    assert not res.converged and "maximum iterations" in res.reason


@pytest.mark.parametrize("d,expected", [
    ((1.0, None, None), np.inf),      # a phase's first steps say nothing about the rate
    ((1.0, 2.0, None), np.inf),
    ((1.0, 0.5, 1.0), np.inf),        # growing changes: no bound
    ((1.0, 1.0, 2.0), np.inf),
    ((1.0, 2.0, 4.0), 1.0),           # ratio 1/2: 1/2 + 1/4 + ... = 1
    ((0.98, 1.0, 1.0 / 0.98), 0.98 * 49.0),  # ratio 0.98: 49 more steps' worth
    ((1e-6, 1.0, 2.0), 1e-6),         # quadratic convergence: the slower ratio (1/2) counts
    ((1e-4, 0.0074, 0.0077), 1e-4 * (74 / 77) / (3 / 77)),  # one short step in a slow valley: not a contraction
])
def test_remaining_decrease_bound_is_the_geometric_tail(d, expected):
    got = remaining_decrease_bound(*d)
    if np.isinf(expected):
        assert np.isinf(got)
    else:
        assert got == pytest.approx(expected, rel=1e-3)
