"""What the cross-laser method is given: the sensor frame (from the sensor calibration) and the
settings of the procedure (motion speeds and sizes, evaluation switches).

Lengths in mm, angles in rad inside (names ending ``_deg`` are degrees), times in s.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["SensorFrame", "sensor_frame", "CrossLaserSettings"]


@dataclass(frozen=True)
class SensorFrame:
    """What the method needs of the sensor calibration (any object with these attributes works).

    T_base_sensor (4, 4): the orthogonal sensor frame in the base frame [mm]; beta_rad: angle from
    the X beam to the Y beam about Z_s; gap_mm: distance between the beams along Z_s.
    """

    T_base_sensor: np.ndarray
    beta_rad: float
    gap_mm: float = 0.0

    @property
    def origin_mm(self) -> np.ndarray:
        return self.T_base_sensor[:3, 3]

    @property
    def R_base_sensor(self) -> np.ndarray:
        return self.T_base_sensor[:3, :3]

    def to_base(self, p_s) -> np.ndarray:
        """Points (..., 3) [mm] from the sensor frame to the base frame."""
        return self.origin_mm + np.asarray(p_s, float) @ self.R_base_sensor.T

    def to_sensor(self, p_b) -> np.ndarray:
        """Points (..., 3) [mm] from the base frame to the sensor frame."""
        return (np.asarray(p_b, float) - self.origin_mm) @ self.R_base_sensor


def sensor_frame(obj) -> SensorFrame:
    """A :class:`SensorFrame` from a ``SensorCalibration``, a SensorFrame or a dict with keys
    ``T_base_sensor`` and ``beta_deg`` (optional ``gap_mm``), e.g. ``sensor-calibrate --json``."""
    if isinstance(obj, SensorFrame):
        return obj
    if isinstance(obj, dict):
        T, beta_deg, gap = obj["T_base_sensor"], obj.get("beta_deg", 90.0), obj.get("gap_mm", 0.0)
    else:
        T, beta_deg, gap = obj.T_base_sensor, obj.beta_deg, getattr(obj, "gap_mm", 0.0)
    T = np.array(T, dtype=float)
    if T.shape != (4, 4):
        raise ValueError(f"T_base_sensor: expected 4x4, got {T.shape}")
    T.setflags(write=False)
    return SensorFrame(T_base_sensor=T, beta_rad=math.radians(float(beta_deg)), gap_mm=float(gap))


@dataclass(frozen=True)
class CrossLaserSettings:
    """Motion and evaluation parameters of the cross-laser procedure.

    radius_mm: circle radius R (must exceed the tool's offset from its estimate plus its radius);
    circle_speed_mm_s / accel_mm_s2: path speed and acceleration of the circles;
    sweep_deg: measured sweep of each circle (>= 360 + 90 so four arcs of one full period are
    seen in order; the ramps are added before and after); start_angle_deg: angle of the first
    measured point (45 = between the beams); direction: +1 counter-clockwise about Z_s, -1
    clockwise; cut_from_tip_mm: distance from the estimated tip to where the beam plane cuts the
    tool on the first (and third) circle; delta_z_mm: height difference of the two circles (4-11);
    vertical_speed_mm_s / vertical_travel_mm: speed and half travel (tip above/below the beams) of
    the step-4 moves; move_speed_mm_s / angular_speed_deg_s: the other (repositioning) moves;
    clearance_mm: height of the tip above the beams for approach and retract; beta_correction:
    apply (4-29) (switch off to see the error (4-30)); arc_correction: the blocked-arc correction
    of (4-9) (package docstring); step3_center: where the step-3 circle is centred: ``"axis"``
    puts the axis line measured in steps 1-2 on the origin, so step 3 is a null measurement that
    only corrects what steps 1-2 got wrong (insensitive to beta, R and arc-width errors);
    ``"nominal"`` centres the *initial* estimate's axis point, as the thesis does (its step 3
    measures the full lateral offset of the bent tool and then moves by it).
    """

    radius_mm: float = 25.0
    circle_speed_mm_s: float = 120.0
    accel_mm_s2: float = 2000.0
    sweep_deg: float = 540.0
    start_angle_deg: float = 45.0
    direction: int = 1
    cut_from_tip_mm: float = 15.0
    delta_z_mm: float = 80.0
    vertical_speed_mm_s: float = 20.0
    vertical_travel_mm: float = 6.0
    move_speed_mm_s: float = 250.0
    angular_speed_deg_s: float = 90.0
    clearance_mm: float = 20.0
    beta_correction: bool = True
    arc_correction: bool = True
    step3_center: str = "axis"

    def __post_init__(self):
        if self.step3_center not in ("axis", "nominal"):
            raise ValueError("step3_center must be 'axis' or 'nominal'")
        if self.direction not in (1, -1):
            raise ValueError("direction must be +1 or -1")
        if self.sweep_deg < 450:
            raise ValueError("sweep_deg must be >= 450 (one full period of arcs plus one)")
        for name in ("radius_mm", "circle_speed_mm_s", "accel_mm_s2", "delta_z_mm", "vertical_speed_mm_s",
                     "vertical_travel_mm", "move_speed_mm_s", "angular_speed_deg_s"):
            if not getattr(self, name) > 0:
                raise ValueError(f"{name} must be > 0")
