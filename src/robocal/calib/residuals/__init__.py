"""Residual blocks: the measurement kinds of the calibration core (see :mod:`.base`)."""

from .base import RESIDUAL_BLOCKS, Evaluation, ResidualBlock
from .chain import ChainPoints, TargetChain
from .check import jacobian_errors, perturbed_values
from .distance import DistanceResidual
from .fixed_point import FixedPointResidual
from .plane import PointOnPlaneResidual
from .points import PointResidual
from .prior import PosePriorResidual, PriorResidual
from .reprojection import ReprojectionResidual
from .flange_reprojection import FlangeReprojectionResidual
from .rotation import RotationResidual
from .tool_pose import ToolPointResidual, ToolRotationResidual, tool_chain

__all__ = ["RESIDUAL_BLOCKS", "Evaluation", "ResidualBlock", "TargetChain", "ChainPoints", "PointResidual",
           "RotationResidual", "DistanceResidual", "PointOnPlaneResidual", "PriorResidual", "PosePriorResidual", "ReprojectionResidual", "FlangeReprojectionResidual", "FixedPointResidual", "ToolPointResidual", "ToolRotationResidual", "tool_chain",
           "jacobian_errors", "perturbed_values"]
from .ray_spot import RaySpotResidual, laser_chain  # noqa: E402

__all__ += ["RaySpotResidual", "laser_chain"]
from .spot_spacing import PointSpacingResidual  # noqa: E402

__all__ += ["PointSpacingResidual"]
from .board_shape import BoardShapeReprojectionResidual  # noqa: E402

__all__ += ["BoardShapeReprojectionResidual"]
