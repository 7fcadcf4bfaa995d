"""The cross-laser recalibration (thesis 4.2.2 steps 1-4): plan, execute and evaluate in turn.

:func:`recalibrate_tool` runs the procedure online against an event source (a robot driver or
the simulator); :func:`evaluate_recording` evaluates recorded motions offline. Both end in the
same :class:`CrossLaserResult`: the 5-D tool frame in the flange frame [mm], its residuals and
the cycle time [s].
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ...transforms import transforms_from
from .evaluation import CircleResult, VerticalResult, evaluate_circle, evaluate_vertical
from .events import CrossLaserError, MotionRecord
from .formulas import minimal_rotation, psi_theta_from_axis
from .inputs import CrossLaserSettings, SensorFrame, sensor_frame
from .motions import pose_at_end, pose_at_start
from .planning import lifted, plan_align_circle, plan_axis_circles, plan_vertical, reposition

__all__ = ["CrossLaserResult", "recalibrate_tool", "evaluate_recording"]


@dataclass(frozen=True)
class CrossLaserResult:
    """The recalibrated tool frame and everything that led to it.

    T_flange_tool: 5-D frame: rotation = minimal rotation taking the nominal tool axis to the
    measured one, times the nominal rotation (no twist about the axis, 4-10); origin = TCP.
    axis_flange: measured tool axis (flange -> tip); psi_rad, theta_rad: (4-13) of the axis, with
    ``rotation_5d(psi, theta) @ e_z = axis``; tcp_flange_mm; steps: per-step evaluations
    (``circle1``, ``circle2``, ``circle3``: :class:`CircleResult`, ``vertical``:
    :class:`VerticalResult`); residuals: per-step residuals [mm / deg]; cycle_time_s: from the
    first motion's start to the last motion's end incl. settling; records: the executed motions.
    """

    T_flange_tool: np.ndarray
    axis_flange: np.ndarray
    tcp_flange_mm: np.ndarray
    psi_rad: float
    theta_rad: float
    steps: dict
    residuals: dict
    cycle_time_s: float
    records: tuple = ()
    settings: CrossLaserSettings = field(default_factory=CrossLaserSettings)

    def summary(self) -> dict:
        """The result as plain JSON-ready numbers (angles in degrees)."""
        return {"T_flange_tool": self.T_flange_tool.tolist(), "tcp_flange_mm": self.tcp_flange_mm.tolist(),
                "axis_flange": self.axis_flange.tolist(), "psi_deg": math.degrees(self.psi_rad),
                "theta_deg": math.degrees(self.theta_rad), "residuals": self.residuals,
                "cycle_time_s": self.cycle_time_s, "beta_correction": self.settings.beta_correction}


# ---------------------------------------------------------------------------------------------
# from the step evaluations to the result
# ---------------------------------------------------------------------------------------------


def _axis_from_circles(c1: CircleResult, c2: CircleResult):
    """(4-11, 4-12): the unit tool axis (3,) in the flange frame from the axis points of circles
    1 and 2 (from circle 2, nearer the flange, to circle 1)."""
    d = c1.axis_point_flange - c2.axis_point_flange
    n = np.linalg.norm(d)
    if n < 1e-9:
        raise CrossLaserError("circles 1 and 2 measured the same axis point (delta_z = 0?)")
    return d / n


def _residuals(c1: CircleResult, c2: CircleResult, c3: CircleResult, vert: VerticalResult, a) -> dict:
    """Per-step residuals [deg / mm]: arc spreads, the step-3 centre predicted by the steps 1-2
    axis line vs measured, and the step-4 gap and hysteresis."""
    q3 = c3.axis_point_flange
    R_sf3 = c3.R_sensor_flange
    line_pt = c1.axis_point_flange
    pred = R_sf3 @ (line_pt + a * float((q3 - line_pt) @ a)) + c3.flange_center_sensor
    return {
        "step1_angle_spread_deg": math.degrees(c1.angle_spread_rad),
        "step2_angle_spread_deg": math.degrees(c2.angle_spread_rad),
        "step3_angle_spread_deg": math.degrees(c3.angle_spread_rad),
        "step3_center_vs_axis_mm": float(np.linalg.norm(pred[:2] - c3.center_mm)),
        "step4_gap_residual_mm": vert.gap_residual_mm,
        "step4_hysteresis_x_mm": vert.hysteresis_mm["x"],
        "step4_hysteresis_y_mm": vert.hysteresis_mm["y"],
    }


def _finish(T_nom, c1, c2, c3, vert, records, settings) -> CrossLaserResult:
    """The 5-D tool frame from the four step evaluations; the cycle time from the records."""
    a = _axis_from_circles(c1, c2)
    tcp = vert.tcp_flange_mm
    R_nom = np.asarray(T_nom, float)[:3, :3]
    R_new = minimal_rotation(R_nom[:, 2], a) @ R_nom
    psi, theta = psi_theta_from_axis(a)
    T = transforms_from(R_new, tcp)
    t0 = min(r.t_start_s for r in records)
    t1 = max(r.t_start_s + r.duration_s + r.settle_s for r in records)
    return CrossLaserResult(T_flange_tool=T, axis_flange=a, tcp_flange_mm=tcp, psi_rad=psi, theta_rad=theta,
                            steps={"circle1": c1, "circle2": c2, "circle3": c3, "vertical": vert},
                            residuals=_residuals(c1, c2, c3, vert, a), cycle_time_s=float(t1 - t0),
                            records=tuple(records), settings=settings)


# ---------------------------------------------------------------------------------------------
# online: the four steps against an event source
# ---------------------------------------------------------------------------------------------


class _Execution:
    """The motions of one recalibration sent to ``source`` in order, and their records."""

    def __init__(self, source, sensor: SensorFrame, settings: CrossLaserSettings):
        self.source = source
        self.sensor = sensor
        self.settings = settings
        self.records: list = []

    def run(self, motion) -> MotionRecord:
        rec = self.source.run(motion)
        self.records.append(rec)
        return rec

    def move(self, start_T, end_T, step: int, role: str) -> MotionRecord:
        return self.run(reposition(start_T, end_T, self.settings, step, role))

    def circle(self, motion) -> CircleResult:
        return evaluate_circle(self.run(motion), self.sensor, self.settings)


def _approach(ex: _Execution, circle1, start_pose):
    """From ``start_pose`` (or from above circle 1) down to the start of circle 1; returns the
    pose (4, 4) to return to at the end."""
    s = ex.settings
    first = pose_at_start(circle1)
    above = lifted(first, ex.sensor, s.clearance_mm + s.cut_from_tip_mm)
    home = above if start_pose is None else np.asarray(start_pose, float)
    if start_pose is not None:
        ex.move(home, above, 0, "approach")
    ex.move(above, first, 1, "descend")
    return home


def _measure_axis(ex: _Execution, circle1, circle2):
    """Steps 1 and 2: the two circles ``delta_z`` apart, evaluated."""
    r1 = ex.circle(circle1)
    ex.move(pose_at_end(circle1), pose_at_start(circle2), 2, "lower")
    r2 = ex.circle(circle2)
    return r1, r2


def _align_axis(ex: _Execution, T_nom, r1: CircleResult, axis, circle2):
    """Step 3: re-orient so the measured axis is parallel to ``-Z_s``, circle, evaluate."""
    s = ex.settings
    if s.step3_center == "axis":
        p3 = r1.axis_point_flange
    else:
        p3 = T_nom[:3, 3] - s.cut_from_tip_mm * T_nom[:3, 2]
    circle3 = plan_align_circle(ex.sensor, axis, p3, s)
    raised = ex.move(pose_at_end(circle2), lifted(pose_at_end(circle2), ex.sensor, s.delta_z_mm), 3, "raise")
    ex.move(pose_at_end(raised.motion), pose_at_start(circle3), 3, "reorient")
    return ex.circle(circle3), circle3


def _measure_tcp(ex: _Execution, r1: CircleResult, r3: CircleResult, axis, circle3):
    """Step 4: centre the axis on ``Z_s``, move down and up through the beams, evaluate (4-14).
    Returns the :class:`VerticalResult` and the up move."""
    s = ex.settings
    tip_dist = s.cut_from_tip_mm + float((r1.axis_point_flange - r3.axis_point_flange) @ axis)
    down, up = plan_vertical(ex.sensor, r3.R_sensor_flange, r3.axis_point_flange, axis, tip_dist, s)
    lift = ex.move(pose_at_end(circle3), lifted(pose_at_end(circle3), ex.sensor, s.clearance_mm), 4, "lift")
    ex.move(pose_at_end(lift.motion), pose_at_start(down), 4, "center")
    rd = ex.run(down)
    ru = ex.run(up)
    return evaluate_vertical(rd, ru, ex.sensor), up


def recalibrate_tool(source, sensor, T_flange_tool_nominal, settings: CrossLaserSettings = CrossLaserSettings(),
                     *, start_pose=None) -> CrossLaserResult:
    """Run the full cross-laser recalibration online (thesis 4.2.2 steps 1-4).

    source: an event source with ``run(motion) -> MotionRecord`` (the simulator
    :class:`robocal.sim.tool.light_barrier.LightBarrierCell`, or a robot driver). sensor: the sensor
    calibration (``SensorCalibration``, dict or :class:`SensorFrame`). T_flange_tool_nominal:
    the current tool estimate (4x4, flange frame; its z axis is the tool axis, its origin the tip).
    start_pose: flange pose (4x4, base) before the procedure (default: above the first circle);
    the procedure approaches from it and returns to it, both counted in the cycle time.

    Steps: (1, 2) circles at two heights -> axis points -> tool axis; (3) re-orient so the axis
    is parallel to -Z_s, circle -> centre, move the axis onto Z_s; (4) vertical down/up through
    the beams -> TCP in the flange frame. Returns :class:`CrossLaserResult`.
    """
    sensor = sensor_frame(sensor)
    T_nom = np.asarray(T_flange_tool_nominal, float)
    ex = _Execution(source, sensor, settings)
    circle1, circle2 = plan_axis_circles(sensor, T_nom, settings)
    home = _approach(ex, circle1, start_pose)
    r1, r2 = _measure_axis(ex, circle1, circle2)
    axis = _axis_from_circles(r1, r2)
    r3, circle3 = _align_axis(ex, T_nom, r1, axis, circle2)
    vert, up = _measure_tcp(ex, r1, r3, axis, circle3)
    ex.move(pose_at_end(up), lifted(pose_at_end(up), sensor, settings.clearance_mm), 4, "retract")
    if start_pose is not None:
        ex.move(pose_at_end(ex.records[-1].motion), home, 4, "return")
    return _finish(T_nom, r1, r2, r3, vert, ex.records, settings)


# ---------------------------------------------------------------------------------------------
# offline: recorded motions
# ---------------------------------------------------------------------------------------------


def evaluate_recording(records, sensor, T_flange_tool_nominal, settings: CrossLaserSettings = CrossLaserSettings()):
    """Evaluate recorded motions (e.g. from :func:`robocal.io.barrier_events.read_events_csv`) offline.

    Needs the circles of steps 1, 2, 3 (roles ``circle1``, ``circle2``, ``circle3``) and the
    step-4 ``down`` and ``up`` moves; other motions only count in the cycle time.
    """
    sensor = sensor_frame(sensor)
    by_role = {}
    for r in records:
        by_role.setdefault(r.motion.role, r)
    missing = [k for k in ("circle1", "circle2", "circle3", "down", "up") if k not in by_role]
    if missing:
        raise CrossLaserError(f"recording lacks the motions {', '.join(missing)}")
    r1, r2, r3 = (evaluate_circle(by_role[k], sensor, settings) for k in ("circle1", "circle2", "circle3"))
    vert = evaluate_vertical(by_role["down"], by_role["up"], sensor)
    return _finish(np.asarray(T_flange_tool_nominal, float), r1, r2, r3, vert, list(records), settings)
