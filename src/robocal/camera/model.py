"""A camera as a value: intrinsics, distortion model and coefficients, image size."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .distortion import BROWN_SIZES
from .projection import MODELS, Projection, project_points, undistort_pixels

__all__ = ["Camera"]


@dataclass(frozen=True)
class Camera:
    """A pinhole camera with lens distortion.

    fx, fy [px]: focal lengths; cx, cy [px]: principal point (OpenCV's pixel-centre convention:
    the centre of the top-left pixel is (0, 0)); ``model``: ``"brown"`` (``distortion`` = OpenCV's
    ``k1, k2, p1, p2[, k3[, k4, k5, k6]]``) or ``"division"`` (``distortion`` = ``(kappa,)`` on
    normalised coordinates); ``image_size``: (width, height) [px] or None.
    """

    fx: float
    fy: float
    cx: float
    cy: float
    distortion: tuple = (0.0, 0.0, 0.0, 0.0, 0.0)
    model: str = "brown"
    image_size: tuple | None = field(default=None)

    def __post_init__(self):
        if self.model not in MODELS:
            raise ValueError(f"unknown distortion model {self.model!r}; expected one of {', '.join(MODELS)}")
        d = tuple(float(v) for v in np.asarray(self.distortion, dtype=float).ravel())
        sizes = BROWN_SIZES if self.model == "brown" else (1,)
        if len(d) not in sizes:
            raise ValueError(f"{self.model} distortion takes {' or '.join(map(str, sizes))} coefficients, got {len(d)}")
        if not (self.fx > 0 and self.fy > 0):
            raise ValueError(f"focal lengths must be positive pixels, got fx={self.fx}, fy={self.fy}")
        object.__setattr__(self, "distortion", d)

    @classmethod
    def from_matrix(cls, K, distortion=(0.0, 0.0, 0.0, 0.0, 0.0), model="brown", image_size=None) -> "Camera":
        """From OpenCV's 3x3 camera matrix ``K`` (its skew entry must be zero)."""
        K = np.asarray(K, dtype=float).reshape(3, 3)
        if abs(K[0, 1]) > 1e-12 * abs(K[0, 0]):
            raise ValueError(f"camera matrix has a skew entry K[0, 1] = {K[0, 1]}: not supported")
        return cls(K[0, 0], K[1, 1], K[0, 2], K[1, 2], tuple(np.ravel(distortion)), model, image_size)

    @property
    def intrinsics(self) -> np.ndarray:
        """(fx, fy, cx, cy) [px]."""
        return np.array([self.fx, self.fy, self.cx, self.cy])

    @property
    def matrix(self) -> np.ndarray:
        """OpenCV's 3x3 camera matrix."""
        return np.array([[self.fx, 0.0, self.cx], [0.0, self.fy, self.cy], [0.0, 0.0, 1.0]])

    def project(self, points, jacobian: bool = False) -> Projection:
        """Pixels of points (N, 3) [mm, camera frame]; see :func:`.projection.project_points`."""
        return project_points(points, self.intrinsics, self.distortion, self.model, jacobian)

    def rays(self, pixels) -> np.ndarray:
        """Undistorted normalised coordinates (N, 2) of pixels (N, 2)."""
        return undistort_pixels(pixels, self.intrinsics, self.distortion, self.model)
