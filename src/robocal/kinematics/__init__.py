"""Kinematic models, batched forward kinematics, analytic Jacobians and inverse kinematics."""

from .links import MODEL_KINDS, Link
from .model import EndEffector, ParameterTable, RobotModel

__all__ = ["MODEL_KINDS", "Link", "EndEffector", "ParameterTable", "RobotModel"]
