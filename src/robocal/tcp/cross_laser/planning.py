"""The motion plan of the cross-laser procedure (thesis 4.2.2 steps 1-4): where the circles and
the lines go, in the sensor frame, for a given tool estimate.

The flange is held so the tool axis points along ``-Z_s`` (:func:`measuring_orientation`);
circles run about ``Z_s`` through the sensor origin's neighbourhood, the step-4 moves along
``Z_s``. Positions in mm, angles in rad (``settings`` fields ending ``_deg`` are degrees).
"""

from __future__ import annotations

import math

import numpy as np

from ...transforms import rot_x
from .formulas import minimal_rotation
from .inputs import CrossLaserSettings, SensorFrame, sensor_frame
from .motions import CircleMove, LinearMove

__all__ = ["measuring_orientation", "plan_axis_circles", "plan_align_circle", "plan_vertical"]

_RX_PI = rot_x(np.pi)  # flange X_e = X_s, Y_e = -Y_s, Z_e = -Z_s (thesis figure 4-8)


def measuring_orientation(axis_flange) -> np.ndarray:
    """``R_sensor_flange`` (3, 3) that points the tool axis (3,) (flange frame) along ``-Z_s`` with
    no twist: ``Rx(pi) R5^T`` with ``R5`` the minimal rotation ``e_z -> axis``; ``Rx(pi)`` (the
    thesis's orientation) for a tool along the flange Z axis."""
    return _RX_PI @ minimal_rotation([0, 0, 1.0], axis_flange).T


def _circle_motion(sensor: SensorFrame, center_s, R_sensor_flange, settings: CrossLaserSettings, step, role):
    """A measuring circle about ``Z_s`` with the flange centre at ``center_s`` (3,) [mm, sensor];
    the speed ramps are added before and after the measured sweep."""
    d = settings.direction
    ramp = settings.circle_speed_mm_s ** 2 / (2 * settings.accel_mm_s2) / settings.radius_mm + math.radians(5.0)
    start = math.radians(settings.start_angle_deg) - d * ramp
    sweep = d * (math.radians(settings.sweep_deg) + 2 * ramp)
    Rb = sensor.R_base_sensor
    return CircleMove(center_mm=sensor.to_base(center_s), radius_mm=settings.radius_mm, normal=Rb[:, 2],
                      ref_dir=Rb[:, 0], start_angle_rad=start, sweep_rad=sweep, speed_mm_s=settings.circle_speed_mm_s,
                      accel_mm_s2=settings.accel_mm_s2, R_base_flange=Rb @ R_sensor_flange, step=step, role=role)


def _flange_center_for(point_flange, R_sensor_flange, height_s=0.0):
    """Flange position (sensor frame) that puts the flange point ``point_flange`` at (0, 0, h)."""
    return np.array([0.0, 0.0, height_s]) - R_sensor_flange @ np.asarray(point_flange, float)


def plan_axis_circles(sensor, T_flange_tool_estimate, settings: CrossLaserSettings = CrossLaserSettings()):
    """Steps 1 and 2: two circles about ``Z_s`` whose centres put the *estimated* tool axis on
    the sensor origin, the beam plane cutting the tool ``cut_from_tip_mm`` and ``cut_from_tip_mm
    + delta_z_mm`` from the estimated tip; the second circle is ``delta_z_mm`` lower.
    ``T_flange_tool_estimate`` (4, 4) [mm]. Returns two :class:`CircleMove` s."""
    sensor = sensor_frame(sensor)
    T = np.asarray(T_flange_tool_estimate, float)
    a, tip = T[:3, 2], T[:3, 3]
    R_sf = measuring_orientation(a)
    out = []
    for k, u in enumerate((settings.cut_from_tip_mm, settings.cut_from_tip_mm + settings.delta_z_mm), 1):
        F = _flange_center_for(tip - u * a, R_sf)
        out.append(_circle_motion(sensor, F, R_sf, settings, step=k, role=f"circle{k}"))
    return tuple(out)


def plan_align_circle(sensor, axis_flange, axis_point_flange, settings: CrossLaserSettings = CrossLaserSettings()):
    """Step 3: the flange re-oriented so the measured axis (3,) is parallel to ``-Z_s`` (4-10,
    4-13), and placed so the measured axis point ``axis_point_flange`` (3,) [mm] is on the sensor
    origin; one circle."""
    sensor = sensor_frame(sensor)
    R_sf = measuring_orientation(axis_flange)
    F = _flange_center_for(axis_point_flange, R_sf)
    return _circle_motion(sensor, F, R_sf, settings, step=3, role="circle3")


def plan_vertical(sensor, R_sensor_flange, axis_point_flange, axis_flange, tip_distance_mm,
                  settings: CrossLaserSettings = CrossLaserSettings()):
    """Step 4: the tool axis on ``Z_s`` (the centred position), the estimated tip
    ``vertical_travel_mm`` above the beams; move down to ``vertical_travel_mm`` below, then back up.

    ``tip_distance_mm``: estimated distance from ``axis_point_flange`` to the tip along the axis.
    Returns ``(down, up)`` :class:`LinearMove` s.
    """
    sensor = sensor_frame(sensor)
    a = np.asarray(axis_flange, float) / np.linalg.norm(axis_flange)
    tip = np.asarray(axis_point_flange, float) + tip_distance_mm * a
    h = settings.vertical_travel_mm
    top = _flange_center_for(tip, R_sensor_flange, +h)
    bottom = _flange_center_for(tip, R_sensor_flange, -h)
    Rb = sensor.R_base_sensor @ R_sensor_flange
    kw = dict(speed_mm_s=settings.vertical_speed_mm_s, angular_speed_rad_s=math.radians(settings.angular_speed_deg_s),
              accel_mm_s2=settings.accel_mm_s2, step=4)
    down = LinearMove(sensor.to_base(top), sensor.to_base(bottom), Rb, Rb, role="down", **kw)
    up = LinearMove(sensor.to_base(bottom), sensor.to_base(top), Rb, Rb, role="up", **kw)
    return down, up


def reposition(start_T, end_T, settings: CrossLaserSettings, step, role) -> LinearMove:
    """A repositioning ``movel`` between two flange poses (4, 4) at the settings' move speeds."""
    return LinearMove(start_T[:3, 3], end_T[:3, 3], start_T[:3, :3], end_T[:3, :3],
                      speed_mm_s=settings.move_speed_mm_s, angular_speed_rad_s=math.radians(settings.angular_speed_deg_s),
                      accel_mm_s2=settings.accel_mm_s2, step=step, role=role)


def lifted(T, sensor: SensorFrame, dz) -> np.ndarray:
    """The flange pose ``T`` (4, 4) moved by ``dz`` [mm] along ``Z_s``."""
    out = np.array(T, float)
    out[:3, 3] = out[:3, 3] + dz * sensor.R_base_sensor[:, 2]
    return out
