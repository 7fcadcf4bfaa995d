"""Geometry of the simulated thermal cell: monitored points on a car body and the robot poses from
which the robot-held sensor sees them (mm, rad)."""

from __future__ import annotations

import math

import numpy as np

from ...kinematics.model import RobotModel
from ...transforms import invert_transforms, rot_x, so3_exp
from ..robot import as_rng

__all__ = ["car_body_points", "monitor_poses"]


def car_body_points(rng, n: int = 34, *, centre=(2100.0, 0.0, 600.0), size=(1000.0, 1500.0),
                    crown_mm: float = 120.0) -> np.ndarray:
    """``n`` monitored points (n, 3) [mm, base frame] on a car-body-like surface: a jittered grid over
    ``size`` (x by y) around ``centre`` on a gently crowned roof (``crown_mm`` higher in the middle)."""
    rng = as_rng(rng)
    nx = max(2, int(round(math.sqrt(n * size[0] / size[1]))))
    ny = -(-n // nx)
    gx, gy = np.meshgrid(np.linspace(-0.5, 0.5, nx), np.linspace(-0.5, 0.5, ny), indexing="ij")
    uv = np.stack([gx.ravel(), gy.ravel()], axis=1)
    keep = np.sort(rng.choice(len(uv), n, replace=False))
    uv = uv[keep] + rng.uniform(-0.25, 0.25, (n, 2)) / np.array([nx, ny])
    x = centre[0] + uv[:, 0] * size[0]
    y = centre[1] + uv[:, 1] * size[1]
    z = centre[2] + crown_mm * (1.0 - 4.0 * (uv[:, 0] ** 2 + uv[:, 1] ** 2) / 2.0)
    return np.stack([x, y, z], axis=1)


def _ik_pose(model, T_base_flange, prev):
    from ...kinematics import ik_analytic

    from ...calib.cell import default_cell, feasible

    qs, ok = ik_analytic(model, model.T_world_base @ T_base_flange, within_limits=True)
    if ok.any():
        ok[ok] = feasible(default_cell(), model, qs[ok])  # a branch the robot can take on its floor
    if not ok.any():
        return None
    cand = qs[ok]
    ref = model.limits.mean(axis=1) if prev is None else prev
    return cand[np.argmin(np.sum((cand - ref) ** 2, axis=1))]


def monitor_poses(model: RobotModel, points, T_flange_sensor, rng, *, standoff_mm: float = 250.0,
                  tilt_deg: float = 20.0, max_tries: int = 50):
    """Robot poses (n, 6) from which the robot-held sensor sees each monitored point.

    The sensor's z axis points at the point from ``standoff_mm`` away, tilted from straight down by
    up to ``tilt_deg`` about a random axis, with a random turn about z; the flange pose is
    ``T_base_sensor . T_flange_sensor^-1`` and the joints come from the closed-form IK (the branch
    closest to the previous pose). Returns the joints (n, 6) [rad]."""
    rng = as_rng(rng)
    pts = np.asarray(points, float)
    T_sf = invert_transforms(np.asarray(T_flange_sensor, float))
    out, prev = [], None
    for i, p in enumerate(pts):
        for _ in range(max_tries):
            axis = rng.normal(size=3)
            axis /= np.linalg.norm(axis)
            R = so3_exp(axis * math.radians(tilt_deg) * rng.uniform(0.0, 1.0)) @ rot_x(math.pi) @ \
                so3_exp(np.array([0.0, 0.0, rng.uniform(-math.pi, math.pi)]))
            T_bs = np.eye(4)
            T_bs[:3, :3] = R
            T_bs[:3, 3] = p - R[:, 2] * standoff_mm
            q = _ik_pose(model, T_bs @ T_sf, prev)
            if q is not None:
                out.append(q)
                prev = q
                break
        else:
            raise ValueError(f"monitored point {i} at {p.tolist()} mm: no reachable sensor pose")
    return np.array(out)
