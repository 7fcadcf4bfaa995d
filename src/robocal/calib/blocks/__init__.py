"""Parameter blocks: the unknowns of a calibration, each on its manifold (see :mod:`.base`)."""

from .camera import CameraIntrinsics
from .base import GaussianPrior, ParameterBlock, free_mask
from .frames import StationFrames
from .manifolds import FramesBlock, UnitVectorsBlock, VectorBlock, so3_right_jacobian_inverse, tangent_basis
from .planes import Planes, plane_normal_derivatives, plane_normals
from .points import TargetPoints
from .robot import RobotGeometry
from .tool import ToolFrame

__all__ = ["CameraIntrinsics", "GaussianPrior", "ParameterBlock", "free_mask", "VectorBlock", "FramesBlock", "UnitVectorsBlock",
           "StationFrames", "TargetPoints", "Planes", "RobotGeometry", "ToolFrame", "plane_normals", "plane_normal_derivatives",
           "so3_right_jacobian_inverse", "tangent_basis"]
from .laser import LaserMount  # noqa: E402

__all__ += ["LaserMount"]
