"""Touch-up flange poses around a known TCP (tests/test_tcp_formulas.py, tests/test_tool_gates.py
and docs/reliability.md's touch-up gate): the tool points down at a reference tip, tilted about
varied axes."""

from __future__ import annotations

import math

import numpy as np

from ...transforms import rot_x, rot_y, rot_z

__all__ = ["P_REF_MM", "TCP_TRUE_MM", "touch_poses"]

#: the true TCP in the flange frame [mm] and the reference tip in the base frame [mm]
TCP_TRUE_MM = np.array([12.0, -7.0, 180.0])
P_REF_MM = np.array([900.0, 100.0, 300.0])


def touch_poses(n: int, rng, tilt_deg=(25.0, 45.0), noise: float = 0.0, tcp=TCP_TRUE_MM) -> np.ndarray:
    """``n`` flange poses (n, 4, 4) [mm] whose TCP ``tcp`` touches ``P_REF_MM``: tool pointing down,
    azimuths spread around the circle (+-0.3 rad), tilts drawn in ``tilt_deg`` [deg], a random spin
    about the tool axis, and Gaussian position noise ``noise`` [mm] per coordinate (``rng``: a numpy
    Generator)."""
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
