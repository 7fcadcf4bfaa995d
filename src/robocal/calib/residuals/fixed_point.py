"""A tool point, carried by measured flange poses, that touches one fixed point (touch-up TCP).

``R_i t + p_i = P`` (METHODS.md 5, (4-4)): the flange poses ``T_i = [R_i | p_i]`` are measured
(read from the controller), the tool point ``t`` (flange frame) and the fixed point ``P`` (base
frame) are parameter blocks.
"""

from __future__ import annotations

import numpy as np

from ..errors import ProblemError
from .base import ResidualBlock

__all__ = ["FixedPointResidual"]


class FixedPointResidual(ResidualBlock):
    """``r_i = -(R_i t + p_i - P) / sigma``, 3 rows per pose (the measured value is 0).

    T_base_flange: (N, 4, 4) flange poses [mm]; tool: a block whose value is the tool point
    (3,) [mm] in the flange frame; point: a block whose value is the fixed point (3,) [mm] in the
    base frame (both additive, e.g. :class:`~robocal.calib.blocks.VectorBlock`); sigma [mm].
    Prediction derivatives: ``R_i`` w.r.t. ``t``, ``-I`` w.r.t. ``P``.
    """

    kind = "fixed_point"

    def __init__(self, T_base_flange, tool, point, sigma: float | None = None):
        T = np.asarray(T_base_flange, dtype=float)
        if T.ndim != 3 or T.shape[1:] != (4, 4):
            raise ProblemError(f"T_base_flange: expected shape (N, 4, 4), got {T.shape}")
        for blk in (tool, point):
            if blk.size != 3:
                raise ProblemError(f"{blk.name}: a point block needs 3 variables, got {blk.size}")
        self.R, self.p = T[:, :3, :3].copy(), T[:, :3, 3].copy()
        self.tool, self.point = tool, point
        super().__init__((tool, point), np.repeat(np.arange(len(T)), 3), sigma)

    def predicted(self, t, P) -> np.ndarray:
        """``R_i t + p_i - P`` (N, 3) [mm]."""
        return np.einsum("nij,j->ni", self.R, np.ravel(t)) + self.p - np.ravel(P)

    def evaluate(self, ev, jacobian):
        w = self.weight
        r = -self.predicted(ev[self.tool], ev[self.point]).ravel() * w
        if not jacobian:
            return r, None
        jac = {}
        if ev.wants(self.tool):
            jac[self.tool] = self.R.reshape(-1, 3) * w
        if ev.wants(self.point):
            jac[self.point] = np.tile(-np.eye(3), (len(self.R), 1)) * w
        return r, jac

    def errors(self, r):
        """Distances [mm] of the tool point from the fixed point, one per pose."""
        return np.linalg.norm((np.asarray(r) * (self.sigma or 1.0)).reshape(-1, 3), axis=1)

    @classmethod
    def example(cls, rng):
        from ...transforms import so3_exp
        from ..blocks import VectorBlock

        T = np.tile(np.eye(4), (5, 1, 1))
        T[:, :3, :3] = so3_exp(rng.normal(0, 0.7, (5, 3)))
        T[:, :3, 3] = rng.normal(0, 500, (5, 3))
        tool = VectorBlock("tcp", ["tcp.x", "tcp.y", "tcp.z"], ["mm"] * 3, rng.normal(0, 100, 3))
        point = VectorBlock("P_ref", ["P_ref.x", "P_ref.y", "P_ref.z"], ["mm"] * 3, rng.normal(0, 500, 3))
        return cls(T, tool, point, sigma=0.1)
