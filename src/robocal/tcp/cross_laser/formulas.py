"""The cross-laser method's equations (thesis 4-8 ... 4-14) and the beta correction, on numbers.

Arcs are named by the quadrant they sweep (see :mod:`robocal.tcp.cross_laser`): ``angle 1``
X+ -> Y+, ``angle 2`` Y+ -> X-, ``angle 3`` X- -> Y-, ``angle 4`` Y- -> X+. Lengths in mm,
angles in rad. Nothing here knows about motions, events or files.
"""

from __future__ import annotations

import math

import numpy as np

from ...transforms import rot_x, rot_z, so3_exp
from ..sensor import center_from_beam_distances

__all__ = [
    "angles_from_durations",
    "center_distances",
    "circle_center",
    "axis_vector_thesis",
    "euler_psi_theta",
    "rotation_5d",
    "psi_theta_from_axis",
    "minimal_rotation",
    "tcp_in_flange",
]


def angles_from_durations(durations) -> np.ndarray:
    """(4-8): ``angle_i = 2 pi t_i / (t1 + t2 + t3 + t4)`` [rad] from the four arc durations."""
    t = np.asarray(durations, dtype=float)
    if t.shape[-1] != 4 or np.any(t <= 0):
        raise ValueError(f"expected four positive durations, got {t}")
    return 2 * np.pi * t / t.sum(axis=-1, keepdims=True)


def center_distances(angles, radius_mm: float, arc_widths_rad=(0.0, 0.0)):
    """(4-9): signed distances ``(d_x, d_y)`` [mm] of the circle centre to the X and Y beams.

    ``angles`` (4,): the arcs 1..4 [rad] (quadrant names, see the module docstring). ``d_x = R'
    cos((a3 + a4)/2)``, ``d_y = R'' cos((a2 + a3)/2)`` with ``R' = R cos(delta_x / 2)``, ``R'' = R
    cos(delta_y / 2)`` (arc-width correction; ``arc_widths_rad = (delta_x, delta_y)`` = 0 gives the
    thesis's formula).
    """
    a = np.asarray(angles, dtype=float)
    dlx, dly = arc_widths_rad
    d_x = radius_mm * math.cos(0.5 * dlx) * np.cos(0.5 * (a[..., 2] + a[..., 3]))
    d_y = radius_mm * math.cos(0.5 * dly) * np.cos(0.5 * (a[..., 1] + a[..., 2]))
    return d_x, d_y


def circle_center(d_x, d_y, beta_rad: float, beta_correction: bool = True) -> np.ndarray:
    """Circle centre ``(x, y)`` (2,) [mm] in the orthogonal sensor frame from the beam distances.

    With ``beta_correction`` (4-29) via :func:`robocal.tcp.sensor.center_from_beam_distances`;
    without it the thesis's uncorrected ``(d_y, d_x)``, whose x error is (4-30).
    """
    if beta_correction:
        x, y = center_from_beam_distances(d_x, d_y, beta_rad)
        return np.array([float(x), float(y)])
    return np.array([float(d_y), float(d_x)])


def axis_vector_thesis(center1, center2, dz_mm: float) -> np.ndarray:
    """(4-12) as printed: ``(d_y2 - d_y1, d_x1 - d_x2, dz)`` (3,) from the centres ``(d_y, d_x)``.

    Valid only for the thesis's set-up (flange X_e = X_s, Y_e = -Y_s, Z_e = -Z_s, both circles
    centred on the sensor origin, circle 2 ``dz`` lower). It is the tool axis mirrored in x and y:
    the true axis (flange -> tip) in the flange frame is ``(-v_x, -v_y, v_z)``; feeding this vector
    to (4-13) and (4-10) gives a frame whose z column is the true axis (the two sign flips cancel).
    """
    c1 = np.asarray(center1, float)
    c2 = np.asarray(center2, float)
    return np.array([c2[0] - c1[0], c1[1] - c2[1], float(dz_mm)])


def euler_psi_theta(delta) -> tuple:
    """(4-13) as printed: ``psi = sign(-dx) arccos(dy / rho)``, ``theta = arccos(dz / |d|)`` [rad].

    ``psi`` in [-pi, pi), ``theta`` in [0, pi). The sign factor ``-dx/|-dx|`` is undefined for
    ``dx = 0``; then ``psi = arccos(dy / rho)`` >= 0. For ``dx = dy = 0`` psi is 0.
    """
    dx, dy, dz = (float(v) for v in delta)
    rho = math.hypot(dx, dy)
    theta = math.acos(max(-1.0, min(1.0, dz / math.sqrt(rho * rho + dz * dz))))
    if rho < 1e-15:
        return 0.0, theta
    psi = math.acos(max(-1.0, min(1.0, dy / rho)))
    if -dx < 0:
        psi = -psi
    if psi >= math.pi:
        psi -= 2 * math.pi
    return psi, theta


def rotation_5d(psi: float, theta: float) -> np.ndarray:
    """(4-10): ``Rz(psi) Rx(theta) Rz(-psi)`` (3, 3), a rotation by theta about ``(cos psi, sin psi, 0)``:
    the 5-D frame, no rotation about the tool's own axis. Its z column is
    ``(sin psi sin theta, -cos psi sin theta, cos theta)``."""
    return rot_z(psi) @ rot_x(theta) @ rot_z(-psi)


def psi_theta_from_axis(axis) -> tuple:
    """``(psi, theta)`` [rad] with ``rotation_5d(psi, theta) @ e_z = axis / |axis|``.

    Equal to :func:`euler_psi_theta` applied to ``(-a_x, -a_y, a_z)`` (the thesis's (4-12)
    vector), i.e. ``psi = atan2(a_x, -a_y)``, ``theta = arccos(a_z)``.
    """
    return euler_psi_theta((-axis[0], -axis[1], axis[2]))


def minimal_rotation(u, v) -> np.ndarray:
    """The rotation (3, 3) of smallest angle taking direction ``u`` (3,) to ``v`` (3,) (about ``u x v``).

    For ``u = e_z`` this is :func:`rotation_5d` of :func:`psi_theta_from_axis` ``(v)``.
    """
    u = np.asarray(u, float) / np.linalg.norm(u)
    v = np.asarray(v, float) / np.linalg.norm(v)
    w = np.cross(u, v)
    s, c = np.linalg.norm(w), float(u @ v)
    if s < 1e-15:
        if c > 0:
            return np.eye(3)
        k = np.cross(u, [1.0, 0, 0] if abs(u[0]) < 0.9 else [0, 1.0, 0])
        return so3_exp(np.pi * k / np.linalg.norm(k))
    return so3_exp(w / s * math.atan2(s, c))


def tcp_in_flange(origin_base, flange_base, R_base_flange) -> np.ndarray:
    """(4-14) in the flange frame: the TCP ``t = R_base_flange^T (O_s - p_e)`` (3,) [mm].

    ``origin_base`` (3,): the sensor origin O_s; ``flange_base`` (3,): the flange position p_e
    with the TCP at O_s; ``R_base_flange`` (3, 3): the flange orientation at that moment. The
    thesis's (4-14) ``O_s - p_e`` is this vector in base coordinates; it is the TCP only when the
    flange is aligned with the base.
    """
    return np.asarray(R_base_flange, float).T @ (np.asarray(origin_base, float) - np.asarray(flange_base, float))
