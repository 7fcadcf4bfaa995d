"""Camera models (issue 14, METHODS.md section 3 "Hand-eye"): pinhole with Brown–Conrady
distortion in OpenCV's convention or HALCON's division model; batched projection with analytic
Jacobians; undistortion. Math only: numpy, no files, no OpenCV."""

from .distortion import BROWN_SIZES, brown_distort, division_distort, division_undistort
from .model import Camera
from .projection import MODELS, Projection, distort, project_points, undistort_normalized, undistort_pixels

__all__ = ["BROWN_SIZES", "MODELS", "Camera", "Projection", "brown_distort", "division_distort",
           "division_undistort", "distort", "project_points", "undistort_normalized", "undistort_pixels"]
