"""The three manifolds parameter blocks live on: plain vectors, rigid frames, unit vectors.

* :class:`VectorBlock` -- any array of numbers, additive steps (``value + delta``);
* :class:`FramesBlock` -- G rigid frames (G, 4, 4) [mm], 6 variables each: a left perturbation
  ``T <- [exp(w) | v] . T`` (rotation vector ``w`` [rad], translation ``v`` [mm]) applied after every
  accepted step, so a frame is always a valid rigid transform (no penalty terms). Reported as the
  rotation vector of ``R`` and the origin ``t``;
* :class:`UnitVectorsBlock` -- L directions (L, 3), 2 variables each: small rotations [rad] about the
  local east and north directions of the vector (``u <- exp(d1 e + d2 n) u``). Reported as
  azimuth and elevation [rad].
"""

from __future__ import annotations

import numpy as np

from ...transforms import rodrigues_coefficients, skew, so3_exp, so3_log
from ..errors import ProblemError
from .base import ParameterBlock

__all__ = ["VectorBlock", "FramesBlock", "UnitVectorsBlock", "so3_right_jacobian_inverse", "tangent_basis"]

_FRAME_VARIABLES = (("rx", "rad"), ("ry", "rad"), ("rz", "rad"), ("x", "mm"), ("y", "mm"), ("z", "mm"))


def so3_right_jacobian_inverse(phi) -> np.ndarray:
    """Inverse right Jacobian of SO(3) at rotation vectors phi (N, 3): (N, 3, 3).

    ``log(exp(phi) exp(d)) = phi + Jr^-1(phi) d`` to first order.
    """
    th = np.linalg.norm(phi, axis=-1)[:, None, None]
    K = skew(phi)
    small = th < 1e-6
    ths = np.where(small, 1.0, th)
    c = np.where(small, 1.0 / 12.0, 1.0 / ths**2 - (1.0 + np.cos(ths)) / (2.0 * ths * np.sin(ths)))
    return np.eye(3) + 0.5 * K + c * (K @ K)


def _small_rotation(x, y, z) -> np.ndarray:
    """exp(skew(w)) (3, 3) of one rotation vector w = (x, y, z) [rad] in scalar arithmetic: the
    solvers' frame update, ~2x faster than :func:`so3_exp` for one vector. It equals ``so3_exp`` to
    rounding (~1e-16), not bit for bit, which is why the simulators keep ``so3_exp``."""
    a, b = rodrigues_coefficients(x, y, z)
    bxy, bxz, byz = b * x * y, b * x * z, b * y * z
    return np.array([[1.0 - b * (y * y + z * z), bxy - a * z, bxz + a * y],
                     [bxy + a * z, 1.0 - b * (x * x + z * z), byz - a * x],
                     [bxz - a * y, byz + a * x, 1.0 - b * (x * x + y * y)]])  # I + a K + b K^2, K = skew(w)


class VectorBlock(ParameterBlock):
    """Numbers with additive steps. ``initial`` of any shape (its size = number of names)."""

    def __init__(self, name, names, units, initial, *, free=True, prior=None, group=None):
        super().__init__(name, names, units, initial, free=free, prior=prior, group=group)
        if self.initial.size != self.size:
            raise ProblemError(f"{self.name}: initial value has {self.initial.size} numbers for {self.size} names")

    def retract(self, value, delta):
        return value + np.asarray(delta).reshape(value.shape)

    def local(self, value):
        return np.ravel(value)

    def prior_error(self, value, mean):
        return np.ravel(mean - value), np.eye(self.size)


class FramesBlock(ParameterBlock):
    """G rigid frames (G, 4, 4), 6 variables each (``<label>.rx .. <label>.z``)."""

    def __init__(self, name, initial, *, labels=None, free=True, prior=None, group=None):
        T = np.array(initial, dtype=float)
        if T.ndim == 2:
            T = T[None]
        if T.ndim != 3 or T.shape[1:] != (4, 4):
            raise ProblemError(f"{name}: expected (4, 4) or (G, 4, 4) frames, got shape {np.shape(initial)}")
        G = len(T)
        if labels is None:
            labels = [name] if G == 1 else [f"{name}{g}" for g in range(G)]
        if len(labels) != G:
            raise ProblemError(f"{name}: {len(labels)} labels for {G} frames")
        self.labels = tuple(labels)
        names = [f"{lab}.{c}" for lab in self.labels for c, _ in _FRAME_VARIABLES]
        units = [u for _ in self.labels for _, u in _FRAME_VARIABLES]
        super().__init__(name, names, units, T, free=free, prior=prior, group=group)

    @property
    def n_frames(self) -> int:
        return len(self.labels)

    def retract(self, value, delta):
        d = np.asarray(delta).reshape(-1, 6)
        if len(d) == 1:  # one frame (the usual base): scalar rotation, 2-D products
            R = _small_rotation(*(float(v) for v in d[0, :3]))
            out = value.copy()
            out[0, :3, :3] = R @ value[0, :3, :3]
            out[0, :3, 3] = R @ value[0, :3, 3] + d[0, 3:]
            return out
        R = so3_exp(d[:, :3])
        out = value.copy()
        out[:, :3, :3] = R @ value[:, :3, :3]
        out[:, :3, 3] = (R @ value[:, :3, 3, None])[..., 0] + d[:, 3:]
        return out

    def local(self, value):
        return np.concatenate([so3_log(value[:, :3, :3]), value[:, :3, 3]], axis=1).ravel()

    def prior_error(self, value, mean):
        # e = (log(R_mean R^T), t_mean - t); a left step exp(w) moves them by -Jr^-1 w and
        # -(w x t + v) (see the rotation residual for the same derivative)
        G = len(value)
        R, t = value[:, :3, :3], value[:, :3, 3]
        e_rot = so3_log(mean[:, :3, :3] @ np.swapaxes(R, 1, 2))
        e = np.concatenate([e_rot, mean[:, :3, 3] - t], axis=1).ravel()
        D = np.zeros((G, 6, G, 6))
        g = np.arange(G)
        D[g, :3, g, :3] = so3_right_jacobian_inverse(e_rot)
        D[g, 3:, g, :3] = -skew(t)
        D[g, 3:, g, 3:] = np.eye(3)
        return e, D.reshape(6 * G, 6 * G)


def tangent_basis(u) -> tuple:
    """Orthonormal tangent directions (east, north) of unit vectors u (L, 3): two (L, 3) arrays.

    East is ``z x u`` normalised (the azimuth direction); at the poles, x is used instead of z.
    """
    u = np.asarray(u, dtype=float)
    ref = np.zeros_like(u)
    pole = np.hypot(u[:, 0], u[:, 1]) < 1e-9
    ref[:, 2] = np.where(pole, 0.0, 1.0)
    ref[:, 0] = np.where(pole, 1.0, 0.0)
    east = np.cross(ref, u)
    east /= np.linalg.norm(east, axis=1, keepdims=True)
    return east, np.cross(u, east)


class UnitVectorsBlock(ParameterBlock):
    """L directions (L, 3), 2 variables each (``<label>.azimuth``, ``<label>.elevation`` [rad]).

    The variables are small rotations of the vector towards its east and north tangent directions
    (:func:`tangent_basis`); values are reported as azimuth and elevation.
    """

    def __init__(self, name, initial, *, labels=None, free=True, prior=None, group=None):
        u = np.array(initial, dtype=float).reshape(-1, 3)
        norm = np.linalg.norm(u, axis=1)
        if np.any(norm < 1e-12):
            raise ProblemError(f"{name}: a direction has zero length")
        u = u / norm[:, None]
        L = len(u)
        if labels is None:
            labels = [name] if L == 1 else [f"{name}{i}" for i in range(L)]
        self.labels = tuple(labels)
        names = [f"{lab}.{c}" for lab in self.labels for c in ("azimuth", "elevation")]
        super().__init__(name, names, ["rad"] * len(names), u, free=free, prior=prior, group=group)

    def retract(self, value, delta):
        d = np.reshape(delta, (-1, 2))
        east, north = tangent_basis(value)
        w = np.cross(value, d[:, :1] * east + d[:, 1:] * north)  # rotation axis * angle
        out = (so3_exp(w) @ value[:, :, None])[..., 0]
        return out / np.linalg.norm(out, axis=1, keepdims=True)

    def local(self, value):
        az = np.arctan2(value[:, 1], value[:, 0])
        el = np.arcsin(np.clip(value[:, 2], -1.0, 1.0))
        return np.stack([az, el], axis=1).ravel()

    def derivative(self, value) -> np.ndarray:
        """d u / d delta: (L, 3, 2) [per rad] (the east and north directions)."""
        east, north = tangent_basis(value)
        return np.stack([east, north], axis=-1)

    def prior_error(self, value, mean):
        # e = components of (mean - u) along the mean's east and north directions (fixed, so
        # D = du/d delta projected on them)
        basis = np.stack(tangent_basis(mean), axis=1)  # (L, 2, 3)
        e = np.einsum("lbi,li->lb", basis, mean - value).ravel()
        L = len(value)
        D = np.zeros((L, 2, L, 2))
        l_ = np.arange(L)
        D[l_, :, l_, :] = np.einsum("lbi,lik->lbk", basis, self.derivative(value))
        return e, D.reshape(2 * L, 2 * L)
