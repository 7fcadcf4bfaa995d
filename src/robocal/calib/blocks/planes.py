"""Planes for point-on-plane constraints: unit normal by two angles and an offset."""

from __future__ import annotations

import numpy as np

from ..errors import ProblemError
from .manifolds import VectorBlock

__all__ = ["Planes", "plane_normals", "plane_normal_derivatives"]

_PLANE_VARIABLES = (("azimuth", "rad"), ("elevation", "rad"), ("offset", "mm"))


def plane_normals(pl) -> np.ndarray:
    """Unit normals (..., 3) of planes (..., 3) = (azimuth, elevation [rad], offset [mm])."""
    az, el = pl[..., 0], pl[..., 1]
    return np.stack([np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.sin(el)], axis=-1)


def plane_normal_derivatives(pl):
    """d normal / d azimuth and d normal / d elevation, each (..., 3)."""
    az, el = pl[..., 0], pl[..., 1]
    d_az = np.stack([-np.cos(el) * np.sin(az), np.cos(el) * np.cos(az), np.zeros_like(az)], axis=-1)
    d_el = np.stack([-np.sin(el) * np.cos(az), -np.sin(el) * np.sin(az), np.cos(el)], axis=-1)
    return d_az, d_el


class Planes(VectorBlock):
    """L planes (L, 3): normal azimuth, elevation [rad] and offset [mm] (``n . p = offset``), additive.

    Variables ``plane0.azimuth``, ``plane0.elevation``, ``plane0.offset``, ... (``prefix``).
    Identifiability group ``"planes"``.
    """

    group = "planes"

    def __init__(self, initial=None, *, name: str = "planes", prefix: str = "plane", free=True, prior=None):
        pl = np.zeros((0, 3)) if initial is None else np.asarray(initial, dtype=float).reshape(-1, 3)
        if not np.all(np.isfinite(pl)):
            raise ProblemError(f"{name}: initial planes contain NaN or infinite values")
        names = [f"{prefix}{i}.{c}" for i in range(len(pl)) for c, _ in _PLANE_VARIABLES]
        units = [u for _ in range(len(pl)) for _, u in _PLANE_VARIABLES]
        super().__init__(name, names, units, pl, free=free, prior=prior)

    @property
    def n_planes(self) -> int:
        return len(self.initial)
