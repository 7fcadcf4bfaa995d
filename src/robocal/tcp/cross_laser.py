"""The cross-laser tool-frame recalibration (thesis 4.2, 4.3.2): plan the motions, evaluate them.

Two light barriers cross at the sensor origin ``O_s`` (see :mod:`robocal.tcp.sensor` for the
sensor frame and the beta correction). The robot holds the tool perpendicular to the beam plane
and moves it on circles of radius ``R`` at constant speed; the four beam interruptions split the
period into four arcs, from which the circle centre follows. Two circles ``dz`` apart give the
tool axis, a third circle after re-aligning the axis with ``Z_s`` centres it, and vertical moves
through the beams give the TCP. The result is the 5-D tool frame in the flange frame.

Frames and signs (all verified against the simulator :mod:`robocal.sim.light_barrier` in
``tests/test_cross_laser.py``):

- Sensor frame S = the orthogonal frame ``T_base_sensor`` of the calibration (X_s along the X
  beam, Y_s' orthogonal to it in the beam plane, Z_s = X_s x Y_beam). Circles run about ``+Z_s``
  (counter-clockwise seen from +Z_s) unless ``direction = -1``; angle 0 is ``+X_s``.
- The four arcs are named by the quadrant they sweep (thesis figure 4-5): ``angle 1`` between the
  crossing of the X beam on its ``+X_s`` half ("X+") and the crossing of the Y beam on its
  positive half ("Y+"), ``angle 2`` Y+ -> X-, ``angle 3`` X- -> Y-, ``angle 4`` Y- -> X+.
  With these names (4-9) gives ``d_x = R cos((a3 + a4)/2)`` = signed distance of the circle centre
  to the X beam, positive on the +Y_s' side, and ``d_y = R cos((a2 + a3)/2)`` = signed distance
  to the Y beam, positive on the +X_s side; the centre is ``(d_y, d_x)`` for orthogonal beams and
  :func:`robocal.tcp.sensor.center_from_beam_distances` (4-29) otherwise (the beta correction).
- The tool's axis direction ``a`` points from the flange to the tip (the tool frame's Z axis).

Beyond the thesis (documented, switchable):

- *arc-width correction*: the tool is a cylinder of radius r, so each beam is blocked over an
  arc, and the crossing time is taken as the middle of the blocked interval. On a circle the
  middle of the blocked arc is not the crossing of the beam line: exactly, it is the crossing of
  a circle of radius ``R cos(delta/2)`` (delta = the blocked arc of that beam, the same for both
  crossings of one beam). (4-9) therefore uses ``R cos(delta/2)``; without it the centre is
  scaled by ``cos(delta/2)`` (1 % for r = 3 mm, R = 25 mm).
- (4-14) is applied in the flange frame: ``t = R_base_flange^T (O_s - p_e)``; the thesis
  subtracts base-frame coordinates (METHODS.md section 7).
- The tool axis is obtained as two points on the axis in the flange frame (one per circle),
  which is (4-11, 4-12) for the thesis's flange orientation and valid for any orientation.
  (4-12) printed as ``(d_y2 - d_y1, d_x1 - d_x2, dz)`` is the mirror image of the axis in x and y;
  combined with (4-13) and (4-10), whose ``R`` has the z column ``(-dx, -dy, dz)/|.|``, the
  thesis's chain still yields the right axis (see :func:`axis_vector_thesis`).

Units: mm, s, rad inside. ``T_a_b`` = pose of b in a.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field

import numpy as np

from ..transforms import rot_x, rot_z, so3_exp, so3_log, transforms_from
from .sensor import center_from_beam_distances

__all__ = [
    "BarrierEvent",
    "MotionRecord",
    "CircleMove",
    "LinearMove",
    "motion_from_dict",
    "SensorFrame",
    "sensor_frame",
    "CrossLaserSettings",
    "CircleResult",
    "VerticalResult",
    "CrossLaserResult",
    "CrossLaserError",
    "angles_from_durations",
    "center_distances",
    "circle_center",
    "axis_vector_thesis",
    "euler_psi_theta",
    "rotation_5d",
    "psi_theta_from_axis",
    "minimal_rotation",
    "tcp_in_flange",
    "plan_axis_circles",
    "plan_align_circle",
    "plan_vertical",
    "evaluate_circle",
    "evaluate_vertical",
    "recalibrate_tool",
    "evaluate_recording",
    "read_events_csv",
    "write_events_csv",
]


class CrossLaserError(ValueError):
    """The recorded events cannot be evaluated (missing crossings, inconsistent pattern)."""


# ---------------------------------------------------------------------------------------------
# events and motions
# ---------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class BarrierEvent:
    """A barrier state change seen by the controller.

    time_s: controller time of the I/O sample that showed the new state; barrier ``"x"`` or
    ``"y"``; state ``"blocked"`` or ``"clear"``; flange_mm (3,): flange position the controller
    reports at that time (base frame, ``None`` if not recorded).
    """

    time_s: float
    barrier: str
    state: str
    flange_mm: np.ndarray | None = None


def _trapezoid(length: float, speed: float, accel: float):
    """Duration, peak speed and ramp time of a rest-to-rest trapezoidal profile."""
    if length <= 0:
        return 0.0, 0.0, 0.0
    if speed <= 0 or accel <= 0:
        raise ValueError("speed and acceleration must be > 0")
    if length >= speed * speed / accel:
        t_acc = speed / accel
        return length / speed + t_acc, speed, t_acc
    vmax = math.sqrt(length * accel)
    t_acc = vmax / accel
    return 2 * t_acc, vmax, t_acc


def _path_s(t, length, accel, duration, vmax, t_acc):
    t = np.clip(np.asarray(t, dtype=float), 0.0, duration)
    s_ramp = 0.5 * accel * t * t
    s_end = length - 0.5 * accel * (duration - t) ** 2
    s_mid = 0.5 * accel * t_acc * t_acc + vmax * (t - t_acc)
    return np.where(t < t_acc, s_ramp, np.where(t > duration - t_acc, s_end, s_mid))


def _arr(x, shape=None):
    a = np.array(x, dtype=float)
    if shape is not None and a.shape != shape:
        raise ValueError(f"expected shape {shape}, got {a.shape}")
    a.setflags(write=False)
    return a


class _TrapezoidMove:
    """Shared timing of a programmed move: a trapezoidal speed profile over ``_length`` [mm]."""

    @property
    def _profile(self):
        return _trapezoid(self._length, self.speed_mm_s, self.accel_mm_s2)

    @property
    def duration_s(self) -> float:
        return self._profile[0]

    @property
    def constant_speed_window_s(self) -> tuple:
        d, _, t_acc = self._profile
        return t_acc, d - t_acc


@dataclass(frozen=True)
class CircleMove(_TrapezoidMove):
    """A circular flange motion at constant orientation (a controller ``movec``), base frame.

    Flange position ``center + R (cos(phi) e1 + sin(phi) e2)`` with ``e1 = ref_dir``, ``e2 =
    normal x e1``; ``phi`` runs from ``start_angle_rad`` through ``sweep_rad`` (positive =
    counter-clockwise about ``normal``) on a trapezoidal speed profile (``speed_mm_s``,
    ``accel_mm_s2``). ``R_base_flange`` is the constant flange orientation.
    """

    center_mm: np.ndarray
    radius_mm: float
    normal: np.ndarray
    ref_dir: np.ndarray
    start_angle_rad: float
    sweep_rad: float
    speed_mm_s: float
    accel_mm_s2: float
    R_base_flange: np.ndarray
    step: int = 0
    role: str = "circle"

    kind = "circle"

    def __post_init__(self):
        object.__setattr__(self, "center_mm", _arr(self.center_mm, (3,)))
        n = np.asarray(self.normal, float)
        n = n / np.linalg.norm(n)
        e1 = np.asarray(self.ref_dir, float)
        e1 = e1 - (e1 @ n) * n
        e1 = e1 / np.linalg.norm(e1)
        object.__setattr__(self, "normal", _arr(n))
        object.__setattr__(self, "ref_dir", _arr(e1))
        object.__setattr__(self, "R_base_flange", _arr(self.R_base_flange, (3, 3)))

    @property
    def _length(self) -> float:
        return abs(self.sweep_rad) * self.radius_mm

    def phase(self, t) -> np.ndarray:
        """Programmed angle phi [rad] at motion time ``t`` [s] (from the start of this motion)."""
        d, vmax, t_acc = self._profile
        L = abs(self.sweep_rad) * self.radius_mm
        s = _path_s(t, L, self.accel_mm_s2, d, vmax, t_acc)
        return self.start_angle_rad + math.copysign(1.0, self.sweep_rad) * s / self.radius_mm

    @property
    def angular_speed_rad_s(self) -> float:
        return self._profile[1] / self.radius_mm

    def positions(self, t) -> np.ndarray:
        phi = self.phase(t)
        e2 = np.cross(self.normal, self.ref_dir)
        return (self.center_mm + self.radius_mm * (np.cos(phi)[..., None] * self.ref_dir
                                                   + np.sin(phi)[..., None] * e2))

    def poses(self, t) -> np.ndarray:
        """Commanded flange poses ``T_base_flange`` (N, 4, 4) at motion times ``t`` (N,)."""
        p = self.positions(np.atleast_1d(t))
        return transforms_from(np.broadcast_to(self.R_base_flange, p.shape[:-1] + (3, 3)), p)

    def to_dict(self) -> dict:
        return {"kind": "circle", "step": int(self.step), "role": self.role,
                "center_mm": [float(x) for x in self.center_mm], "radius_mm": float(self.radius_mm),
                "normal": [float(x) for x in self.normal], "ref_dir": [float(x) for x in self.ref_dir],
                "start_angle_deg": math.degrees(self.start_angle_rad), "sweep_deg": math.degrees(self.sweep_rad),
                "speed_mm_s": float(self.speed_mm_s), "accel_mm_s2": float(self.accel_mm_s2),
                "R_base_flange": [[float(x) for x in r] for r in self.R_base_flange]}


@dataclass(frozen=True)
class LinearMove(_TrapezoidMove):
    """A straight flange motion with the orientation interpolated (``movel``), base frame.

    Position and rotation (about the fixed axis of ``R_start^T R_end``) follow the same
    trapezoidal profile; its length is the larger of the distance and the rotation angle times
    ``speed_mm_s / angular_speed_rad_s``.
    """

    start_mm: np.ndarray
    end_mm: np.ndarray
    R_start: np.ndarray
    R_end: np.ndarray
    speed_mm_s: float
    angular_speed_rad_s: float
    accel_mm_s2: float
    step: int = 0
    role: str = "move"

    kind = "line"

    def __post_init__(self):
        object.__setattr__(self, "start_mm", _arr(self.start_mm, (3,)))
        object.__setattr__(self, "end_mm", _arr(self.end_mm, (3,)))
        object.__setattr__(self, "R_start", _arr(self.R_start, (3, 3)))
        object.__setattr__(self, "R_end", _arr(self.R_end, (3, 3)))

    @property
    def _rotvec(self):
        return so3_log(self.R_start.T @ self.R_end)

    @property
    def _length(self) -> float:
        dist = float(np.linalg.norm(self.end_mm - self.start_mm))
        ang = float(np.linalg.norm(self._rotvec))
        return max(dist, ang * self.speed_mm_s / self.angular_speed_rad_s)

    def fraction(self, t) -> np.ndarray:
        L = self._length
        if L <= 0:
            return np.ones_like(np.asarray(t, float))
        d, vmax, t_acc = self._profile
        return _path_s(t, L, self.accel_mm_s2, d, vmax, t_acc) / L

    def positions(self, t) -> np.ndarray:
        lam = self.fraction(t)[..., None]
        return self.start_mm + lam * (self.end_mm - self.start_mm)

    def poses(self, t) -> np.ndarray:
        t = np.atleast_1d(np.asarray(t, float))
        lam = self.fraction(t)
        R = self.R_start @ so3_exp(lam[..., None] * self._rotvec)
        return transforms_from(R, self.positions(t))

    def to_dict(self) -> dict:
        return {"kind": "line", "step": int(self.step), "role": self.role,
                "start_mm": [float(x) for x in self.start_mm], "end_mm": [float(x) for x in self.end_mm],
                "R_start": [[float(x) for x in r] for r in self.R_start],
                "R_end": [[float(x) for x in r] for r in self.R_end],
                "speed_mm_s": float(self.speed_mm_s), "angular_speed_deg_s": math.degrees(self.angular_speed_rad_s),
                "accel_mm_s2": float(self.accel_mm_s2)}


def motion_from_dict(d: dict):
    """Inverse of ``CircleMove.to_dict`` / ``LinearMove.to_dict``."""
    kind = d.get("kind")
    if kind == "circle":
        return CircleMove(center_mm=d["center_mm"], radius_mm=float(d["radius_mm"]), normal=d["normal"],
                          ref_dir=d["ref_dir"], start_angle_rad=math.radians(float(d["start_angle_deg"])),
                          sweep_rad=math.radians(float(d["sweep_deg"])), speed_mm_s=float(d["speed_mm_s"]),
                          accel_mm_s2=float(d["accel_mm_s2"]), R_base_flange=d["R_base_flange"],
                          step=int(d.get("step", 0)), role=str(d.get("role", "circle")))
    if kind == "line":
        return LinearMove(start_mm=d["start_mm"], end_mm=d["end_mm"], R_start=d["R_start"], R_end=d["R_end"],
                          speed_mm_s=float(d["speed_mm_s"]),
                          angular_speed_rad_s=math.radians(float(d["angular_speed_deg_s"])),
                          accel_mm_s2=float(d["accel_mm_s2"]), step=int(d.get("step", 0)),
                          role=str(d.get("role", "move")))
    raise ValueError(f"unknown motion kind {kind!r} (expected 'circle' or 'line')")


@dataclass(frozen=True)
class MotionRecord:
    """One executed motion: the motion, its start on the controller clock, its events."""

    motion: object
    t_start_s: float
    events: tuple = ()
    duration_s: float = 0.0
    settle_s: float = 0.0


# ---------------------------------------------------------------------------------------------
# sensor frame
# ---------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class SensorFrame:
    """What the method needs of the sensor calibration (any object with these attributes works)."""

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
        return self.origin_mm + np.asarray(p_s, float) @ self.R_base_sensor.T

    def to_sensor(self, p_b) -> np.ndarray:
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


# ---------------------------------------------------------------------------------------------
# formulas
# ---------------------------------------------------------------------------------------------


def angles_from_durations(durations) -> np.ndarray:
    """(4-8): ``angle_i = 2 pi t_i / (t1 + t2 + t3 + t4)`` [rad] from the four arc durations."""
    t = np.asarray(durations, dtype=float)
    if t.shape[-1] != 4 or np.any(t <= 0):
        raise ValueError(f"expected four positive durations, got {t}")
    return 2 * np.pi * t / t.sum(axis=-1, keepdims=True)


def center_distances(angles, radius_mm: float, arc_widths_rad=(0.0, 0.0)):
    """(4-9): signed distances ``(d_x, d_y)`` of the circle centre to the X and Y beams.

    ``angles`` (4,): the arcs 1..4 (quadrant names, see the module docstring). ``d_x = R'
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
    """Circle centre ``(x, y)`` in the orthogonal sensor frame from the beam distances.

    With ``beta_correction`` (4-29) via :func:`robocal.tcp.sensor.center_from_beam_distances`;
    without it the thesis's uncorrected ``(d_y, d_x)``, whose x error is (4-30).
    """
    if beta_correction:
        x, y = center_from_beam_distances(d_x, d_y, beta_rad)
        return np.array([float(x), float(y)])
    return np.array([float(d_y), float(d_x)])


def axis_vector_thesis(center1, center2, dz_mm: float) -> np.ndarray:
    """(4-12) as printed: ``(d_y2 - d_y1, d_x1 - d_x2, dz)`` from the centres ``(d_y, d_x)``.

    Valid only for the thesis's set-up (flange X_e = X_s, Y_e = -Y_s, Z_e = -Z_s, both circles
    centred on the sensor origin, circle 2 ``dz`` lower). It is the tool axis mirrored in x and y:
    the true axis (flange -> tip) in the flange frame is ``(-v_x, -v_y, v_z)``; feeding this vector
    to (4-13) and (4-10) gives a frame whose z column is the true axis (the two sign flips cancel).
    """
    c1 = np.asarray(center1, float)
    c2 = np.asarray(center2, float)
    return np.array([c2[0] - c1[0], c1[1] - c2[1], float(dz_mm)])


def euler_psi_theta(delta) -> tuple:
    """(4-13) as printed: ``psi = sign(-dx) arccos(dy / rho)``, ``theta = arccos(dz / |d|)``.

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
    """(4-10): ``Rz(psi) Rx(theta) Rz(-psi)``, a rotation by theta about ``(cos psi, sin psi, 0)``:
    the 5-D frame, no rotation about the tool's own axis. Its z column is
    ``(sin psi sin theta, -cos psi sin theta, cos theta)``."""
    return rot_z(psi) @ rot_x(theta) @ rot_z(-psi)


def psi_theta_from_axis(axis) -> tuple:
    """``(psi, theta)`` with ``rotation_5d(psi, theta) @ e_z = axis / |axis|``.

    Equal to :func:`euler_psi_theta` applied to ``(-a_x, -a_y, a_z)`` (the thesis's (4-12)
    vector), i.e. ``psi = atan2(a_x, -a_y)``, ``theta = arccos(a_z)``.
    """
    return euler_psi_theta((-axis[0], -axis[1], axis[2]))


def minimal_rotation(u, v) -> np.ndarray:
    """The rotation of smallest angle taking direction ``u`` to direction ``v`` (about ``u x v``).

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
    """(4-14) in the flange frame: the TCP ``t = R_base_flange^T (O_s - p_e)``.

    ``origin_base``: the sensor origin O_s; ``flange_base``: the flange position p_e with the TCP
    at O_s; ``R_base_flange``: the flange orientation at that moment. The thesis's (4-14)
    ``O_s - p_e`` is this vector in base coordinates; it is the TCP only when the flange is
    aligned with the base.
    """
    return np.asarray(R_base_flange, float).T @ (np.asarray(origin_base, float) - np.asarray(flange_base, float))


# ---------------------------------------------------------------------------------------------
# settings and plans
# ---------------------------------------------------------------------------------------------


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
    of (4-9) (module docstring); step3_center: where the step-3 circle is centred: ``"axis"``
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


_RX_PI = rot_x(np.pi)  # flange X_e = X_s, Y_e = -Y_s, Z_e = -Z_s (thesis figure 4-8)


def measuring_orientation(axis_flange) -> np.ndarray:
    """``R_sensor_flange`` that points the tool axis (flange frame) along ``-Z_s`` with no twist:
    ``Rx(pi) R5^T`` with ``R5`` the minimal rotation ``e_z -> axis``; ``Rx(pi)`` (the thesis's
    orientation) for a tool along the flange Z axis."""
    return _RX_PI @ minimal_rotation([0, 0, 1.0], axis_flange).T


def _circle_motion(sensor: SensorFrame, center_s, R_sensor_flange, settings: CrossLaserSettings, step, role):
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
    + delta_z_mm`` from the estimated tip; the second circle is ``delta_z_mm`` lower."""
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
    """Step 3: the flange re-oriented so the measured axis is parallel to ``-Z_s`` (4-10, 4-13),
    and placed so the measured axis point ``axis_point_flange`` is on the sensor origin; one circle."""
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


def _move(start_T, end_T, settings, step, role):
    return LinearMove(start_T[:3, 3], end_T[:3, 3], start_T[:3, :3], end_T[:3, :3],
                      speed_mm_s=settings.move_speed_mm_s, angular_speed_rad_s=math.radians(settings.angular_speed_deg_s),
                      accel_mm_s2=settings.accel_mm_s2, step=step, role=role)


def _lifted(T, sensor: SensorFrame, dz):
    out = np.array(T, float)
    out[:3, 3] = out[:3, 3] + dz * sensor.R_base_sensor[:, 2]
    return out


def _start_pose(motion):
    return motion.poses([0.0])[0]


def _end_pose(motion):
    return motion.poses([motion.duration_s])[0]


# ---------------------------------------------------------------------------------------------
# evaluation
# ---------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class CircleResult:
    """Evaluation of one measuring circle.

    angles_rad (4,): arcs 1..4 (4-8); d_x_mm, d_y_mm: (4-9); center_mm (2,): circle centre of the
    tool's axis point in the orthogonal sensor frame (beta-corrected if asked); arc_widths_rad:
    blocked arcs (delta_x, delta_y); period_s; n_arcs: arcs averaged; angle_spread_rad: largest
    spread of one arc over repeated periods (a residual); axis_point_flange (3,): the tool-axis
    point in the flange frame; R_sensor_flange: flange orientation during the circle.
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


def _intervals(events, barrier, t_lo, t_hi):
    """Blocked intervals (t_blocked, t_clear) of one barrier fully inside [t_lo, t_hi]."""
    out = []
    t_on = None
    for e in sorted(events, key=lambda e: e.time_s):
        if e.barrier != barrier:
            continue
        if e.state == "blocked":
            t_on = e.time_s
        elif e.state == "clear" and t_on is not None:
            if t_on >= t_lo and e.time_s <= t_hi:
                out.append((t_on, e.time_s))
            t_on = None
    return out


_ARC_OF = {frozenset(("X+", "Y+")): 0, frozenset(("Y+", "X-")): 1, frozenset(("X-", "Y-")): 2,
           frozenset(("Y-", "X+")): 3}


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
    w0, w1 = m.constant_speed_window_s
    t0 = record.t_start_s
    beta = sensor.beta_rad
    Rs = sensor.R_base_sensor
    e1_s = Rs.T @ m.ref_dir
    e2_s = Rs.T @ np.cross(m.normal, m.ref_dir)
    ybeam = np.array([math.cos(beta), math.sin(beta)])
    crossings = []
    widths = {"x": [], "y": []}
    for b in ("x", "y"):
        for ta, tb in _intervals(record.events, b, t0 + w0, t0 + w1):
            tm = 0.5 * (ta + tb)
            phi = float(m.phase(tm - t0))
            u = (math.cos(phi) * e1_s + math.sin(phi) * e2_s)[:2]
            side = u[0] if b == "x" else float(u @ ybeam)
            crossings.append((tm, ("X" if b == "x" else "Y") + ("+" if side > 0 else "-")))
            widths[b].append(tb - ta)
    crossings.sort()
    if len(crossings) < 5:
        raise CrossLaserError(f"circle (step {m.step}): {len(crossings)} complete beam crossings, need >= 5 "
                              "(is the tool within the circle radius of the sensor origin?)")
    sums = np.zeros(4)
    per = [[] for _ in range(4)]
    for (ta, la), (tb, lb) in zip(crossings[:-1], crossings[1:]):
        k = _ARC_OF.get(frozenset((la, lb)))
        if k is None:
            raise CrossLaserError(f"circle (step {m.step}): crossings {la} then {lb} at {ta:.4f}/{tb:.4f} s: a beam "
                                  "crossing is missing or the tool is off the circle")
        per[k].append(tb - ta)
    if any(len(p) == 0 for p in per):
        raise CrossLaserError(f"circle (step {m.step}): not all four arcs were seen")
    mean = np.array([np.mean(p) for p in per])
    sums = mean.sum()
    angles = angles_from_durations(mean)
    omega = 2 * np.pi / sums
    spread = max((max(p) - min(p)) * omega for p in per)
    if settings.arc_correction:
        dl = (omega * float(np.mean(widths["x"])), omega * float(np.mean(widths["y"])))
    else:
        dl = (0.0, 0.0)
    d_x, d_y = center_distances(angles, m.radius_mm, dl)
    c = circle_center(d_x, d_y, beta, settings.beta_correction)
    R_sf = Rs.T @ m.R_base_flange
    F_s = sensor.to_sensor(m.center_mm)
    q = R_sf.T @ (np.array([c[0], c[1], 0.0]) - F_s)
    return CircleResult(angles_rad=angles, d_x_mm=float(d_x), d_y_mm=float(d_y), center_mm=c,
                        arc_widths_rad=(float(omega * np.mean(widths["x"])), float(omega * np.mean(widths["y"]))),
                        period_s=float(sums), n_arcs=sum(len(p) for p in per), angle_spread_rad=float(spread),
                        axis_point_flange=q, R_sensor_flange=R_sf, flange_center_sensor=F_s)


@dataclass(frozen=True)
class VerticalResult:
    """Step 4: flange positions at the four events (base frame), their mean p_e, the TCP (4-14,
    flange frame), the beam heights found (sensor Z) and residuals."""

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
    pos = {}
    for rec, state in ((down, "blocked"), (up, "clear")):
        for b in ("x", "y"):
            ev = [e for e in rec.events if e.barrier == b and e.state == state]
            if not ev:
                raise CrossLaserError(f"step 4: beam {b} never became {state} during the "
                                      f"{'down' if state == 'blocked' else 'up'} move")
            if ev[0].flange_mm is None:
                raise CrossLaserError("step 4: events carry no flange position")
            pos[f"{b}_{state}"] = np.asarray(ev[0].flange_mm, float)
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
        return {"T_flange_tool": self.T_flange_tool.tolist(), "tcp_flange_mm": self.tcp_flange_mm.tolist(),
                "axis_flange": self.axis_flange.tolist(), "psi_deg": math.degrees(self.psi_rad),
                "theta_deg": math.degrees(self.theta_rad), "residuals": self.residuals,
                "cycle_time_s": self.cycle_time_s, "beta_correction": self.settings.beta_correction}


def _axis_from_circles(c1: CircleResult, c2: CircleResult):
    d = c1.axis_point_flange - c2.axis_point_flange     # (4-11, 4-12): from circle 2 (nearer the flange) to 1
    n = np.linalg.norm(d)
    if n < 1e-9:
        raise CrossLaserError("circles 1 and 2 measured the same axis point (delta_z = 0?)")
    return d / n


def _finish(sensor, T_nom, c1, c2, c3, vert, records, settings):
    a = _axis_from_circles(c1, c2)
    q3 = c3.axis_point_flange
    tcp = vert.tcp_flange_mm
    # residuals: step 3 centre predicted by the steps 1-2 axis line vs measured; TCP off the axis line
    R_sf3 = c3.R_sensor_flange
    line_pt = c1.axis_point_flange
    pred = R_sf3 @ (line_pt + a * float((q3 - line_pt) @ a)) + c3.flange_center_sensor
    R_nom = np.asarray(T_nom, float)[:3, :3]
    R_new = minimal_rotation(R_nom[:, 2], a) @ R_nom
    psi, theta = psi_theta_from_axis(a)
    T = transforms_from(R_new, tcp)
    residuals = {
        "step1_angle_spread_deg": math.degrees(c1.angle_spread_rad),
        "step2_angle_spread_deg": math.degrees(c2.angle_spread_rad),
        "step3_angle_spread_deg": math.degrees(c3.angle_spread_rad),
        "step3_center_vs_axis_mm": float(np.linalg.norm(pred[:2] - c3.center_mm)),
        "step4_gap_residual_mm": vert.gap_residual_mm,
        "step4_hysteresis_x_mm": vert.hysteresis_mm["x"],
        "step4_hysteresis_y_mm": vert.hysteresis_mm["y"],
    }
    t0 = min(r.t_start_s for r in records)
    t1 = max(r.t_start_s + r.duration_s + r.settle_s for r in records)
    return CrossLaserResult(T_flange_tool=T, axis_flange=a, tcp_flange_mm=tcp, psi_rad=psi, theta_rad=theta,
                            steps={"circle1": c1, "circle2": c2, "circle3": c3, "vertical": vert},
                            residuals=residuals, cycle_time_s=float(t1 - t0), records=tuple(records), settings=settings)


def recalibrate_tool(source, sensor, T_flange_tool_nominal, settings: CrossLaserSettings = CrossLaserSettings(),
                     *, start_pose=None) -> CrossLaserResult:
    """Run the full cross-laser recalibration online (thesis 4.2.2 steps 1-4).

    source: an event source with ``run(motion) -> MotionRecord`` (the simulator
    :class:`robocal.sim.light_barrier.LightBarrierCell`, or a robot driver). sensor: the sensor
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
    records = []
    c1m, c2m = plan_axis_circles(sensor, T_nom, settings)
    first = _start_pose(c1m)
    above = _lifted(first, sensor, settings.clearance_mm + settings.cut_from_tip_mm)
    home = above if start_pose is None else np.asarray(start_pose, float)
    if start_pose is not None:
        records.append(source.run(_move(home, above, settings, 0, "approach")))
    records.append(source.run(_move(above, first, settings, 1, "descend")))
    records.append(source.run(c1m))
    records.append(source.run(_move(_end_pose(c1m), _start_pose(c2m), settings, 2, "lower")))
    records.append(source.run(c2m))
    r1 = evaluate_circle(records[-3], sensor, settings)
    r2 = evaluate_circle(records[-1], sensor, settings)
    a = _axis_from_circles(r1, r2)
    if settings.step3_center == "axis":
        p3 = r1.axis_point_flange
    else:
        p3 = T_nom[:3, 3] - settings.cut_from_tip_mm * T_nom[:3, 2]
    c3m = plan_align_circle(sensor, a, p3, settings)
    records.append(source.run(_move(_end_pose(c2m), _lifted(_end_pose(c2m), sensor, settings.delta_z_mm), settings, 3,
                                    "raise")))
    records.append(source.run(_move(records[-1].motion.poses([records[-1].motion.duration_s])[0], _start_pose(c3m),
                                    settings, 3, "reorient")))
    records.append(source.run(c3m))
    r3 = evaluate_circle(records[-1], sensor, settings)
    tip_dist = settings.cut_from_tip_mm + float((r1.axis_point_flange - r3.axis_point_flange) @ a)
    down, up = plan_vertical(sensor, r3.R_sensor_flange, r3.axis_point_flange, a, tip_dist, settings)
    records.append(source.run(_move(_end_pose(c3m), _lifted(_end_pose(c3m), sensor, settings.clearance_mm), settings, 4,
                                    "lift")))
    records.append(source.run(_move(_end_pose(records[-1].motion), _start_pose(down), settings, 4, "center")))
    rd = source.run(down)
    ru = source.run(up)
    records += [rd, ru]
    vert = evaluate_vertical(rd, ru, sensor)
    records.append(source.run(_move(_end_pose(up), _lifted(_end_pose(up), sensor, settings.clearance_mm), settings, 4,
                                    "retract")))
    if start_pose is not None:
        records.append(source.run(_move(_end_pose(records[-1].motion), home, settings, 4, "return")))
    return _finish(sensor, T_nom, r1, r2, r3, vert, records, settings)


def evaluate_recording(records, sensor, T_flange_tool_nominal, settings: CrossLaserSettings = CrossLaserSettings()):
    """Evaluate recorded motions (e.g. from :func:`read_events_csv`) offline.

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
    return _finish(sensor, np.asarray(T_flange_tool_nominal, float), r1, r2, r3, vert, list(records), settings)


# ---------------------------------------------------------------------------------------------
# events file
# ---------------------------------------------------------------------------------------------

EVENTS_FORMAT = "robocal-barrier-events/1"


def write_events_csv(path, records, note: str | None = None):
    """Write motion records as a barrier-events file (format ``robocal-barrier-events/1``).

    Layout (docs in the CLI help of ``robocal tcp cross-laser``)::

        # format: robocal-barrier-events/1
        # motion: {"id": 0, "t_start_s": ..., "duration_s": ..., "settle_s": ..., "kind": "circle", ...}
        ...
        motion,time_s,barrier,state,x_mm,y_mm,z_mm
        2,1.2345,x,blocked,-850.1,-170.2,390.0
    """
    from pathlib import Path

    lines = [f"# format: {EVENTS_FORMAT}", "# length_unit: mm, time_unit: s, angles in motion headers: deg"]
    if note:
        lines += [f"# {ln}" for ln in str(note).splitlines()]
    rows = []
    for i, r in enumerate(records):
        head = {"id": i, "t_start_s": float(r.t_start_s), "duration_s": float(r.duration_s),
                "settle_s": float(r.settle_s)}
        head.update(r.motion.to_dict())
        lines.append("# motion: " + json.dumps(head, separators=(",", ":")))
        for e in r.events:
            p = e.flange_mm if e.flange_mm is not None else (math.nan,) * 3
            rows.append(f"{i},{e.time_s:.6f},{e.barrier},{e.state},{p[0]:.6f},{p[1]:.6f},{p[2]:.6f}")
    lines.append("motion,time_s,barrier,state,x_mm,y_mm,z_mm")
    Path(path).write_text("\n".join(lines + rows) + "\n", encoding="utf-8")
    return Path(path)


def read_events_csv(path) -> list:
    """Read a barrier-events file (see :func:`write_events_csv`) into :class:`MotionRecord` s.

    Raises ``ValueError`` naming the file and line for malformed content.
    """
    from pathlib import Path

    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8-sig")
    except OSError as exc:
        raise ValueError(f"{path}: cannot read: {exc}") from None
    heads, events, header, fmt = {}, {}, None, None
    for ln, line in enumerate(text.splitlines(), 1):
        s = line.strip()
        if not s:
            continue
        if s.startswith("#"):
            body = s[1:].strip()
            if body.startswith("format:"):
                fmt = body.split(":", 1)[1].strip()
                if fmt != EVENTS_FORMAT:
                    raise ValueError(f"{path}, line {ln}: format {fmt!r} not supported (expected {EVENTS_FORMAT})")
            elif body.startswith("motion:"):
                try:
                    d = json.loads(body.split(":", 1)[1])
                    mid = int(d["id"])
                    heads[mid] = (d, motion_from_dict(d))
                except (ValueError, KeyError, TypeError) as exc:
                    raise ValueError(f"{path}, line {ln}: bad motion header: {exc}") from None
            continue
        fields = [f.strip() for f in s.split(",")]
        if header is None:
            if fields != ["motion", "time_s", "barrier", "state", "x_mm", "y_mm", "z_mm"]:
                raise ValueError(f"{path}, line {ln}: header must be 'motion,time_s,barrier,state,x_mm,y_mm,z_mm'")
            header = fields
            continue
        if len(fields) != 7:
            raise ValueError(f"{path}, line {ln}: expected 7 fields, got {len(fields)}")
        try:
            mid, t = int(fields[0]), float(fields[1])
            xyz = np.array([float(v) for v in fields[4:]])
        except ValueError:
            raise ValueError(f"{path}, line {ln}: non-numeric motion, time or position") from None
        if fields[2] not in ("x", "y"):
            raise ValueError(f"{path}, line {ln}, column 'barrier': {fields[2]!r} is not x or y")
        if fields[3] not in ("blocked", "clear"):
            raise ValueError(f"{path}, line {ln}, column 'state': {fields[3]!r} is not blocked or clear")
        if mid not in heads:
            raise ValueError(f"{path}, line {ln}: motion {mid} has no '# motion:' header")
        events.setdefault(mid, []).append(BarrierEvent(t, fields[2], fields[3], None if np.any(np.isnan(xyz)) else xyz))
    if fmt is None:
        raise ValueError(f"{path}: missing '# format: {EVENTS_FORMAT}' line")
    if header is None:
        raise ValueError(f"{path}: missing the header line 'motion,time_s,barrier,state,x_mm,y_mm,z_mm'")
    return [MotionRecord(motion=m, t_start_s=float(d["t_start_s"]), events=tuple(events.get(i, ())),
                         duration_s=float(d.get("duration_s", m.duration_s)), settle_s=float(d.get("settle_s", 0.0)))
            for i, (d, m) in sorted(heads.items())]
