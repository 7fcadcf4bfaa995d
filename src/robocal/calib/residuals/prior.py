"""Gaussian priors on parameter blocks as residual rows (added by the problem for blocks with a prior)."""

from __future__ import annotations

import numpy as np

from .base import ResidualBlock

__all__ = ["PriorResidual"]


class PriorResidual(ResidualBlock):
    """``r = e / sigma`` for each free variable of ``block``, ``e`` = the block's
    ``prior_error(value, prior.mean)`` (prior mean minus value in local coordinates).

    Rows belong to no pose (label -1): robust losses leave them alone.
    """

    kind = "prior"

    def __init__(self, block):
        if block.prior is None:
            raise ValueError(f"{block.name}: the block has no prior")
        self.block = block
        self.rows = np.flatnonzero(block.free)
        self.row_weight = 1.0 / np.asarray(block.prior.sigma, dtype=float)[self.rows]
        self.mean = block.prior.mean
        super().__init__((block,), np.full(len(self.rows), -1), None)

    def evaluate(self, ev, jacobian):
        e, D = self.block.prior_error(ev[self.block], self.mean)
        r = e[self.rows] * self.row_weight
        if not jacobian:
            return r, None
        return r, {self.block: D[self.rows] * self.row_weight[:, None]}

    @classmethod
    def example(cls, rng):
        from ..blocks import GaussianPrior, Planes, RobotGeometry, StationFrames, UnitVectorsBlock, VectorBlock
        from .examples import example_frames, example_robot

        model = example_robot(rng)
        frames0 = example_frames(rng, 2)
        blocks = [
            VectorBlock("v", ["v.a", "v.b", "v.c"], ["mm", "mm", "rad"], rng.normal(0, 10, 3),
                        prior=GaussianPrior(sigma=[1.0, 2.0, 0.1], mean=rng.normal(0, 10, 3))),
            StationFrames(frames0, prior=GaussianPrior(sigma=0.5, mean=example_frames(rng, 2)),
                          free=[True] * 9 + [False] + [True] * 2),
            UnitVectorsBlock("dirs", rng.normal(0, 1, (2, 3)),
                             prior=GaussianPrior(sigma=0.01, mean=_unit(rng.normal(0, 1, (2, 3))))),
            RobotGeometry(model, ["a2", "theta3", "beta4"], prior=GaussianPrior(sigma=0.1)),
            Planes([[0.3, 1.2, 800.0]], prior=GaussianPrior(sigma=[0.01, 0.01, 1.0], mean=[[0.2, 1.1, 790.0]])),
        ]
        return [cls(b) for b in blocks]


def _unit(v):
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


class PosePriorResidual(PriorResidual):
    """A Gaussian prior on ``block`` whose rows belong to poses: ``r = e / sigma`` as
    :class:`PriorResidual`, but given here (the block itself carries no prior, so the problem adds
    no second one) and each free variable's row labelled with ``poses`` (size,), so robust losses
    weigh it together with that pose's measurements -- e.g. a per-image correction of a robot pose
    whose prior grows when the robot reading was wrong.

    sigma: scalar or (size,) in the block's variable units; mean: in the block's value
    representation (default its initial value); poses: (size,) pose index per variable.
    """

    def __init__(self, block, sigma, poses, mean=None):
        self.block = block
        self.rows = np.flatnonzero(block.free)
        sigma = np.broadcast_to(np.asarray(sigma, dtype=float), (block.size,))
        if not np.all(sigma > 0):
            raise ValueError(f"{block.name}: prior sigma must be positive")
        self.row_weight = 1.0 / sigma[self.rows]
        self.mean = np.array(block.initial if mean is None else mean, dtype=float)
        poses = np.asarray(poses, dtype=int).reshape(-1)
        if poses.shape != (block.size,):
            raise ValueError(f"{block.name}: poses must have one entry per variable ({block.size})")
        ResidualBlock.__init__(self, (block,), poses[self.rows], None)

    @classmethod
    def example(cls, rng):
        from ..blocks import FramesBlock
        from .examples import example_frames

        frames = FramesBlock("corrections", example_frames(rng, 3), free=[True] * 16 + [False] * 2)
        return cls(frames, rng.uniform(0.01, 1.0, 18), np.repeat(np.arange(3), 6), mean=example_frames(rng, 3))
