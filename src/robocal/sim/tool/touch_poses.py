"""Flange poses of a touch-up (four-point) TCP calibration: the tool's tip held on one reference
point from varied tilts, built from a known TCP (the cell of ``tests/test_tcp_formulas.py`` and
``tests/test_tool_gates.py``, shared with the documented figures of docs/tcp.md). Lengths mm,
angles rad unless a name says deg."""

from __future__ import annotations

import math

import numpy as np

from ...transforms import rot_x, rot_y, rot_z

__all__ = ["P_REF_MM", "TCP_TRUE_MM", "touch_poses"]

#: the true TCP in the flange frame [mm]
TCP_TRUE_MM = np.array([12.0, -7.0, 180.0])
#: the reference point the tip touches, in the base frame [mm]
P_REF_MM = np.array([900.0, 100.0, 300.0])


def touch_poses(n: int, rng, tilt_deg=(25.0, 45.0), noise: float = 0.0, tcp=TCP_TRUE_MM) -> np.ndarray:
    """``n`` flange poses (n, 4, 4) [mm] whose TCP ``tcp`` (3,) [mm] touches :data:`P_REF_MM`: the
    tool pointing down, spread in azimuth, tilted by ``tilt_deg`` (uniform range) [deg] about varied
    axes and spun at random; ``noise`` [mm] Gaussian per coordinate on the flange position (``rng``:
    a numpy Generator)."""
    T = []
    for i in range(n):
        az = 2 * math.pi * i / n + rng.uniform(-0.3, 0.3)
        tilt = math.radians(rng.uniform(*tilt_deg))
        spin = rng.uniform(-math.pi, math.pi)
        R = rot_z(az) @ rot_x(tilt) @ rot_y(math.pi) @ rot_z(spin)
        p = P_REF_MM - R @ tcp + rng.normal(0.0, noise, 3)
        M = np.eye(4)
        M[:3, :3], M[:3, 3] = R, p
        T.append(M)
    return np.array(T)
