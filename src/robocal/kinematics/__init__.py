"""Kinematic models, batched forward kinematics, analytic Jacobians and inverse kinematics."""

from .convert import ConversionError, dh_to_mdh, mdh_to_urdf, to_urdf_kind
from .ik import IKResult, ik_numeric
from .ik_analytic import NotAnalyticError, ik_analytic, is_analytic, opw_from_model
from .links import MODEL_KINDS, Link
from .model import EndEffector, ParameterTable, RobotModel

__all__ = ["MODEL_KINDS", "ConversionError", "EndEffector", "IKResult", "Link", "NotAnalyticError", "ParameterTable",
           "RobotModel", "dh_to_mdh", "ik_analytic", "ik_numeric", "is_analytic", "mdh_to_urdf", "opw_from_model",
           "to_urdf_kind"]
