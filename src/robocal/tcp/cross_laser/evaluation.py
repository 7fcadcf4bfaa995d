"""Evaluation of the measuring motions: one circle (4-8, 4-9, the centre and the tool-axis point)
and the step-4 vertical moves (4-14, the TCP).

Inputs are :class:`~robocal.tcp.cross_laser.MotionRecord` s; lengths in mm, angles in rad,
times in s.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .events import CrossLaserError, MotionRecord, arc_durations, beam_crossings, switch_positions
from .formulas import angles_from_durations, center_distances, circle_center, tcp_in_flange
from .inputs import CrossLaserSettings, sensor_frame

__all__ = ["CircleResult", "VerticalResult", "evaluate_circle", "evaluate_vertical"]


@dataclass(frozen=True)
class CircleResult:
    """Evaluation of one measuring circle.

    angles_rad (4,): arcs 1..4 (4-8); d_x_mm, d_y_mm: (4-9); center_mm (2,): circle centre of the
    tool's axis point in the orthogonal sensor frame (beta-corrected if asked); arc_widths_rad:
    blocked arcs (delta_x, delta_y); period_s; n_arcs: arcs averaged; angle_spread_rad: largest
    spread of one arc over repeated periods (a residual); axis_point_flange (3,): the tool-axis
    point in the flange frame; R_sensor_flange (3, 3): flange orientation during the circle;
    flange_center_sensor (3,): the programmed circle centre in the sensor frame.
    """

    angles_rad: np.ndarray
    d_x_mm: float
    d_y_mm: float
    center_mm: np.ndarray
    arc_widths_rad: tuple
    period_s: float
    n_arcs: int
    angle_spread_rad: float
    axis_point_flange: np.ndarray
    R_sensor_flange: np.ndarray
    flange_center_sensor: np.ndarray


def evaluate_circle(record: MotionRecord, sensor, settings: CrossLaserSettings = CrossLaserSettings()) -> CircleResult:
    """(4-8), (4-9) and the centre for one circle record (the tool axis point in the flange frame).

    Crossings = middles of blocked intervals inside the constant-speed part of the circle; each is
    labelled X+/X-/Y+/Y- from the programmed angle at that time; consecutive crossings give arcs
    1..4, averaged over all periods seen; (4-8) normalizes them by their sum.
    """
    sensor = sensor_frame(sensor)
    m = record.motion
    if getattr(m, "kind", None) != "circle":
        raise CrossLaserError("evaluate_circle needs a circle motion")
    crossings, widths = beam_crossings(record, sensor)
    per = arc_durations(crossings, m.step)
    mean = np.array([np.mean(p) for p in per])
    period = mean.sum()
    angles = angles_from_durations(mean)
    omega = 2 * np.pi / period
    spread = max((max(p) - min(p)) * omega for p in per)
    widths_rad = (omega * float(np.mean(widths["x"])), omega * float(np.mean(widths["y"])))
    d_x, d_y = center_distances(angles, m.radius_mm, widths_rad if settings.arc_correction else (0.0, 0.0))
    c = circle_center(d_x, d_y, sensor.beta_rad, settings.beta_correction)
    R_sf = sensor.R_base_sensor.T @ m.R_base_flange
    F_s = sensor.to_sensor(m.center_mm)
    q = R_sf.T @ (np.array([c[0], c[1], 0.0]) - F_s)
    return CircleResult(angles_rad=angles, d_x_mm=float(d_x), d_y_mm=float(d_y), center_mm=c,
                        arc_widths_rad=(float(widths_rad[0]), float(widths_rad[1])),
                        period_s=float(period), n_arcs=sum(len(p) for p in per), angle_spread_rad=float(spread),
                        axis_point_flange=q, R_sensor_flange=R_sf, flange_center_sensor=F_s)


@dataclass(frozen=True)
class VerticalResult:
    """Step 4: flange positions at the four events (base frame), their mean p_e, the TCP (4-14,
    flange frame), the beam heights found (sensor Z) and residuals [mm]."""

    flange_positions_mm: dict
    flange_mean_mm: np.ndarray
    tcp_flange_mm: np.ndarray
    beam_heights_mm: dict
    gap_residual_mm: float
    hysteresis_mm: dict


def evaluate_vertical(down: MotionRecord, up: MotionRecord, sensor) -> VerticalResult:
    """(4-14) in the flange frame from the step-4 down/up moves: X and Y beams blocked while
    going down, clear while going up; p_e = mean of the four flange positions."""
    sensor = sensor_frame(sensor)
    pos = switch_positions(down, up)
    p_e = np.mean(list(pos.values()), axis=0)
    R_bf = down.motion.R_start
    tcp = tcp_in_flange(sensor.origin_mm, p_e, R_bf)
    # height of each beam relative to O_s: where the tip was when it switched = flange height - p_e height
    z = {k: float(sensor.to_sensor(v)[2] - sensor.to_sensor(p_e)[2]) for k, v in pos.items()}
    hx = 0.5 * (z["x_blocked"] + z["x_clear"])
    hy = 0.5 * (z["y_blocked"] + z["y_clear"])
    return VerticalResult(flange_positions_mm=pos, flange_mean_mm=p_e, tcp_flange_mm=tcp,
                          beam_heights_mm={"x": hx, "y": hy},
                          gap_residual_mm=float(abs(hy - hx) - sensor.gap_mm),
                          hysteresis_mm={b: float(z[f"{b}_clear"] - z[f"{b}_blocked"]) for b in ("x", "y")})
