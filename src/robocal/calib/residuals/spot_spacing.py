"""A known distance between two fixed points of one block (the ruled spacing of plate targets).

The closed chain (METHODS.md section 3) has no length reference of its own: every length of the
robot, the laser mount and the spots can grow by the same factor and every ray still meets its
spot. One known distance -- two targets of the plate a ruled ``d`` apart -- fixes the scale.
"""

from __future__ import annotations

import numpy as np

from ..errors import ProblemError
from .base import ResidualBlock

__all__ = ["PointSpacingResidual"]


class PointSpacingResidual(ResidualBlock):
    """``r = (d - |P_a - P_b|) / sigma``, one row per pair (no pose: row label -1).

    points: a block whose value is S points (S, 3) [mm] (additive, e.g. a ``VectorBlock``);
    pairs: (m, 2) indices of the points; distances: (m,) or a scalar, the known distances [mm];
    sigma [mm]: the uncertainty of the known distance.
    """

    kind = "spacing"

    def __init__(self, points, pairs, distances, sigma: float | None = None):
        self.pairs = np.asarray(pairs, dtype=int).reshape(-1, 2)
        S = points.size // 3
        if self.pairs.size and (self.pairs.min() < 0 or self.pairs.max() >= S):
            raise ProblemError(f"spacing: point index out of range 0..{S - 1}")
        if np.any(self.pairs[:, 0] == self.pairs[:, 1]):
            raise ProblemError("spacing: a pair names the same point twice")
        self.distances = np.broadcast_to(np.asarray(distances, dtype=float), (len(self.pairs),)).copy()
        if not np.all(self.distances > 0):
            raise ProblemError(f"spacing: distances must be positive [mm], got {self.distances}")
        self.points = points
        super().__init__((points,), np.full(len(self.pairs), -1), sigma)

    def evaluate(self, ev, jacobian):
        P = np.asarray(ev[self.points], dtype=float).reshape(-1, 3)
        diff = P[self.pairs[:, 0]] - P[self.pairs[:, 1]]
        dist = np.linalg.norm(diff, axis=1)
        w = self.weight
        r = (self.distances - dist) * w
        if not jacobian or not ev.wants(self.points):
            return r, ({} if jacobian else None)
        u = diff / dist[:, None]
        m = len(self.pairs)
        J = np.zeros((m, P.shape[0], 3))
        J[np.arange(m), self.pairs[:, 0]] = u * w
        J[np.arange(m), self.pairs[:, 1]] = -u * w
        return r, {self.points: J.reshape(m, -1)}

    def errors(self, r) -> np.ndarray:
        """|known - fitted distance| [mm] per pair."""
        return np.abs(np.asarray(r)) * (self.sigma or 1.0)

    @classmethod
    def example(cls, rng):
        from ..blocks import VectorBlock

        pts = VectorBlock("spots", [f"s{k}.{c}" for k in range(4) for c in "xyz"], ["mm"] * 12, rng.normal(0, 100, 12))
        return cls(pts, [(0, 1), (1, 2), (3, 0)], rng.uniform(20, 80, 3), sigma=0.02)
