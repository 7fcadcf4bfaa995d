"""A least-squares problem on which Gauss-Newton converges only linearly, for the solver's stopping
rule (tests/test_lm_stop_linear.py and docs/reliability.md "One convergence policy").

The problem (Nocedal & Wright, *Numerical Optimization*, 2nd ed., sec. 10.3, the large-residual
example): per pose, the rows ``x + 1`` and ``c x^2 + x - 1``. For ``c < 1`` the minimum is x = 0
(gradient ``(x + 1) + (c x^2 + x - 1)(2 c x + 1)`` vanishes there, curvature ``2 - 2c`` per pose)
with cost ``n_poses`` (each pose leaves 1 + 1 squared); near it the Gauss-Newton iteration
contracts as ``x -> c x`` (the dropped term ``r2 r2'' = -2c`` is c times ``J^T J = 2``).
"""

from __future__ import annotations

import numpy as np

from ..calib.blocks import VectorBlock
from ..calib.core import Problem
from ..calib.residuals.base import ResidualBlock

__all__ = ["C", "N_POSES", "X0", "LargeResidual", "excess_in_variances", "large_residual_problem"]

C = 0.99          # Gauss-Newton contraction factor near the minimum
N_POSES = 2000
X0 = 1.0


class LargeResidual(ResidualBlock, register=False):
    """Rows (x + 1, C x^2 + x - 1) per pose (a test problem, not a measurement kind)."""

    kind = "large_residual"

    def __init__(self, block, n_poses):
        self.block = block
        super().__init__((block,), np.repeat(np.arange(n_poses), 2), None)

    def evaluate(self, ev, jacobian):
        x = float(ev[self.block][0])
        n = self.n_rows // 2
        r = np.tile([x + 1.0, C * x * x + x - 1.0], n)
        if not jacobian:
            return r, None
        # jac is the derivative of the prediction: r(x + d) ~ r - jac d
        return r, {self.block: -np.tile([1.0, 2.0 * C * x + 1.0], n)[:, None]}


def large_residual_problem() -> Problem:
    """The problem with ``N_POSES`` poses, started at ``X0``."""
    block = VectorBlock("x", ["x"], ["1"], np.array([X0]))
    return Problem([block], [LargeResidual(block, N_POSES)], n_poses=N_POSES)


def excess_in_variances(res) -> tuple:
    """(cost - cost at the minimum) in residual variances, ``2 (C - C*) / s^2`` with
    ``s^2 = 2 C* / (M - n)``, and the solution's x: ``(excess, x)``."""
    x = float(res.values[0])
    cost = 0.5 * N_POSES * ((x + 1.0) ** 2 + (C * x * x + x - 1.0) ** 2)
    cost_min = float(N_POSES)
    s2 = 2.0 * cost_min / (2 * N_POSES - 1)
    return 2.0 * (cost - cost_min) / s2, x
