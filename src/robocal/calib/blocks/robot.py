"""The robot geometry block: a named subset of a robot model's kinematic parameters."""

from __future__ import annotations

import numpy as np

from ...kinematics.model import RobotModel
from ..errors import ProblemError
from .base import ParameterBlock

__all__ = ["RobotGeometry"]


class RobotGeometry(ParameterBlock):
    """Selected kinematic parameters of ``model`` (joint offsets included), by name.

    The value is the model's whole parameter vector (P,) [mm | rad] (``model.params.values``
    unless ``initial`` is given); the block's variables are the parameters ``names`` in that order
    (default: the model's free parameters), additive. ``free`` can fix some of them again.
    Unknown names raise with a suggestion (``model.params.index``).
    """

    group = "geometry"

    def __init__(self, model: RobotModel, names=None, *, name: str = "geometry", initial=None, free=True,
                 prior=None):
        pnames = model.params.names
        if names is None:
            names = [n for n, f in zip(pnames, model.params.free) if f]
        names = list(names)
        for n in names:
            model.params.index(n)  # raises with a suggestion for unknown names
        self.model = model
        self.index = np.array([pnames.index(n) for n in names], dtype=int)
        units = [model.params.units[i] for i in self.index]
        value = model.params.values if initial is None else np.asarray(initial, dtype=float)
        if value.shape != (len(pnames),):
            raise ProblemError(f"{name}: initial value must be the model's {len(pnames)} parameters, got {value.shape}")
        super().__init__(name, names, units, value, free=free, prior=prior)

    def retract(self, value, delta):
        out = value.copy()
        out[self.index] += delta
        return out

    def local(self, value):
        return value[self.index]

    def prior_error(self, value, mean):
        return (mean - value)[self.index], np.eye(self.size)
