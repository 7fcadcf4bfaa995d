"""Light-barrier simulator: beams with mounting errors, a cylindrical tool, a robot on its path.

Used to test the tool-frame methods (:mod:`robocal.tcp.cross_laser`, the sensor calibration) end
to end. Lengths mm, times s, angles rad unless a name says ``_deg``. ``T_a_b`` = pose of b in a.

Model:

- A **light barrier** is a 3-D line, a point and a unit direction from emitter to receiver
  (:class:`LightBarrier`; treated as infinite: the tool is always near the crossing).
- The **cross-laser sensor** (:meth:`CrossLaserSensor.build`) starts from a nominal frame and
  adds the mounting errors: the Y beam at ``beta`` from the X beam about Z_s (non-orthogonal),
  the two beams ``gap_mm`` apart along Z_s (not coplanar: the X beam at -gap/2, the Y beam at
  +gap/2, so the origin M of the common perpendicular stays the nominal origin), and the whole
  sensor tilted by ``tilt_deg`` about a horizontal axis of the base and turned ``yaw_deg`` about
  its Z axis. :meth:`CrossLaserSensor.true_frame` is the truth a perfect calibration would find.
- The **tool** (:class:`CylinderTool`) is a cylinder of radius r along the tool frame's Z axis,
  from ``length_mm`` behind the tip to the tip (the tool frame origin, the TCP), with a flat or a
  spherical tip (a ball of radius r whose apex is the TCP). :meth:`CylinderTool.collided` bends
  it: a random tilt about an axis perpendicular to the tool through a pivot near the flange, plus
  a random offset; the result is again a tool frame with no twist about its own axis.
- A beam is **blocked** while it meets the tool: the line intersects the finite cylinder (flat
  tip) or comes closer than r to the axis segment ending r before the tip (spherical tip).
- The **robot** (:class:`LightBarrierCell`) executes the controller's Cartesian path
  (:class:`~robocal.tcp.cross_laser.CircleMove`, :class:`~robocal.tcp.cross_laser.LinearMove`,
  trapezoidal speed profiles) with repeatability noise: per motion, a constant offset plus a
  smooth wobble (three sinusoids of 0.5-4 Hz), together of standard deviation
  ``repeatability_mm / 3.6`` per axis (ISO 9283: RP = mean + 3 std of the distance, ~3.6 sigma
  for isotropic Gaussian noise). The barrier state is sampled on the controller's I/O clock
  (``io_rate_hz``) and arrives ``latency_s`` late; an event is the first sample showing a new
  state, stamped with that sample's time and the flange position the controller believes
  (commanded path, no noise). Each motion adds its duration and ``settle_s`` to the clock: the
  sum is the simulated cycle time.
- Optionally the flange poses of every motion are checked for reachability with the robot
  model's numerical IK (``robot_model``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ...transforms import rot_axis, rot_z, transforms_from
from .barrier_geometry import BeamDirt, barrier_blocked
from ..robot import as_rng

__all__ = [
    "LightBarrier",
    "CrossLaserSensor",
    "CylinderTool",
    "LightBarrierCell",
    "barrier_blocked",
    "BeamDirt",
    "simulate_sensor_calibration_points",
]


def _unit(v, name="vector"):
    v = np.asarray(v, dtype=float)
    n = np.linalg.norm(v)
    if not n > 0:
        raise ValueError(f"{name} has zero length")
    out = v / n
    out.setflags(write=False)
    return out


def _ro(a):
    a = np.array(a, dtype=float)
    a.setflags(write=False)
    return a


@dataclass(frozen=True)
class LightBarrier:
    """A beam: ``point_mm`` (3,) on it and unit ``direction`` (3,) from emitter to receiver (base)."""

    name: str
    point_mm: np.ndarray
    direction: np.ndarray

    def __post_init__(self):
        object.__setattr__(self, "point_mm", _ro(self.point_mm))
        object.__setattr__(self, "direction", _unit(self.direction, f"barrier {self.name} direction"))


@dataclass(frozen=True)
class CrossLaserSensor:
    """Two crossing barriers ``x`` and ``y`` (base frame)."""

    x_beam: LightBarrier
    y_beam: LightBarrier

    @classmethod
    def build(cls, T_base_nominal, *, beta_deg: float = 90.0, gap_mm: float = 0.0, tilt_deg: float = 0.0,
              tilt_axis_deg: float = 0.0, yaw_deg: float = 0.0) -> "CrossLaserSensor":
        """Sensor from its nominal frame plus mounting errors.

        ``T_base_nominal`` (4x4): nominal sensor frame (X beam along its x, Y beam along its y,
        crossing at its origin). ``beta_deg``: angle from the X beam to the Y beam about Z_s.
        ``gap_mm``: distance between the beams along Z_s (Y beam above). ``tilt_deg``: rotation
        of the sensor about the horizontal base axis at ``tilt_axis_deg`` from base X (about base
        Z), through the sensor origin. ``yaw_deg``: rotation about the sensor's own Z axis.
        """
        T = np.asarray(T_base_nominal, float)
        k = np.array([math.cos(math.radians(tilt_axis_deg)), math.sin(math.radians(tilt_axis_deg)), 0.0])
        R = rot_axis(k, math.radians(tilt_deg)) @ T[:3, :3] @ rot_z(math.radians(yaw_deg))
        o = T[:3, 3]
        b = math.radians(beta_deg)
        x_dir = R[:, 0]
        y_dir = math.cos(b) * R[:, 0] + math.sin(b) * R[:, 1]
        return cls(LightBarrier("x", o - 0.5 * gap_mm * R[:, 2], x_dir),
                   LightBarrier("y", o + 0.5 * gap_mm * R[:, 2], y_dir))

    @property
    def beams(self) -> dict:
        return {"x": self.x_beam, "y": self.y_beam}

    def true_frame(self) -> dict:
        """The sensor frame a perfect calibration finds (keys of ``robocal tcp sensor-calibrate --json``):
        origin M of the common perpendicular, x_axis, y_axis (Y beam), y_axis_orthogonal, z_axis,
        T_base_sensor, beta_deg, gap_mm."""
        A, n = self.x_beam.point_mm, self.x_beam.direction
        C, m = self.y_beam.point_mm, self.y_beam.direction
        w = A - C
        k1, k2, k3, k4, k5 = n @ n, m @ m, n @ m, w @ n, w @ m
        den = k3 * k3 - k1 * k2
        t = (k2 * k4 - k3 * k5) / den
        s = (k3 * k4 - k1 * k5) / den
        P, Q = A + t * n, C + s * m
        M = 0.5 * (P + Q)
        z = np.cross(n, m)
        z = z / np.linalg.norm(z)
        o = np.cross(z, n)
        T = transforms_from(np.column_stack([n, o, z]), M)
        return {"origin_mm": M, "x_axis": n.copy(), "y_axis": m.copy(), "y_axis_orthogonal": o, "z_axis": z,
                "T_base_sensor": T, "beta_deg": math.degrees(math.atan2(m @ o, m @ n)),
                "gap_mm": float(np.linalg.norm(Q - P))}


@dataclass(frozen=True)
class CylinderTool:
    """A cylindrical tool: ``T_flange_tool`` (origin = tip/TCP, z = axis pointing out of the
    flange), ``radius_mm``, ``length_mm`` (tip to the cylinder's base along -z), ``tip``
    ``"spherical"`` (ball end, apex at the TCP) or ``"flat"``. ``T_tool_shank`` (4, 4), optional:
    runout -- the physical cylinder (shank and ball) sits at this pose in the tool frame while
    the TCP (the point that matters, e.g. the centring cone a measuring arm probes) stays the
    tool frame's origin (:meth:`with_runout`)."""

    T_flange_tool: np.ndarray
    radius_mm: float = 3.0
    length_mm: float = 180.0
    tip: str = "spherical"
    T_tool_shank: np.ndarray | None = None

    def __post_init__(self):
        object.__setattr__(self, "T_flange_tool", _ro(self.T_flange_tool))
        if self.T_tool_shank is not None:
            object.__setattr__(self, "T_tool_shank", _ro(self.T_tool_shank))
        if self.tip not in ("spherical", "flat"):
            raise ValueError(f"tip must be 'spherical' or 'flat', got {self.tip!r}")
        if not (self.radius_mm > 0 and self.length_mm > 2 * self.radius_mm):
            raise ValueError("need radius_mm > 0 and length_mm > 2 radius_mm")

    @property
    def axis_flange(self) -> np.ndarray:
        return self.T_flange_tool[:3, 2].copy()

    @property
    def tcp_flange_mm(self) -> np.ndarray:
        return self.T_flange_tool[:3, 3].copy()

    def segment_flange(self):
        """(base point, end point) of the tool axis segment in the flange frame; for a spherical
        tip the end is the ball centre (r before the tip). With runout, of the displaced shank."""
        T = self.T_flange_tool if self.T_tool_shank is None else self.T_flange_tool @ self.T_tool_shank
        a, tip = T[:3, 2], T[:3, 3]
        end = tip - self.radius_mm * a if self.tip == "spherical" else tip
        return tip - self.length_mm * a, end

    def with_runout(self, eccentricity_mm: float, tilt_deg: float, rng) -> "CylinderTool":
        """A copy whose cylinder is off the TCP: shifted ``eccentricity_mm`` and tilted
        ``tilt_deg`` about the tip, both in random directions perpendicular to the tool axis."""
        rng = as_rng(rng)
        g, h = rng.uniform(0.0, 2.0 * np.pi, 2)
        shift = eccentricity_mm * np.array([math.cos(g), math.sin(g), 0.0])
        R = rot_axis(np.array([math.cos(h), math.sin(h), 0.0]), math.radians(tilt_deg))
        return CylinderTool(self.T_flange_tool, self.radius_mm, self.length_mm, self.tip, transforms_from(R, shift))

    def collided(self, rng, *, tilt_deg=(1.0, 3.0), offset_mm=(0.5, 3.0), axial_mm=(-1.0, 0.5),
                 pivot_from_base_mm: float = 10.0):
        """A bent copy of the tool after a simulated collision, and a dict describing the damage.

        Tilt: uniform in ``tilt_deg`` about a random axis perpendicular to the tool axis through the
        pivot ``pivot_from_base_mm`` from the tool's base (near the flange). Offset: a lateral shift
        (uniform magnitude in ``offset_mm``, random direction perpendicular to the new axis) plus an
        axial one (uniform in ``axial_mm``, positive = longer). No twist about the tool axis.
        """
        rng = as_rng(rng)
        a = self.axis_flange
        tip = self.tcp_flange_mm
        pivot = tip - (self.length_mm - pivot_from_base_mm) * a
        perp = np.cross(a, [1.0, 0, 0] if abs(a[0]) < 0.9 else [0, 1.0, 0])
        perp /= np.linalg.norm(perp)
        perp2 = np.cross(a, perp)
        g = rng.uniform(0, 2 * np.pi)
        k = math.cos(g) * perp + math.sin(g) * perp2
        tilt = math.radians(rng.uniform(*tilt_deg))
        Rc = rot_axis(k, tilt)
        a_new = Rc @ a
        h = rng.uniform(0, 2 * np.pi)
        lat = math.cos(h) * (Rc @ perp) + math.sin(h) * (Rc @ perp2)
        off = rng.uniform(*offset_mm) * lat + rng.uniform(*axial_mm) * a_new
        tip_new = pivot + Rc @ (tip - pivot) + off
        T = transforms_from(Rc @ self.T_flange_tool[:3, :3], tip_new)
        info = {"tilt_deg": math.degrees(tilt), "tilt_axis_flange": k, "offset_mm": off, "pivot_flange_mm": pivot}
        return CylinderTool(T, self.radius_mm, self.length_mm, self.tip, self.T_tool_shank), info


class LightBarrierCell:
    """A robot cell with barriers: executes motions, returns barrier events, keeps the clock.

    sensor: a :class:`CrossLaserSensor` or a dict name -> :class:`LightBarrier`; tool:
    :class:`CylinderTool` (its true geometry); rng: seed or Generator (required, for the robot
    noise); io_rate_hz, latency_s, repeatability_mm, settle_s: see the module docstring;
    robot_model / q_seed: check each motion's poses with numerical IK (``reach_errors_mm`` keeps
    the worst position error per motion; ``None`` if not checked). Realism
    (:mod:`robocal.sim.tool.barrier_effects`): latency_jitter_s: each event is stamped a further
    uniform 0..jitter later (on the I/O clock); accuracy: the robot's absolute error (an object
    with ``apply(motion, t, T) -> T``, e.g. :class:`~robocal.sim.tool.barrier_effects.RobotAccuracy`);
    dirt: ``{beam name: BeamDirt}``.
    """

    def __init__(self, sensor, tool: CylinderTool, rng, *, io_rate_hz: float = 1000.0, latency_s: float = 0.002,
                 repeatability_mm: float = 0.1, settle_s: float = 0.1, robot_model=None, q_seed=None,
                 latency_jitter_s: float = 0.0, accuracy=None, dirt=None):
        self.beams = sensor.beams if isinstance(sensor, CrossLaserSensor) else dict(sensor)
        self.tool = tool
        self.rng = as_rng(rng)
        if not io_rate_hz > 0 or latency_s < 0 or repeatability_mm < 0 or settle_s < 0:
            raise ValueError("need io_rate_hz > 0 and latency_s, repeatability_mm, settle_s >= 0")
        self.io_rate_hz = float(io_rate_hz)
        self.latency_s = float(latency_s)
        self.repeatability_mm = float(repeatability_mm)
        self.settle_s = float(settle_s)
        self.robot_model = robot_model
        self._q = None if q_seed is None else np.asarray(q_seed, float)
        self.time_s = 0.0
        self._state = None
        self.reach_errors_mm: list = []
        if latency_jitter_s < 0:
            raise ValueError("latency_jitter_s must be >= 0")
        self.latency_jitter_s = float(latency_jitter_s)
        self.accuracy = accuracy
        self.dirt = dict(dirt or {})

    # -------------------------------------------------------------------------------- noise
    def _noise_fn(self):
        sigma = self.repeatability_mm / 3.6
        if sigma == 0:
            return lambda t: np.zeros((len(np.atleast_1d(t)), 3))
        sb = sw = sigma / math.sqrt(2.0)
        bias = self.rng.normal(0.0, sb, 3)
        f = self.rng.uniform(0.5, 4.0, (3, 3))
        ph = self.rng.uniform(0, 2 * np.pi, (3, 3))
        amp = sw * math.sqrt(2.0 / 3.0)

        def noise(t):
            t = np.atleast_1d(np.asarray(t, float))[:, None, None]
            return bias + amp * np.sin(2 * np.pi * f * t + ph).sum(axis=-1)

        return noise

    def blocked_at(self, T_base_flange) -> dict:
        """Barrier states for actual flange poses (N, 4, 4)."""
        T = np.asarray(T_base_flange, float).reshape(-1, 4, 4)
        b0, e0 = self.tool.segment_flange()
        R, p = T[:, :3, :3], T[:, :3, 3]
        B = p + R @ b0
        E = p + R @ e0
        return {k: barrier_blocked(beam, B, E, self.tool.radius_mm, self.tool.tip, self.dirt.get(k))
                for k, beam in self.beams.items()}

    def _check_reach(self, motion):
        if self.robot_model is None:
            return None
        from ...kinematics import ik_numeric

        ts = np.linspace(0.0, motion.duration_s, 5)
        T = motion.poses(ts)
        q0 = self._q if self._q is not None else np.zeros(self.robot_model.n_joints)
        res = ik_numeric(self.robot_model, T, q0)
        if res.all_converged:
            self._q = res.q[-1]
        err = float(np.max(res.position_error_mm)) if res.all_converged else math.inf
        self.reach_errors_mm.append(err)
        return err

    def _jittered(self, i: int, n: int) -> int:
        """The sample that reports a change first shown by sample ``i`` (latency jitter)."""
        if self.latency_jitter_s == 0:
            return i
        return min(n - 1, i + math.ceil(self.rng.uniform(0.0, self.latency_jitter_s) * self.io_rate_hz - 1e-9))

    # -------------------------------------------------------------------------------- running
    def run(self, motion):
        """Execute ``motion`` (anything with ``duration_s`` and ``poses(t)``); return a
        :class:`~robocal.tcp.cross_laser.MotionRecord` with the barrier events."""
        from ...tcp.cross_laser import BarrierEvent, MotionRecord

        self._check_reach(motion)
        t0 = self.time_s
        dur = float(motion.duration_s)
        dt = 1.0 / self.io_rate_hz
        k0 = math.ceil(t0 * self.io_rate_hz - 1e-9)
        k1 = math.floor((t0 + dur) * self.io_rate_hz + 1e-9)
        ts = np.arange(k0, k1 + 1) * dt
        noise = self._noise_fn()
        t_seen = np.clip(ts - self.latency_s - t0, 0.0, dur)       # the beam state the sample reflects
        T_act = motion.poses(t_seen)
        T_act[:, :3, 3] += noise(t_seen)
        if self.accuracy is not None:
            T_act = self.accuracy.apply(motion, t_seen, T_act)
        states = self.blocked_at(T_act)
        cmd = motion.poses(np.clip(ts - t0, 0.0, dur))[:, :3, 3]
        if self._state is None:
            self._state = {k: bool(v[0]) if len(v) else False for k, v in states.items()}
        events = []
        for name, st in states.items():
            prev = np.concatenate([[self._state[name]], st[:-1]])
            for i in np.flatnonzero(st != prev):
                k = self._jittered(i, len(ts))
                events.append(BarrierEvent(float(ts[k]), name, "blocked" if st[i] else "clear", cmd[k].copy()))
            if len(st):
                self._state[name] = bool(st[-1])
        events.sort(key=lambda e: e.time_s)
        self.time_s = t0 + dur + self.settle_s
        return MotionRecord(motion=motion, t_start_s=t0, events=tuple(events), duration_s=dur, settle_s=self.settle_s)


def simulate_sensor_calibration_points(sensor: CrossLaserSensor, T_base_nominal, rng, *, pin_radius_mm: float = 3.0,
                                       pin_length_mm: float = 80.0, spacing_mm: float = 60.0, travel_mm: float = 12.0,
                                       speed_mm_s: float = 2.0, io_rate_hz: float = 1000.0, latency_s: float = 0.002,
                                       repeatability_mm: float = 0.1, accel_mm_s2: float = 2000.0, **cell_effects):
    """Simulate the pin procedure of thesis 4.3.1 and return ``({label: (3,)}, cycle_time_s)``.

    A calibration pin (flat-ended cylinder coaxial with the flange Z axis) crosses each beam at
    two places ``spacing_mm`` either side of the nominal origin: 1/2 = flange positions where the
    beam becomes blocked/unblocked as the vertical pin moves horizontally across it (along base Y
    for the X beam, base X for the Y beam), 3/4 = the same as the horizontal pin (pointing along
    the 1 -> 2 motion, its middle at the beam) moves down. Labels A, B on the X beam, C, D on the
    Y beam, as :func:`robocal.tcp.sensor.calibrate_sensor` expects. Positions are the controller's
    (commanded) flange positions at the events, so latency x speed biases them (slow ``speed``).
    ``cell_effects``: the realism keywords of :class:`LightBarrierCell` (latency_jitter_s,
    accuracy, dirt) -- the same cell the tool is later measured in.
    """
    from ...tcp.cross_laser import LinearMove

    Tn = np.asarray(T_base_nominal, float)
    o, Rn = Tn[:3, 3], Tn[:3, :3]
    pin = CylinderTool(np.eye(4) @ transforms_from(np.eye(3), [0, 0, pin_length_mm]), pin_radius_mm,
                       pin_length_mm, "flat")
    cell = LightBarrierCell(sensor, pin, rng, io_rate_hz=io_rate_hz, latency_s=latency_s,
                            repeatability_mm=repeatability_mm, settle_s=0.1, **cell_effects)
    down = np.diag([1.0, -1.0, -1.0])                 # flange Z down, X along base X
    ex, ey, ez = np.eye(3)
    pts = {}
    jobs = (("A", "x", -1), ("B", "x", +1), ("C", "y", -1), ("D", "y", +1))
    for label, beam, sgn in jobs:
        along = Rn[:, 0] if beam == "x" else Rn[:, 1]
        P = o + sgn * spacing_mm * along
        across = ey if beam == "x" else ex
        # 1/2: vertical pin, its middle at the beam height, moving horizontally across
        c = P + 0.5 * pin_length_mm * ez
        mv = LinearMove(c - travel_mm * across, c + travel_mm * across, down, down, speed_mm_s, 1.0, accel_mm_s2)
        rec = cell.run(mv)
        pts.update(_two_events(rec, beam, label, 1))
        # 3/4: horizontal pin along `across`, flange origin `pin_length/2` before the beam, moving down
        Rh = np.column_stack([np.cross(-ez, across), -ez, across])
        c = P - 0.5 * pin_length_mm * across
        mv = LinearMove(c + travel_mm * ez, c - travel_mm * ez, Rh, Rh, speed_mm_s, 1.0, accel_mm_s2)
        rec = cell.run(mv)
        pts.update(_two_events(rec, beam, label, 3))
    return pts, cell.time_s


def _two_events(rec, beam, label, first):
    ev = [e for e in rec.events if e.barrier == beam]
    on = [e for e in ev if e.state == "blocked"]
    off = [e for e in ev if e.state == "clear"]
    if not on or not off:
        raise RuntimeError(f"sensor calibration point {label}: the pin did not cross the {beam} beam")
    return {f"{label}{first}": on[0].flange_mm, f"{label}{first + 1}": off[-1].flange_mm}
