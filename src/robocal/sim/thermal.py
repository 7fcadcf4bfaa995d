"""Thermal simulator: a robot that heats up in production, drifts, and is measured (METHODS.md 4).

The pieces, all seeded and all in mm / rad / s:

* :class:`ProductionSchedule` -- production cycles (work at a motor load, then a short
  measurement phase, then an optional idle gap). :meth:`ProductionSchedule.generate` draws one
  (~3-min cycles, jittered loads, random idle gaps, optional long breaks);
  :func:`standard_schedules` gives the three different runs of the thesis-like experiment.
* :class:`HeatSource` / :class:`ThermalModel` -- one first-order heat source per joint motor::

      tau_j dh_j/dt = G_j u_j(t) - h_j            (h_j: temperature rise [K], u_j: motor load 0..1)

  integrated exactly over the piecewise-constant load of the schedule (so heating during
  production and cooling when idle are both first order with the same time constant, ~1 h).
  The heaviest sources are joints 2-4. The parameter drift is linear in the thermal state with a
  fixed direction per source, ``dX(t) = sum_j h_j(t) D_j`` (P,) [mm | rad]: each ``D_j`` is
  dominated by a few lengths and angles of joints 2-4 (expansion of the arms, tilt of the
  shoulder axis, elbow offset, wrist twist) plus small seeded contributions on every free
  parameter. Because the sources heat with different gains and time constants, the total drift
  direction is *nearly* fixed, as observed on real robots. :meth:`ThermalModel.kr150_default`
  is scaled so the TCP of the 3.1 m KR150 moves 0.1-0.5 mm after ~3 h of production.
* :class:`ThermalCell` -- the measurement cell: the (geometrically slightly off) true robot with
  joint-angle noise (``VirtualRobot``), a fixed stereo sensor measuring the centre of a ø38.1 mm
  sphere on the flange in its own frame (``T_sensor_base``, noise ~0.02 mm per coordinate), and
  a robot-held sensor (``T_flange_sensor`` on the flange, noise ~0.02 mm) measuring 34 monitored
  points on a car body spread over ~1.5 x 1 m, each from its own robot pose.
  :meth:`ThermalCell.simulate` runs a schedule and returns a :class:`ThermalRun`.

A run starts cold. The cold reference (sphere at every sphere pose, every monitored point) is
measured at t = 0 before production; then after each production cycle the robot measures the 34
monitored points and the sphere at its sphere poses (one thermal state per cycle: the
measurement takes < 1 min, during which the drift changes by < 1 %). Recorded joints are the
commanded ones; the robot really stands at ``q + noise`` (joint-angle noise: backlash,
elasticity, the robot's repeatability; not seen by the encoders).

Files: :func:`write_run` writes a run as robocal measurement files (``docs/measurement-files.md``):
sphere and monitored-point files (cold reference and all cycles, pose ids ``c012-p03``), a
``cycles.csv`` with the measurement times and a ``truth.json``;
:func:`robocal.io.thermal_files.read_run` reads them back.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..io.atomic import atomic_write_text
from ..io.measurements import Measurements, write_measurements
from ..io.thermal_files import write_cycles
from ..kinematics.model import RobotModel
from ..transforms import invert_transforms, rot_x, so3_exp
from .robot import VirtualRobot, as_rng, parameter_kinds

__all__ = [
    "SPHERE_DIAMETER_MM", "HeatSource", "ThermalModel", "ProductionSchedule", "standard_schedules",
    "ThermalCell", "ThermalRun", "car_body_points", "monitor_poses", "write_run",
]

SPHERE_DIAMETER_MM = 38.1

# joint motor loads in a production cycle (relative, heaviest in joints 2-4) and in the measurement phase
PRODUCTION_LOAD = np.array([0.6, 1.0, 0.9, 0.8, 0.5, 0.5])
MEASUREMENT_LOAD = 0.3


# ---------------------------------------------------------------------------------------------- schedule
@dataclass(frozen=True)
class ProductionSchedule:
    """Production cycles of one run (times in s from the start of the run).

    Cycle c: production work from ``start_s[c]`` for ``work_s[c]`` at relative load ``load[c]``
    (0..1, times :data:`PRODUCTION_LOAD` per joint), then the measurement phase of
    ``measure_s`` at load :data:`MEASUREMENT_LOAD`, then ``idle_s[c]`` of idle (load 0: cooling).
    The measurement instant of cycle c is the middle of its measurement phase
    (:attr:`measurement_times_s`).
    """

    work_s: np.ndarray
    load: np.ndarray
    idle_s: np.ndarray
    measure_s: float = 40.0
    name: str = ""

    def __post_init__(self):
        w = np.asarray(self.work_s, float)
        ld = np.asarray(self.load, float)
        idle = np.asarray(self.idle_s, float)
        if not (w.ndim == 1 and w.shape == ld.shape == idle.shape and len(w)):
            raise ValueError("ProductionSchedule: work_s, load, idle_s must be 1-D of the same length >= 1")
        if np.any(w < 0) or np.any(idle < 0) or np.any((ld < 0) | (ld > 1)) or self.measure_s < 0:
            raise ValueError("ProductionSchedule: durations must be >= 0 and loads in [0, 1]")
        for k, v in (("work_s", w), ("load", ld), ("idle_s", idle)):
            v.setflags(write=False)
            object.__setattr__(self, k, v)

    @property
    def n_cycles(self) -> int:
        return len(self.work_s)

    @property
    def start_s(self) -> np.ndarray:
        """Start time of every cycle (n,) [s]."""
        length = self.work_s + self.measure_s + self.idle_s
        return np.concatenate([[0.0], np.cumsum(length)[:-1]])

    @property
    def measurement_times_s(self) -> np.ndarray:
        """The measurement instant of every cycle (n,) [s]."""
        return self.start_s + self.work_s + 0.5 * self.measure_s

    @property
    def duration_s(self) -> float:
        return float(np.sum(self.work_s + self.measure_s + self.idle_s))

    def segments(self):
        """Piecewise-constant load: ``(t_start (S,), duration (S,), relative load (S, 6))``."""
        n = self.n_cycles
        dur = np.stack([self.work_s, np.full(n, self.measure_s), self.idle_s], axis=1).reshape(-1)
        loads = np.stack([self.load[:, None] * PRODUCTION_LOAD, np.full((n, 6), MEASUREMENT_LOAD),
                          np.zeros((n, 6))], axis=1).reshape(-1, 6)
        t0 = np.concatenate([[0.0], np.cumsum(dur)[:-1]])
        return t0, dur, loads

    @classmethod
    def generate(cls, rng, n_cycles: int = 90, *, cycle_s: float = 180.0, jitter_s: float = 10.0,
                 measure_s: float = 40.0, load_range=(0.8, 1.0), gap_probability: float = 0.05,
                 gap_mean_s: float = 240.0, breaks=None, name: str = "") -> "ProductionSchedule":
        """A random schedule: cycles of ``cycle_s`` +- ``jitter_s`` (work + measurement), loads
        uniform in ``load_range``, after each cycle an idle gap with probability
        ``gap_probability`` (exponential, mean ``gap_mean_s``), and fixed ``breaks``
        ``{cycle index: idle seconds}`` (e.g. a 45-min stop after cycle 40). ``rng``: seed or Generator."""
        rng = as_rng(rng)
        work = cycle_s - measure_s + rng.uniform(-jitter_s, jitter_s, n_cycles)
        load = rng.uniform(*load_range, n_cycles)
        idle = np.where(rng.random(n_cycles) < gap_probability, rng.exponential(gap_mean_s, n_cycles), 0.0)
        for c, s in (breaks or {}).items():
            idle[int(c)] += float(s)
        return cls(np.maximum(work, 0.0), np.clip(load, 0, 1), idle, measure_s, name)


def standard_schedules(seed: int = 7, n_cycles: int = 90) -> list:
    """Three different runs of ~3-min cycles (the thesis-like experiment):

    1. screening run: steady production, loads 0.85-1.0, rare short gaps;
    2. evaluation run: loads 0.7-1.0, more gaps and a 45-min stop after 45 % of the cycles (the
       robot cools down and heats up again);
    3. evaluation run: faster cycles (160 s) at loads 0.9-1.0, a 30-min stop after 70 % of the
       cycles.
    """
    rng = as_rng(seed)
    s = rng.integers(0, 2**31, 3)
    return [
        ProductionSchedule.generate(int(s[0]), n_cycles, load_range=(0.85, 1.0), gap_probability=0.03, name="run 1"),
        ProductionSchedule.generate(int(s[1]), n_cycles, load_range=(0.7, 1.0), gap_probability=0.1,
                                    breaks={int(0.45 * n_cycles): 2700.0}, name="run 2"),
        ProductionSchedule.generate(int(s[2]), n_cycles, cycle_s=160.0, load_range=(0.9, 1.0), gap_probability=0.05,
                                    breaks={int(0.7 * n_cycles): 1800.0}, name="run 3"),
    ]


# ---------------------------------------------------------------------------------------------- heat
@dataclass(frozen=True)
class HeatSource:
    """A heat source (joint motor): steady-state temperature rise ``gain_K`` at full load,
    time constant ``tau_s`` and the parameter drift per kelvin ``direction`` (P,) [mm/K | rad/K]."""

    name: str
    joint: int
    gain_K: float
    tau_s: float
    direction: np.ndarray


@dataclass
class ThermalModel:
    """Joint heat sources and the parameter drift they cause (see the module docstring).

    sources: one :class:`HeatSource` per joint motor, ``sources[j].joint == j + 1``.
    names: the robot's parameter names (P,), matching the directions.
    """

    sources: tuple
    names: tuple

    @property
    def directions(self) -> np.ndarray:
        """(S, P) drift per kelvin of every source."""
        return np.stack([s.direction for s in self.sources])

    @property
    def gains(self) -> np.ndarray:
        return np.array([s.gain_K for s in self.sources])

    @property
    def taus(self) -> np.ndarray:
        return np.array([s.tau_s for s in self.sources])

    def states(self, schedule: ProductionSchedule, times_s, h0=None) -> np.ndarray:
        """Thermal state (T, S) [K] at ``times_s`` (any order, >= 0), starting at ``h0`` (default cold, 0).

        Exact solution of the first-order equations over the schedule's piecewise-constant load;
        after the end of the schedule the robot stays idle (cools)."""
        t = np.asarray(times_s, float)
        t0, dur, loads = schedule.segments()
        G, tau = self.gains, self.taus
        joint = np.array([s.joint - 1 for s in self.sources])
        target = loads[:, joint] * G                                      # (Seg, S) equilibrium per segment
        # state at each segment start
        h = np.zeros((len(t0) + 1, len(G)))
        h[0] = 0.0 if h0 is None else np.asarray(h0, float)
        decay = np.exp(-dur[:, None] / tau)
        for i in range(len(t0)):
            h[i + 1] = target[i] + (h[i] - target[i]) * decay[i]
        seg = np.clip(np.searchsorted(t0, t, side="right") - 1, 0, len(t0) - 1)
        end = t0[-1] + dur[-1]
        after = t >= end
        dt = np.where(after, t - end, t - t0[seg])[:, None]
        hs = np.where(after[:, None], h[-1], h[seg])
        tg = np.where(after[:, None], 0.0, target[seg])
        return tg + (hs - tg) * np.exp(-dt / tau)

    def drift(self, states) -> np.ndarray:
        """Parameter drifts (T, P) [mm | rad] for thermal states (T, S)."""
        return np.asarray(states, float) @ self.directions

    @classmethod
    def kr150_default(cls, model: RobotModel, rng, *, scale: float = 1.0, leak: float = 1.0) -> "ThermalModel":
        """Heat sources of a KUKA KR150-like robot (DH + beta parameter names).

        Dominant drifts per kelvin (cast aluminium arms: 23e-6 / K): joint 2 (shoulder motor, 25 K, 0.9 h)
        stretches ``a1``, part of the upper arm ``a2`` and the column ``d1`` and tilts the
        shoulder axis (``beta2``); joint 3 (elbow motor, 22 K, 1.0 h) stretches ``a2``, ``a3`` and
        ``d4`` and shifts the elbow offset (``theta3``); joint 4 (wrist motors on the forearm,
        16 K, 0.8 h) stretches the forearm ``d4`` and twists ``alpha4``; joints 1, 5, 6 (9, 7, 5 K)
        add column height, turn of the base and flange length ``d6``. On top, every source gets
        small seeded contributions on every free parameter (``leak`` times 1.5e-4 mm/K or
        1.5e-7 rad/K standard deviation). ``scale`` multiplies all drifts.
        """
        rng = as_rng(rng)
        names = model.params.names
        idx = {n: i for i, n in enumerate(names)}
        P = len(names)
        al = 23e-6                       # cast aluminium arm housings, 1/K
        L = {n: abs(float(v)) for n, v in zip(names, model.params.values)}
        main = {
            1: (9.0, 1.2, {"d1": 0.3 * al * L.get("d1", 675.0), "theta1": 2.0e-6}),
            2: (25.0, 0.9, {"a1": 0.8 * al * L.get("a1", 350.0), "a2": 0.25 * al * L.get("a2", 1350.0),
                            "beta2": 1.2e-5}),
            3: (22.0, 1.0, {"a2": 0.35 * al * L.get("a2", 1350.0), "a3": 0.004, "theta3": 1.0e-5,
                            "d4": 0.2 * al * L.get("d4", 1400.0)}),
            4: (16.0, 0.8, {"d4": 0.4 * al * L.get("d4", 1400.0), "alpha4": 2.0e-5, "a3": 0.002}),
            5: (7.0, 0.7, {"d6": 1.5 * al * L.get("d6", 215.0)}),
            6: (5.0, 0.7, {"d6": 0.8 * al * L.get("d6", 215.0)}),
        }
        kinds = parameter_kinds(model)
        free = model.params.free
        sources = []
        for j in range(1, 7):
            gain, tau_h, dom = main[j]
            d = np.zeros(P)
            for n, v in dom.items():
                if n in idx:
                    d[idx[n]] += v
            noise = rng.standard_normal(P) * np.where(kinds == "length", 1.5e-4, 1.5e-7)
            d += leak * np.where(free, noise, 0.0)
            d *= scale
            d.setflags(write=False)
            sources.append(HeatSource(f"A{j} motor", j, gain, tau_h * 3600.0, d))
        return cls(tuple(sources), tuple(names))


# ---------------------------------------------------------------------------------------------- geometry
def car_body_points(rng, n: int = 34, *, centre=(2100.0, 0.0, 600.0), size=(1000.0, 1500.0),
                    crown_mm: float = 120.0) -> np.ndarray:
    """``n`` monitored points (n, 3) [mm, base frame] on a car-body-like surface: a jittered grid over
    ``size`` (x by y) around ``centre`` on a gently crowned roof (``crown_mm`` higher in the middle)."""
    rng = as_rng(rng)
    nx = max(2, int(round(math.sqrt(n * size[0] / size[1]))))
    ny = -(-n // nx)
    gx, gy = np.meshgrid(np.linspace(-0.5, 0.5, nx), np.linspace(-0.5, 0.5, ny), indexing="ij")
    uv = np.stack([gx.ravel(), gy.ravel()], axis=1)
    keep = np.sort(rng.choice(len(uv), n, replace=False))
    uv = uv[keep] + rng.uniform(-0.25, 0.25, (n, 2)) / np.array([nx, ny])
    x = centre[0] + uv[:, 0] * size[0]
    y = centre[1] + uv[:, 1] * size[1]
    z = centre[2] + crown_mm * (1.0 - 4.0 * (uv[:, 0] ** 2 + uv[:, 1] ** 2) / 2.0)
    return np.stack([x, y, z], axis=1)


def _ik_pose(model, T_base_flange, prev):
    from ..kinematics import ik_analytic

    qs, ok = ik_analytic(model, model.T_world_base @ T_base_flange, within_limits=True)
    if not ok.any():
        return None
    cand = qs[ok]
    ref = model.limits.mean(axis=1) if prev is None else prev
    return cand[np.argmin(np.sum((cand - ref) ** 2, axis=1))]


def monitor_poses(model: RobotModel, points, T_flange_sensor, rng, *, standoff_mm: float = 250.0,
                  tilt_deg: float = 20.0, max_tries: int = 50):
    """Robot poses (n, 6) from which the robot-held sensor sees each monitored point.

    The sensor's z axis points at the point from ``standoff_mm`` away, tilted from straight down by
    up to ``tilt_deg`` about a random axis, with a random turn about z; the flange pose is
    ``T_base_sensor . T_flange_sensor^-1`` and the joints come from the closed-form IK (the branch
    closest to the previous pose). Returns the joints (n, 6) [rad]."""
    rng = as_rng(rng)
    pts = np.asarray(points, float)
    T_sf = invert_transforms(np.asarray(T_flange_sensor, float))
    out, prev = [], None
    for i, p in enumerate(pts):
        for _ in range(max_tries):
            axis = rng.normal(size=3)
            axis /= np.linalg.norm(axis)
            R = so3_exp(axis * math.radians(tilt_deg) * rng.uniform(0.0, 1.0)) @ rot_x(math.pi) @ \
                so3_exp(np.array([0.0, 0.0, rng.uniform(-math.pi, math.pi)]))
            T_bs = np.eye(4)
            T_bs[:3, :3] = R
            T_bs[:3, 3] = p - R[:, 2] * standoff_mm
            q = _ik_pose(model, T_bs @ T_sf, prev)
            if q is not None:
                out.append(q)
                prev = q
                break
        else:
            raise ValueError(f"monitored point {i} at {p.tolist()} mm: no reachable sensor pose")
    return np.array(out)


# ---------------------------------------------------------------------------------------------- run
@dataclass
class ThermalRun:
    """A simulated run (all cycles), with the truth.

    schedule; times_s (C,): measurement instants; states (C, S) [K]; delta_true (C, P): true
    parameter drifts [mm | rad] at the measurements.
    q_sphere (m, n): recorded (commanded) sphere poses; sphere_cold (m, 3): cold reference of the
    sphere centre in the sensor frame [mm]; sphere (C, m, 3): every cycle's measurement.
    q_monitor (K, n); monitor_cold (K, 3); monitor (C, K, 3): the monitored points measured by the
    robot-held sensor, in its frame [mm].
    timeline_s (T,), timeline_states (T, S), tcp_drift_mm (T,): a fine thermal history (every
    ``timeline_step_s``) and the TCP (flange at ``q_tcp``) drift magnitude over it.
    """

    schedule: ProductionSchedule
    times_s: np.ndarray
    states: np.ndarray
    delta_true: np.ndarray
    q_sphere: np.ndarray
    sphere_cold: np.ndarray
    sphere: np.ndarray
    q_monitor: np.ndarray
    monitor_cold: np.ndarray
    monitor: np.ndarray
    timeline_s: np.ndarray
    timeline_states: np.ndarray
    tcp_drift_mm: np.ndarray
    seed: object = None

    @property
    def n_cycles(self) -> int:
        return len(self.times_s)


@dataclass
class ThermalCell:
    """The simulated cell (see the module docstring). Build with :meth:`standard`.

    robot: the true robot (``robot.nominal`` is the model the compensation uses, ``robot.true_model``
    what the arm really follows cold, ``robot.joint_noise`` the joint-angle noise).
    thermal: the :class:`ThermalModel`. T_sensor_base (4, 4): the fixed stereo sensor (base frame
    written in the sensor frame); P_e (3,): sphere centre on the flange; sphere_noise_mm.
    T_flange_sensor (4, 4): the robot-held sensor; body_points (K, 3): monitored points (base
    frame); monitor_noise_mm. q_sphere (m, n): the screening sphere poses; q_monitor (K, n): the
    monitored poses; q_tcp (n,): the pose whose flange drift is reported in the timeline.
    """

    robot: VirtualRobot
    thermal: ThermalModel
    T_sensor_base: np.ndarray
    P_e: np.ndarray
    T_flange_sensor: np.ndarray
    body_points: np.ndarray
    q_sphere: np.ndarray
    q_monitor: np.ndarray
    q_tcp: np.ndarray
    sphere_noise_mm: float = 0.02
    monitor_noise_mm: float = 0.02
    sphere_centre_base: np.ndarray = field(default_factory=lambda: np.zeros(3))
    seed: object = None

    @property
    def model(self) -> RobotModel:
        """The nominal model (what the compensation knows)."""
        return self.robot.nominal

    @classmethod
    def standard(cls, seed: int = 2024, *, robot: str | RobotModel = "kuka_kr150_r3100", n_sphere_poses: int = 20,
                 n_monitor: int = 34, sphere_centre=(1600.0, -1250.0, 1000.0), sphere_spread_mm=(250.0, 200.0, 150.0),
                 sphere_tilt_deg: float = 60.0, P_e=(25.0, -40.0, 160.0), sphere_noise_mm: float = 0.02,
                 monitor_noise_mm: float = 0.02, joint_noise_deg: float = 0.0003, length_sigma_mm: float = 0.2,
                 angle_sigma_deg: float = 0.02, drift_scale: float = 1.0, drift_leak: float = 1.0) -> "ThermalCell":
        """The thesis-like cell on the KR150 R3100 (every draw from ``seed``).

        The stereo sensor stands 700 mm below the sphere measurement volume (``sphere_centre``,
        base frame) looking up, with a random turn and tilt; ``n_sphere_poses`` sphere poses span
        ``sphere_spread_mm`` (half sizes) with flange tilts up to ``sphere_tilt_deg``
        (:func:`robocal.thermal.design_sphere_poses`). The robot-held sensor sits 180 mm in front
        of the flange; ``n_monitor`` points on a car body (~1.5 x 1 m, centred 2.1 m in front of
        the robot). The true robot differs from the nominal model by ``length_sigma_mm`` /
        ``angle_sigma_deg`` (a calibrated robot's residual errors) and has joint-angle noise
        ``joint_noise_deg`` (5e-6 rad ~ 0.015 mm at 3 m, the KR150's repeatability).
        """
        from ..robots import load_robot
        from ..thermal import design_sphere_poses

        rng = as_rng(seed)
        nominal = load_robot(robot) if isinstance(robot, str) else robot
        seeds = rng.integers(0, 2**31, 8)
        true = VirtualRobot.perturbed(nominal, int(seeds[0]), length_sigma_mm=length_sigma_mm,
                                      angle_sigma_deg=angle_sigma_deg, offset_sigma_deg=angle_sigma_deg,
                                      joint_noise_deg=joint_noise_deg)
        thermal = ThermalModel.kr150_default(nominal, int(seeds[1]), scale=drift_scale, leak=drift_leak)
        r2 = as_rng(int(seeds[2]))
        centre = np.asarray(sphere_centre, float)
        T_bs = np.eye(4)
        T_bs[:3, :3] = so3_exp(np.array([0.0, 0.0, r2.uniform(-3, 3)])) @ rot_x(np.pi) @ so3_exp(r2.normal(0, 0.1, 3))
        T_bs[:3, 3] = centre + np.array([0.0, 0.0, -700.0])
        P_e = np.asarray(P_e, float)
        q_sphere = design_sphere_poses(nominal, centre, P_e, n_sphere_poses, int(seeds[3]),
                                       spread_mm=sphere_spread_mm, tilt_deg=sphere_tilt_deg)
        T_fs = np.eye(4)
        T_fs[:3, :3] = so3_exp(np.array([math.radians(15.0), 0.0, 0.0]))
        T_fs[:3, 3] = [0.0, 80.0, 180.0]
        body = car_body_points(int(seeds[4]), n_monitor)
        q_mon = monitor_poses(nominal, body, T_fs, int(seeds[5]))
        q_tcp = np.radians([0.0, -90.0, 90.0, 0.0, 45.0, 0.0])
        return cls(true, thermal, invert_transforms(T_bs), P_e, T_fs, body, q_sphere, q_mon, q_tcp,
                   sphere_noise_mm, monitor_noise_mm, centre, seed)

    # ------------------------------------------------------------------ measurement
    def _flange(self, q, params):
        """True flange poses in the base frame (N, 4, 4) for actual joints and parameters."""
        T, _, _, _ = self.robot.true_model.kinematics_with(q, params, np.eye(4), [0])
        return T[:, 0]

    def measure_sphere(self, q, params, rng) -> np.ndarray:
        """Sphere centres (m, 3) in the sensor frame for commanded ``q`` with true parameters ``params``."""
        rng = as_rng(rng)
        qa = self.robot.encoder_noise(q, rng)
        T = self._flange(qa, params)
        p = T[:, :3, :3] @ self.P_e + T[:, :3, 3]
        p = p @ self.T_sensor_base[:3, :3].T + self.T_sensor_base[:3, 3]
        return p + rng.standard_normal(p.shape) * self.sphere_noise_mm

    def measure_monitor(self, q, params, rng) -> np.ndarray:
        """Monitored points (K, 3) in the robot-held sensor frame (point k from pose ``q[k]``)."""
        rng = as_rng(rng)
        qa = self.robot.encoder_noise(q, rng)
        T = self._flange(qa, params) @ self.T_flange_sensor
        d = self.body_points - T[:, :3, 3]
        p = np.einsum("kji,kj->ki", T[:, :3, :3], d)
        return p + rng.standard_normal(p.shape) * self.monitor_noise_mm

    def tcp_drift(self, deltas, q=None) -> np.ndarray:
        """Flange-origin drift magnitude (T,) [mm] at pose ``q`` (default ``q_tcp``) for deltas (T, P)."""
        q = self.q_tcp if q is None else np.asarray(q, float)
        X = self.robot.true_model.params.values
        d = np.atleast_2d(deltas)
        T0 = self._flange(q[None], X)[0, :3, 3]
        pts = np.array([self._flange(q[None], X + di)[0, :3, 3] for di in d])
        return np.linalg.norm(pts - T0, axis=1)

    def simulate(self, schedule: ProductionSchedule, rng, *, q_sphere=None, timeline_step_s: float = 60.0,
                 timeline_extra_s: float = 0.0) -> ThermalRun:
        """Run ``schedule`` from cold: the cold reference at t = 0, then one measurement of every
        monitored point and every sphere pose (``q_sphere``, default the cell's) per cycle.
        ``timeline_extra_s`` extends the thermal timeline past the end (idle cooling)."""
        seed = rng if isinstance(rng, (int, np.integer)) and not isinstance(rng, bool) else None
        rng = as_rng(rng)
        q_s = self.q_sphere if q_sphere is None else np.asarray(q_sphere, float)
        X = self.robot.true_model.params.values
        times = schedule.measurement_times_s
        states = self.thermal.states(schedule, times)
        delta = self.thermal.drift(states)
        sphere_cold = self.measure_sphere(q_s, X, rng)
        monitor_cold = self.measure_monitor(self.q_monitor, X, rng)
        C = len(times)
        sphere = np.empty((C, len(q_s), 3))
        monitor = np.empty((C, len(self.q_monitor), 3))
        for c in range(C):
            monitor[c] = self.measure_monitor(self.q_monitor, X + delta[c], rng)
            sphere[c] = self.measure_sphere(q_s, X + delta[c], rng)
        tl = np.arange(0.0, schedule.duration_s + timeline_extra_s + 1e-9, timeline_step_s)
        tl_states = self.thermal.states(schedule, tl)
        tl_delta = self.thermal.drift(tl_states)
        qt = np.broadcast_to(self.q_tcp, (len(tl), len(self.q_tcp)))
        T0 = self._flange(self.q_tcp[None], X)[0, :3, 3]
        Tt = np.stack([self._flange(qt[i:i + 1], X + tl_delta[i])[0, :3, 3] for i in range(len(tl))])
        return ThermalRun(schedule, times, states, delta, q_s.copy(), sphere_cold, sphere, self.q_monitor.copy(),
                          monitor_cold, monitor, tl, tl_states, np.linalg.norm(Tt - T0, axis=1), seed)

    def truth(self) -> dict:
        """The cell's hidden truth as plain data (for ``truth.json``)."""
        return {
            "robot": self.model.name,
            "nominal_parameters": self.model.params.as_dict(),
            "true_parameters": self.robot.true_parameters(),
            "T_sensor_base": self.T_sensor_base.tolist(),
            "P_e_mm": self.P_e.tolist(),
            "sphere_diameter_mm": SPHERE_DIAMETER_MM,
            "T_flange_sensor": self.T_flange_sensor.tolist(),
            "body_points_mm": self.body_points.tolist(),
            "sphere_noise_mm": self.sphere_noise_mm,
            "monitor_noise_mm": self.monitor_noise_mm,
            "joint_noise_rad": self.robot.joint_noise.tolist(),
            "heat_sources": [{"name": s.name, "joint": s.joint, "gain_K": s.gain_K, "tau_s": s.tau_s,
                              "direction": dict(zip(self.thermal.names, s.direction.tolist()))}
                             for s in self.thermal.sources],
            "seed": None if self.seed is None else int(self.seed),
        }


# ---------------------------------------------------------------------------------------------- files
def _meas(model, q, points, ids, frame, instrument):
    return Measurements(joints=q, points=points, joint_names=model.controller_joints, pose_ids=ids,
                        prismatic=model.prismatic_joints,
                        metadata={"robot": model.name, "frame": frame, "instrument": instrument})


def write_run(directory, cell: ThermalCell, run: ThermalRun, *, overwrite: bool = False) -> dict:
    """Write a run as measurement files in ``directory``; returns ``{role: path}``.

    ``sphere_cold.csv`` / ``sphere.csv``: the fixed sensor's sphere centres (frame ``sensor``),
    ``monitor_cold.csv`` / ``monitor.csv``: the robot-held sensor's monitored points (frame
    ``tool_sensor``); cycle rows have pose ids ``c<cycle>-p<pose>`` (1-based). ``cycles.csv``:
    cycle, measurement time [s], load, idle after [s]. ``truth.json``: the cell and the true drifts.
    """
    d = Path(directory)
    d.mkdir(parents=True, exist_ok=True)
    m = cell.model
    C, ms, K = run.n_cycles, len(run.q_sphere), len(run.q_monitor)
    sphere_ids = [f"c{c + 1:03d}-p{i + 1:02d}" for c in range(C) for i in range(ms)]
    mon_ids = [f"c{c + 1:03d}-p{i + 1:02d}" for c in range(C) for i in range(K)]
    inst_s = f"stereo fringe projection, sphere d{SPHERE_DIAMETER_MM} mm (simulated, {cell.sphere_noise_mm} mm)"
    inst_m = f"robot-held sensor, car body points (simulated, {cell.monitor_noise_mm} mm)"
    files = {
        "sphere_cold": _meas(m, run.q_sphere, run.sphere_cold, [f"p{i + 1:02d}" for i in range(ms)], "sensor", inst_s),
        "sphere": _meas(m, np.tile(run.q_sphere, (C, 1)), run.sphere.reshape(-1, 3), sphere_ids, "sensor", inst_s),
        "monitor_cold": _meas(m, run.q_monitor, run.monitor_cold, [f"p{i + 1:02d}" for i in range(K)], "tool_sensor",
                              inst_m),
        "monitor": _meas(m, np.tile(run.q_monitor, (C, 1)), run.monitor.reshape(-1, 3), mon_ids, "tool_sensor", inst_m),
    }
    out = {}
    for role, meas in files.items():
        out[role] = write_measurements(d / f"{role}.csv", meas, overwrite=overwrite)
    out["cycles"] = write_cycles(d / "cycles.csv", run.times_s, run.schedule.load, run.schedule.idle_s,
                                 overwrite=overwrite)
    truth = cell.truth()
    truth["delta_true"] = run.delta_true.tolist()
    truth["states_K"] = run.states.tolist()
    out["truth"] = atomic_write_text(d / "truth.json", json.dumps(truth, indent=1), overwrite=overwrite)
    return out
