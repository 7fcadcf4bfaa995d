"""A target that lies on a plane (closed chains: a probe touching a plate)."""

from __future__ import annotations

import numpy as np

from ..blocks.planes import Planes, plane_normal_derivatives, plane_normals
from ..errors import ProblemError
from .base import ResidualBlock
from .chain import TargetChain

__all__ = ["PointOnPlaneResidual"]


class PointOnPlaneResidual(ResidualBlock):
    """``r = -(n . p - offset) / sigma``, one row per contact (the measured value is 0).

    chain: the :class:`TargetChain`; planes: the :class:`~robocal.calib.blocks.Planes` block;
    contacts: sequence of ``(pose, target_index, plane_index)``; sigma [mm].
    """

    kind = "plane"

    def __init__(self, chain: TargetChain, planes: Planes, contacts, sigma: float | None = None):
        contacts = [tuple(c) for c in contacts]
        N, K, L = len(chain.q), chain.n_points, planes.n_planes
        for i, (n, k, pl) in enumerate(contacts):
            if not (0 <= n < N and 0 <= k < K and 0 <= pl < L):
                raise ProblemError(f"on_plane[{i}]: pose, target or plane index out of range")
        n, k, pl = (np.array(v, dtype=int) for v in zip(*contacts)) if contacts else (np.zeros(0, int),) * 3
        self.chain, self.planes = chain, planes
        self.pose, self.target, self.plane = n, k, pl
        super().__init__(chain.parameter_blocks + (planes,), n, sigma)

    def evaluate(self, ev, jacobian):
        out = self.chain.evaluate(ev)
        pl = ev[self.planes][self.plane]
        nrm = plane_normals(pl)
        p = out.points[self.pose, self.target]
        w = self.weight
        r = -(np.einsum("ni,ni->n", nrm, p) - pl[:, 2]) * w
        if not jacobian:
            return r, None
        jac = {blk: np.einsum("ni,nic->nc", nrm, J[self.pose, self.target]) * w for blk, J in out.jac.items()}
        if ev.wants(self.planes):
            d_az, d_el = plane_normal_derivatives(pl)
            m = len(self.pose)
            Jp = np.zeros((m, self.planes.size))
            rows, c = np.arange(m), 3 * self.plane
            Jp[rows, c] = np.einsum("ni,ni->n", d_az, p)
            Jp[rows, c + 1] = np.einsum("ni,ni->n", d_el, p)
            Jp[rows, c + 2] = -1.0
            jac[self.planes] = Jp * w
        return r, jac

    @classmethod
    def example(cls, rng):
        from .examples import example_chain, example_elastic_chain, example_full_elastic_chain

        contacts = [(0, 0, 0), (1, 1, 0), (3, 0, 1), (5, 1, 1)]
        return [cls(factory(rng, n_poses=6, n_stations=2), Planes([[0.3, 1.2, 800.0], [-2.0, 0.2, -100.0]]),
                    contacts, sigma=0.02) for factory in (example_chain, example_elastic_chain, example_full_elastic_chain)]
