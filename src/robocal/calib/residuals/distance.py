"""Distances between the same target at two poses (ballbar, length artefact): no instrument frame needed."""

from __future__ import annotations

import numpy as np

from ..errors import ProblemError
from .base import ResidualBlock
from .chain import TargetChain

__all__ = ["DistanceResidual"]


class DistanceResidual(ResidualBlock):
    """``r = (d_measured - |p(a, k) - p(b, k)|) / sigma``, one row per pair.

    chain: the :class:`TargetChain`; pairs: sequence of ``(pose_a, pose_b, target_index,
    distance_mm)``; sigma [mm]. Row label: ``pose_a``.
    """

    kind = "distance"

    def __init__(self, chain: TargetChain, pairs, sigma: float | None = None):
        pairs = [tuple(p) for p in pairs]
        N, K = len(chain.q), chain.n_points
        for i, (a, b, k, d) in enumerate(pairs):
            if not (0 <= a < N and 0 <= b < N and 0 <= k < K) or not np.isfinite(d):
                raise ProblemError(f"distances[{i}]: poses must be in 0..{N - 1}, target in 0..{K - 1}, distance finite")
        a, b, k, d = (np.array(v) for v in zip(*pairs)) if pairs else (np.zeros(0),) * 4
        self.chain = chain
        self.a, self.b, self.k = a.astype(int), b.astype(int), k.astype(int)
        self.distance = d.astype(float)
        super().__init__(chain.parameter_blocks, self.a, sigma)

    def evaluate(self, ev, jacobian):
        out = self.chain.evaluate(ev)
        a, b, k, w = self.a, self.b, self.k, self.weight
        diff = out.points[a, k] - out.points[b, k]
        dist = np.linalg.norm(diff, axis=1)
        r = (self.distance - dist) * w
        if not jacobian:
            return r, None
        u = diff / dist[:, None]
        return r, {blk: np.einsum("ni,nic->nc", u, J[a, k] - J[b, k]) * w for blk, J in out.jac.items()}

    @classmethod
    def example(cls, rng):
        from .examples import example_chain, example_elastic_chain, example_full_elastic_chain

        pairs = [(0, 1, 0, 500.0), (2, 5, 1, 800.0), (4, 3, 0, 100.0)]
        return [cls(factory(rng, n_poses=6, n_stations=1), pairs, sigma=0.01)
                for factory in (example_chain, example_elastic_chain, example_full_elastic_chain)]
