"""Target points: points carried by end effectors (reflectors, markers, sphere centres, tool tips)."""

from __future__ import annotations

import numpy as np

from ..errors import ProblemError
from .manifolds import VectorBlock

__all__ = ["TargetPoints"]


class TargetPoints(VectorBlock):
    """K points (K, 3) [mm], each in the frame of its end effector, additive.

    labels: (K,) point names (variables ``<label>.x``, ``.y``, ``.z``); end_effectors: (K,) the
    end effector carrying each point (name or index, ``None`` = the model's first), read by the
    chains that use the block; free: per variable as usual, or (K,) bools per point.
    Identifiability group ``"targets"``.
    """

    group = "targets"

    def __init__(self, labels, initial, *, name: str = "targets", end_effectors=None, free=True, prior=None):
        self.labels = tuple(str(x) for x in labels)
        K = len(self.labels)
        pts = np.array(initial, dtype=float).reshape(-1, 3) if K else np.zeros((0, 3))
        if pts.shape != (K, 3):
            raise ProblemError(f"{name}: expected ({K}, 3) initial points, got {np.shape(initial)}")
        self.end_effectors = (None,) * K if end_effectors is None else tuple(end_effectors)
        if len(self.end_effectors) != K:
            raise ProblemError(f"{name}: {len(self.end_effectors)} end effectors for {K} points")
        if not isinstance(free, (bool, np.bool_)):
            free = list(free)
            if K and len(free) == K and all(isinstance(f, (bool, np.bool_)) for f in free):
                free = np.repeat(np.array(free, dtype=bool), 3)  # one flag per point
        names = [f"{lab}.{c}" for lab in self.labels for c in "xyz"]
        super().__init__(name, names, ["mm"] * (3 * K), pts, free=free, prior=prior)
