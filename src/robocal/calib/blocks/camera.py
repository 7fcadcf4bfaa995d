"""Camera intrinsics and lens distortion as a parameter block (issue 14; METHODS.md section 3)."""

from __future__ import annotations

import numpy as np

from ...camera.distortion import BROWN_SIZES
from ..errors import ProblemError
from .manifolds import VectorBlock

__all__ = ["CameraIntrinsics"]

_BROWN_NAMES = ("k1", "k2", "p1", "p2", "k3", "k4", "k5", "k6")


class CameraIntrinsics(VectorBlock):
    """``(fx, fy, cx, cy, d_1..d_K)``: focal lengths and principal point [px] and the distortion
    coefficients [1] of one camera, additive steps.

    Variables ``<name>.fx, .fy, .cx, .cy`` [px] and, for ``model="brown"``, ``.k1, .k2, .p1, .p2
    [, .k3[, .k4, .k5, .k6]]`` (OpenCV's order, 4, 5 or 8 of them) or, for ``model="division"``,
    ``.kappa`` (on normalised coordinates, :mod:`robocal.camera.distortion`). ``free`` as every
    block (e.g. ``free=["cam.fx", "cam.fy", "cam.cx", "cam.cy", "cam.k1", "cam.k2"]``). Group
    ``"camera"``.
    """

    group = "camera"

    def __init__(self, intrinsics, distortion=(0.0, 0.0, 0.0, 0.0, 0.0), *, model: str = "brown",
                 name: str = "cam", free=True, prior=None):
        intr = np.asarray(intrinsics, dtype=float).ravel()
        dist = np.asarray(distortion, dtype=float).ravel()
        if intr.size != 4:
            raise ProblemError(f"{name}: intrinsics are (fx, fy, cx, cy), got {intr.size} numbers")
        if model == "brown":
            if dist.size not in BROWN_SIZES:
                raise ProblemError(f"{name}: Brown-Conrady takes 4, 5 or 8 coefficients, got {dist.size}")
            dnames = _BROWN_NAMES[: dist.size]
        elif model == "division":
            if dist.size != 1:
                raise ProblemError(f"{name}: the division model takes one coefficient (kappa), got {dist.size}")
            dnames = ("kappa",)
        else:
            raise ProblemError(f"{name}: unknown distortion model {model!r} (brown, division)")
        self.model = model
        names = [f"{name}.{v}" for v in ("fx", "fy", "cx", "cy", *dnames)]
        units = ["px"] * 4 + ["1"] * len(dnames)
        super().__init__(name, names, units, np.concatenate([intr, dist]), free=free, prior=prior)

    @staticmethod
    def split(value) -> tuple:
        """``(intrinsics (4,), distortion (K,))`` of a block value."""
        value = np.asarray(value)
        return value[:4], value[4:]
