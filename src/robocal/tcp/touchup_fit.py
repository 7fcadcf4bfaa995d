"""The touch-up TCP fit (thesis (4-4)) as a problem of the calibration core.

``R_i t + p_i = P_ref`` for N flange poses ``T_base_flange = [R_i | p_i]`` [mm]: a tool-point block
``tcp`` (``t`` in the flange frame, mm) and a fixed-point block ``P_ref`` (base frame, mm), read by
one :class:`~robocal.calib.residuals.FixedPointResidual`, solved by the core's Levenberg-Marquardt
(:func:`robocal.calib.solve`). The fit is linear, so the solver reaches the least-squares optimum
to rounding in a few iterations from any start; it also returns what every core solve returns: the
covariance of (t, P_ref) (scaled by the fitted residual variance, 3N - 6 degrees of freedom, unless
``sigma_mm`` is given), and the identifiability report (which directions the poses cannot
determine, and why).
"""

from __future__ import annotations

import numpy as np

from ..calib import Problem, solve
from ..calib.blocks import VectorBlock
from ..calib.residuals import FixedPointResidual

__all__ = ["touchup_problem", "fit_touchup"]

TOOL_NAMES = ("tcp.x", "tcp.y", "tcp.z")
POINT_NAMES = ("P_ref.x", "P_ref.y", "P_ref.z")


def touchup_problem(T_base_flange, tcp0=None, point0=None, sigma_mm: float | None = None) -> Problem:
    """The core problem of (4-4): blocks ``tcp`` and ``P_ref`` (both ranked as targets for the
    identifiability analysis), one fixed-point residual block.

    T_base_flange (N, 4, 4) [mm]; tcp0 (3,) starting TCP (default the flange origin); point0 (3,)
    starting reference point (default the mean flange origin); sigma_mm: pose position noise.
    """
    T = np.asarray(T_base_flange, dtype=float)
    t0 = np.zeros(3) if tcp0 is None else np.asarray(tcp0, dtype=float)
    P0 = T[:, :3, 3].mean(axis=0) if point0 is None else np.asarray(point0, dtype=float)
    tool = VectorBlock("tcp", TOOL_NAMES, ["mm"] * 3, t0, group="targets")
    point = VectorBlock("P_ref", POINT_NAMES, ["mm"] * 3, P0, group="targets")
    return Problem([tool, point], [FixedPointResidual(T, tool, point, sigma=sigma_mm)])


def fit_touchup(T_base_flange, sigma_mm: float | None = None):
    """Solve :func:`touchup_problem` to the least-squares optimum; returns the core's
    :class:`~robocal.calib.solve.CalibrationResult` (``result.value("tcp")``, ``value("P_ref")``,
    ``std``, ``covariance``, ``identifiability``).

    The relative-cost and chi-square stopping rules are off (a linear fit is iterated until the
    step is below ``xtol`` or no step lowers the cost), so the result is the exact linear
    least-squares solution, not one within a fraction of a standard deviation of it.
    """
    return solve(touchup_problem(T_base_flange, sigma_mm=sigma_mm), ftol=0.0, chi2_tol=0.0)
