"""Programmed flange motions of the cross-laser procedure and their trapezoidal timing.

A :class:`CircleMove` is a controller ``movec`` at constant orientation, a :class:`LinearMove` a
``movel`` with the orientation interpolated; both follow a rest-to-rest trapezoidal speed profile
(constant acceleration, cruise, constant deceleration). Positions in mm (base frame), times in s
from the start of the motion, angles in rad. The file form of a motion (the ``# motion:`` header
of the events file) is in :mod:`robocal.io.barrier_events`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ...transforms import so3_exp, so3_log, transforms_from

__all__ = ["CircleMove", "LinearMove"]


def _trapezoid(length: float, speed: float, accel: float):
    """Duration [s], peak speed [mm/s] and ramp time [s] of a rest-to-rest trapezoidal profile
    over ``length`` [mm] with cruise ``speed`` [mm/s] and acceleration ``accel`` [mm/s^2]."""
    if length <= 0:
        return 0.0, 0.0, 0.0
    if speed <= 0 or accel <= 0:
        raise ValueError("speed and acceleration must be > 0")
    if length >= speed * speed / accel:
        t_acc = speed / accel
        return length / speed + t_acc, speed, t_acc
    vmax = math.sqrt(length * accel)
    t_acc = vmax / accel
    return 2 * t_acc, vmax, t_acc


def _path_s(t, length, accel, duration, vmax, t_acc):
    """Path length travelled [mm] at times ``t`` (N,) [s] on the profile of :func:`_trapezoid`."""
    t = np.clip(np.asarray(t, dtype=float), 0.0, duration)
    s_ramp = 0.5 * accel * t * t
    s_end = length - 0.5 * accel * (duration - t) ** 2
    s_mid = 0.5 * accel * t_acc * t_acc + vmax * (t - t_acc)
    return np.where(t < t_acc, s_ramp, np.where(t > duration - t_acc, s_end, s_mid))


def _arr(x, shape=None):
    """A read-only float copy of ``x``, checked against ``shape`` when given."""
    a = np.array(x, dtype=float)
    if shape is not None and a.shape != shape:
        raise ValueError(f"expected shape {shape}, got {a.shape}")
    a.setflags(write=False)
    return a


class _TrapezoidMove:
    """Shared timing of a programmed move: a trapezoidal speed profile over ``_length`` [mm]."""

    @property
    def _profile(self):
        return _trapezoid(self._length, self.speed_mm_s, self.accel_mm_s2)

    @property
    def duration_s(self) -> float:
        return self._profile[0]

    @property
    def constant_speed_window_s(self) -> tuple:
        d, _, t_acc = self._profile
        return t_acc, d - t_acc


@dataclass(frozen=True)
class CircleMove(_TrapezoidMove):
    """A circular flange motion at constant orientation (a controller ``movec``), base frame.

    Flange position ``center + R (cos(phi) e1 + sin(phi) e2)`` with ``e1 = ref_dir``, ``e2 =
    normal x e1``; ``phi`` runs from ``start_angle_rad`` through ``sweep_rad`` (positive =
    counter-clockwise about ``normal``) on a trapezoidal speed profile (``speed_mm_s``,
    ``accel_mm_s2``). ``R_base_flange`` is the constant flange orientation.
    """

    center_mm: np.ndarray
    radius_mm: float
    normal: np.ndarray
    ref_dir: np.ndarray
    start_angle_rad: float
    sweep_rad: float
    speed_mm_s: float
    accel_mm_s2: float
    R_base_flange: np.ndarray
    step: int = 0
    role: str = "circle"

    kind = "circle"

    def __post_init__(self):
        object.__setattr__(self, "center_mm", _arr(self.center_mm, (3,)))
        n = np.asarray(self.normal, float)
        n = n / np.linalg.norm(n)
        e1 = np.asarray(self.ref_dir, float)
        e1 = e1 - (e1 @ n) * n
        e1 = e1 / np.linalg.norm(e1)
        object.__setattr__(self, "normal", _arr(n))
        object.__setattr__(self, "ref_dir", _arr(e1))
        object.__setattr__(self, "R_base_flange", _arr(self.R_base_flange, (3, 3)))

    @property
    def _length(self) -> float:
        return abs(self.sweep_rad) * self.radius_mm

    def phase(self, t) -> np.ndarray:
        """Programmed angle phi [rad] at motion time ``t`` [s] (from the start of this motion)."""
        d, vmax, t_acc = self._profile
        L = abs(self.sweep_rad) * self.radius_mm
        s = _path_s(t, L, self.accel_mm_s2, d, vmax, t_acc)
        return self.start_angle_rad + math.copysign(1.0, self.sweep_rad) * s / self.radius_mm

    @property
    def angular_speed_rad_s(self) -> float:
        return self._profile[1] / self.radius_mm

    def positions(self, t) -> np.ndarray:
        """Commanded flange positions (N, 3) [mm] at motion times ``t`` (N,) [s]."""
        phi = self.phase(t)
        e2 = np.cross(self.normal, self.ref_dir)
        return (self.center_mm + self.radius_mm * (np.cos(phi)[..., None] * self.ref_dir
                                                   + np.sin(phi)[..., None] * e2))

    def poses(self, t) -> np.ndarray:
        """Commanded flange poses ``T_base_flange`` (N, 4, 4) at motion times ``t`` (N,)."""
        p = self.positions(np.atleast_1d(t))
        return transforms_from(np.broadcast_to(self.R_base_flange, p.shape[:-1] + (3, 3)), p)


@dataclass(frozen=True)
class LinearMove(_TrapezoidMove):
    """A straight flange motion with the orientation interpolated (``movel``), base frame.

    Position and rotation (about the fixed axis of ``R_start^T R_end``) follow the same
    trapezoidal profile; its length is the larger of the distance and the rotation angle times
    ``speed_mm_s / angular_speed_rad_s``.
    """

    start_mm: np.ndarray
    end_mm: np.ndarray
    R_start: np.ndarray
    R_end: np.ndarray
    speed_mm_s: float
    angular_speed_rad_s: float
    accel_mm_s2: float
    step: int = 0
    role: str = "move"

    kind = "line"

    def __post_init__(self):
        object.__setattr__(self, "start_mm", _arr(self.start_mm, (3,)))
        object.__setattr__(self, "end_mm", _arr(self.end_mm, (3,)))
        object.__setattr__(self, "R_start", _arr(self.R_start, (3, 3)))
        object.__setattr__(self, "R_end", _arr(self.R_end, (3, 3)))

    @property
    def _rotvec(self):
        return so3_log(self.R_start.T @ self.R_end)

    @property
    def _length(self) -> float:
        dist = float(np.linalg.norm(self.end_mm - self.start_mm))
        ang = float(np.linalg.norm(self._rotvec))
        return max(dist, ang * self.speed_mm_s / self.angular_speed_rad_s)

    def fraction(self, t) -> np.ndarray:
        """Fraction (N,) of the move done at motion times ``t`` (N,) [s], 0 ... 1."""
        L = self._length
        if L <= 0:
            return np.ones_like(np.asarray(t, float))
        d, vmax, t_acc = self._profile
        return _path_s(t, L, self.accel_mm_s2, d, vmax, t_acc) / L

    def positions(self, t) -> np.ndarray:
        """Commanded flange positions (N, 3) [mm] at motion times ``t`` (N,) [s]."""
        lam = self.fraction(t)[..., None]
        return self.start_mm + lam * (self.end_mm - self.start_mm)

    def poses(self, t) -> np.ndarray:
        """Commanded flange poses ``T_base_flange`` (N, 4, 4) at motion times ``t`` (N,)."""
        t = np.atleast_1d(np.asarray(t, float))
        lam = self.fraction(t)
        R = self.R_start @ so3_exp(lam[..., None] * self._rotvec)
        return transforms_from(R, self.positions(t))


def pose_at_start(motion) -> np.ndarray:
    """The commanded flange pose (4, 4) at the start of ``motion``."""
    return motion.poses([0.0])[0]


def pose_at_end(motion) -> np.ndarray:
    """The commanded flange pose (4, 4) at the end of ``motion``."""
    return motion.poses([motion.duration_s])[0]
