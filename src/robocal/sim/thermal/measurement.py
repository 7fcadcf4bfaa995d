"""Measurement errors of the realistic thermal cell: backlash, distance-dependent sensor noise and
outliers (:mod:`robocal.sim.thermal.effects`). Lengths mm, angles rad; every function takes a
``numpy.random.Generator``.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["approach_sides", "backlash_offsets", "distance_noise", "add_outliers"]


def approach_sides(n_poses: int, n_joints: int, rng) -> np.ndarray:
    """(n_poses, n_joints) +-1: the side each joint approaches each pose of a program from."""
    return np.where(rng.random((n_poses, n_joints)) < 0.5, -1.0, 1.0)


def backlash_offsets(sides, joints_effect, rng) -> np.ndarray:
    """Joint offsets (N, n_joints) [rad] from backlash for one execution of a program with the
    approach ``sides`` (N, n_joints): each side flips with ``joints_effect.flip_probability``,
    the joint then stands ``backlash_deg`` on that side."""
    flip = rng.random(np.shape(sides)) < joints_effect.flip_probability
    s = np.where(flip, -np.asarray(sides), np.asarray(sides))
    return s * np.radians(np.asarray(joints_effect.backlash_deg, float))


def distance_noise(points, lateral_mm: float, depth_mm: float, ref_mm: float, rng) -> np.ndarray:
    """Noise (N, 3) [mm] for points (N, 3) in a sensor frame whose z axis is the optical axis:
    standard deviations ``lateral_mm |z| / ref`` in x, y and ``depth_mm (z / ref)^2`` in z."""
    p = np.asarray(points, float)
    z = np.abs(p[:, 2]) / ref_mm
    sd = np.stack([lateral_mm * z, lateral_mm * z, depth_mm * z * z], axis=1)
    return rng.standard_normal(p.shape) * sd


def add_outliers(points, probability: float, range_mm, rng):
    """``(points with outliers (N, 3), mask (N,))``: each point is, with ``probability``, moved
    by a random direction times a magnitude uniform in ``range_mm`` [mm]."""
    p = np.array(points, float, copy=True)
    hit = rng.random(len(p)) < probability
    if hit.any():
        d = rng.standard_normal((int(hit.sum()), 3))
        d /= np.linalg.norm(d, axis=1, keepdims=True)
        p[hit] += d * rng.uniform(range_mm[0], range_mm[1], (len(d), 1))
    return p, hit


def noise_rms(lateral_mm: float, depth_mm: float, ratio: float) -> float:
    """rms per coordinate [mm] of :func:`distance_noise` at distance ``ratio`` times the reference."""
    return math.sqrt((2 * (lateral_mm * ratio) ** 2 + (depth_mm * ratio ** 2) ** 2) / 3.0)
