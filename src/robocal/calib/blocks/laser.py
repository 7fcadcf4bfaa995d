"""The laser pointer's mount on the flange: the closed-chain paper's eq. 3 (METHODS.md section 3).

``T_flange_laser = T0 . Rx(theta_x) . Ry(theta_y) . Tx(px) . Ty(py)``: a nominal mount ``T0``
(identity when the beam leaves the flange centre along Z6, as in the paper) and four small errors,
two rotations about the flange's x and y axes and two offsets across the beam. The beam is the
laser frame's +z axis from its origin. A shift along the beam and a rotation about it move no
spot: they are not parameters (the "ray's own DOF").
"""

from __future__ import annotations

import numpy as np

from ...transforms import skew
from .manifolds import VectorBlock

__all__ = ["LaserMount", "LASER_MOUNT_VARIABLES"]

#: variable suffixes and units of the mount (eq. 3)
LASER_MOUNT_VARIABLES = (("theta_x", "rad"), ("theta_y", "rad"), ("px", "mm"), ("py", "mm"))


def _rx(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def _ry(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


class LaserMount(VectorBlock):
    """(theta_x, theta_y [rad], px, py [mm]) of eq. 3, additive; ``T0`` (4, 4) the nominal mount
    ``T_flange_laser`` [mm]. Variables ``<name>.theta_x`` ... ``<name>.py``; identifiability group
    ``"targets"`` (the mount is kept in preference to robot parameters it trades off against, like a
    tool frame)."""

    group = "targets"

    def __init__(self, initial=(0.0, 0.0, 0.0, 0.0), *, T0=None, name: str = "laser", free=True, prior=None):
        names = [f"{name}.{v}" for v, _ in LASER_MOUNT_VARIABLES]
        units = [u for _, u in LASER_MOUNT_VARIABLES]
        super().__init__(name, names, units, np.asarray(initial, dtype=float).reshape(4), free=free, prior=prior)
        self.T0 = np.eye(4) if T0 is None else np.asarray(T0, dtype=float).reshape(4, 4).copy()

    def transform(self, value) -> np.ndarray:
        """``T_flange_laser`` (4, 4) [mm] of the mount ``value`` (4,)."""
        tx, ty, px, py = np.asarray(value, dtype=float)
        R = _rx(tx) @ _ry(ty)
        T = np.eye(4)
        T[:3, :3] = R
        T[:3, 3] = R @ np.array([px, py, 0.0])
        return self.T0 @ T

    def beam_points(self, value, length_mm: float):
        """The beam's origin and the point ``length_mm`` along it, in the flange frame:
        ``(points (2, 3) [mm], d points / d value (2, 3, 4))``."""
        tx, ty, px, py = np.asarray(value, dtype=float)
        Rx, Ry = _rx(tx), _ry(ty)
        R = Rx @ Ry
        ex, ey, ez = np.eye(3)
        v = np.array([px, py, 0.0])
        origin, axis = R @ v, R @ ez
        d_origin = np.stack([Rx @ skew(ex) @ Ry @ v, R @ skew(ey) @ v, R @ ex, R @ ey], axis=1)  # (3, 4)
        d_axis = np.stack([Rx @ skew(ex) @ Ry @ ez, R @ skew(ey) @ ez, np.zeros(3), np.zeros(3)], axis=1)
        R0, t0 = self.T0[:3, :3], self.T0[:3, 3]
        pts = np.stack([origin, origin + length_mm * axis]) @ R0.T + t0
        dpts = np.einsum("ij,kjc->kic", R0, np.stack([d_origin, d_origin + length_mm * d_axis]))
        return pts, dpts
