"""3-D point measurements: target positions in the instrument frame (laser tracker, CMM, vision
sphere centre). Several targets on one end effector give full 6-D information."""

from __future__ import annotations

import numpy as np

from ..errors import ProblemError
from .base import ResidualBlock
from .chain import TargetChain

__all__ = ["PointResidual"]


def point_distances(r, sigma) -> np.ndarray:
    """Distances [mm] (M,) from weighted 3-D residual rows r (3M,): each row triple times ``sigma``
    (1 when None), then its norm."""
    return np.linalg.norm((np.asarray(r) * (sigma or 1.0)).reshape(-1, 3), axis=1)


class PointResidual(ResidualBlock):
    """``r = (p_measured - p_predicted) / sigma`` for every measured point, 3 rows per point.

    chain: the :class:`~robocal.calib.residuals.chain.TargetChain` predicting the points;
    measured: (N, K, 3) [mm] in the instrument frame, NaN = not measured at that pose;
    sigma: standard deviation of one coordinate [mm] (``None``: weight 1).
    Rows: pose-major, then target, then x, y, z (only measured points).
    """

    kind = "point"

    def __init__(self, chain: TargetChain, measured, sigma: float | None = None):
        measured = np.asarray(measured, dtype=float)
        N, K = len(chain.q), chain.n_points
        if measured.shape != (N, K, 3):
            raise ProblemError(f"points: expected shape ({N}, {K}, 3) (poses, targets, xyz), got {measured.shape}")
        self.chain = chain
        self.measured = measured
        self.mask = np.all(np.isfinite(measured), axis=-1)
        self._all = bool(self.mask.all())
        pose = np.broadcast_to(np.arange(N)[:, None], self.mask.shape)[self.mask]
        super().__init__(chain.parameter_blocks, np.repeat(pose, 3), sigma)

    def evaluate(self, ev, jacobian):
        out = self.chain.evaluate(ev)
        w = self.weight
        if self._all:
            r = ((self.measured - out.points) * w).ravel()
            # weight 1 (no sigma given): the chain's Jacobians as they are (the problem copies them into J)
            jac = ({b: J.reshape(-1, J.shape[-1]) * w for b, J in out.jac.items()} if w != 1.0 else
                   {b: J.reshape(-1, J.shape[-1]) for b, J in out.jac.items()}) if jacobian else None
        else:
            m = self.mask
            r = ((self.measured - out.points)[m] * w).ravel()
            jac = {b: J[m].reshape(-1, J.shape[-1]) * w for b, J in out.jac.items()} if jacobian else None
        return r, jac

    def errors(self, r):
        """Distances [mm] between measured and predicted points (one per measured point)."""
        return point_distances(r, self.sigma)

    @classmethod
    def example(cls, rng):
        from .examples import example_chain, example_elastic_chain, example_full_elastic_chain

        out = []
        for n_stations, factory in ((1, example_chain), (2, example_chain), (1, example_elastic_chain),
                                    (2, example_elastic_chain), (1, example_full_elastic_chain),
                                    (2, example_full_elastic_chain)):
            chain = factory(rng, n_stations=n_stations)
            meas = rng.normal(0, 1000, (len(chain.q), chain.n_points, 3))
            meas[1, 0] = np.nan
            out.append(cls(chain, meas, sigma=0.05))
        return out
