"""A virtual controller answering probe programs: the pairs its forward kinematics would print.

The controller runs a hidden model (any robocal model: nominal, factory-calibrated, ...) and
reports poses rounded like a pendant or a program's number formatting: positions to
``resolution_mm`` and Euler angles to ``resolution_deg`` (UR rotation vectors and ABB quaternions
to the equivalent step), joints as given. ``compensation`` optionally adds a non-geometric
correction (a function of the joints returning a position offset (N, 3) [mm]), as a controller
with a load- or deflection model would.
"""

from __future__ import annotations

import math

import numpy as np

from ..io.controller_pairs import CONTROLLERS, pair_line
from ..transforms import pose_from_transform

__all__ = ["probe_pairs_text"]


def _round(x, step):
    return np.round(np.asarray(x) / step) * step


def probe_pairs_text(model, q, controller: str, *, resolution_mm: float = 0.01, resolution_deg: float = 0.001,
                     compensation=None) -> str:
    """The ``robocal-pair`` lines a ``controller`` running ``model`` prints for joints ``q`` (N, n) [rad]."""
    c = CONTROLLERS[controller]
    q = np.atleast_2d(np.asarray(q, float))
    T = np.linalg.inv(model.T_world_base)[None] @ model.fk(q)
    if compensation is not None:
        T = T.copy()
        T[:, :3, 3] += compensation(q)
    pose = pose_from_transform(T, c["orientation"], c["length_unit"], c["angle_unit"])
    lscale = 1000.0 if c["length_unit"] == "m" else 1.0
    pose[:, :3] = _round(pose[:, :3], resolution_mm / lscale)
    if c["orientation"] == "quaternion":
        pose[:, 3:] = _round(pose[:, 3:], math.radians(resolution_deg) / 2)
    elif c["angle_unit"] == "rad":
        pose[:, 3:] = _round(pose[:, 3:], math.radians(resolution_deg))
    else:
        pose[:, 3:] = _round(pose[:, 3:], resolution_deg)
    qc = np.degrees(q) if c["joint_unit"] == "deg" else q
    lines = [f"# virtual {controller} controller running {model.name} (robocal.sim.controller)"]
    lines += [pair_line(controller, i, qc[i], pose[i], digits=15) for i in range(len(q))]
    return "\n".join(lines) + "\n"
