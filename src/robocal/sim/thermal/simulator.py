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
* Effects outside the compensation model (:mod:`robocal.sim.thermal.effects`): the ``ideal``
  preset has none (this module's behaviour, bit for bit); ``realistic`` adds two-speed nonlinear
  heating with program-dependent duty, the hall temperature (arm, base, sensor stand, car body),
  link bending and a sag that softens with heat, backlash, noise growing with distance and
  outliers; such a cell runs :func:`robocal.sim.thermal.realistic.simulate_realistic`.

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

import math
from dataclasses import dataclass, field

import numpy as np

from ...kinematics.model import RobotModel
from ...transforms import invert_transforms, rot_x, so3_exp
from ..robot import VirtualRobot, as_rng
from .effects import ThermalEffects, thermal_effects
from .heat import HeatSource, ThermalModel
from .poses import car_body_points, monitor_poses
from .run_files import SPHERE_DIAMETER_MM, write_run
from .schedule import MEASUREMENT_LOAD, PRODUCTION_LOAD, ProductionSchedule, standard_schedules

__all__ = [
    "SPHERE_DIAMETER_MM", "HeatSource", "ThermalModel", "ProductionSchedule", "standard_schedules",
    "ThermalCell", "ThermalRun", "car_body_points", "monitor_poses", "write_run",
    "PRODUCTION_LOAD", "MEASUREMENT_LOAD", "ThermalEffects", "thermal_effects",
]


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
    conditions: dict | None = None

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
    effects: the :class:`~robocal.sim.thermal.effects.ThermalEffects` outside the model (default
    none: the ideal cell); realism: what the cell drew for them
    (:class:`~robocal.sim.thermal.realistic.RealismState`, None when ideal).
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
    effects: ThermalEffects = field(default_factory=ThermalEffects.ideal)
    realism: object = None

    @property
    def model(self) -> RobotModel:
        """The nominal model (what the compensation knows)."""
        return self.robot.nominal

    @classmethod
    def standard(cls, seed: int = 2024, *, robot: str | RobotModel = "kuka_kr150_r3100", n_sphere_poses: int = 20,
                 n_monitor: int = 34, sphere_centre=(1600.0, -1250.0, 1000.0), sphere_spread_mm=(250.0, 200.0, 150.0),
                 sphere_tilt_deg: float = 60.0, P_e=(25.0, -40.0, 160.0), sphere_noise_mm: float = 0.02,
                 monitor_noise_mm: float = 0.02, joint_noise_deg: float = 0.0003, length_sigma_mm: float = 0.2,
                 angle_sigma_deg: float = 0.02, drift_scale: float = 1.0, drift_leak: float = 1.0,
                 preset="ideal") -> "ThermalCell":
        """The thesis-like cell on the KR150 R3100 (every draw from ``seed``).

        The stereo sensor stands 700 mm below the sphere measurement volume (``sphere_centre``,
        base frame) looking up, with a random turn and tilt; ``n_sphere_poses`` sphere poses span
        ``sphere_spread_mm`` (half sizes) with flange tilts up to ``sphere_tilt_deg``
        (:func:`robocal.thermal.design_sphere_poses`). The robot-held sensor sits 180 mm in front
        of the flange; ``n_monitor`` points on a car body (~1.5 x 1 m, centred 2.1 m in front of
        the robot). The true robot differs from the nominal model by ``length_sigma_mm`` /
        ``angle_sigma_deg`` (a calibrated robot's residual errors) and has joint-angle noise
        ``joint_noise_deg`` (5e-6 rad ~ 0.015 mm at 3 m, the KR150's repeatability).
        ``preset``: ``"ideal"`` (no effect outside the model), ``"realistic"`` or a
        :class:`~robocal.sim.thermal.effects.ThermalEffects`; the realism is drawn from the
        seed's seventh stream, so every other draw is the same for every preset.
        """
        from ...robots import load_robot
        from ...thermal import design_sphere_poses

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
        cell = cls(true, thermal, invert_transforms(T_bs), P_e, T_fs, body, q_sphere, q_mon, q_tcp,
                   sphere_noise_mm, monitor_noise_mm, centre, seed, thermal_effects(preset))
        if not cell.effects.is_ideal:
            from .realistic import realism_state

            cell.realism = realism_state(cell, int(seeds[6]))
        return cell

    # ------------------------------------------------------------------ measurement
    def _flange(self, q, params):
        """True flange poses in the base frame (N, 4, 4) for actual joints and parameters."""
        T, _, _, _ = self.robot.true_model.kinematics_with(q, params, np.eye(4), [0])
        return T[:, 0]

    def measure_sphere(self, q, params, rng) -> np.ndarray:
        """Sphere centres (m, 3) in the sensor frame for commanded ``q`` with true parameters ``params``
        (a realistic cell: cold hall, fresh approach sides, its noise and outliers)."""
        rng = as_rng(rng)
        if not self.effects.is_ideal:
            return self._measure_realistic("sphere", q, params, rng)
        qa = self.robot.encoder_noise(q, rng)
        T = self._flange(qa, params)
        p = T[:, :3, :3] @ self.P_e + T[:, :3, 3]
        p = p @ self.T_sensor_base[:3, :3].T + self.T_sensor_base[:3, 3]
        return p + rng.standard_normal(p.shape) * self.sphere_noise_mm

    def measure_monitor(self, q, params, rng) -> np.ndarray:
        """Monitored points (K, 3) in the robot-held sensor frame (point k from pose ``q[k]``)."""
        rng = as_rng(rng)
        if not self.effects.is_ideal:
            return self._measure_realistic("monitor", q, params, rng)
        qa = self.robot.encoder_noise(q, rng)
        T = self._flange(qa, params) @ self.T_flange_sensor
        d = self.body_points - T[:, :3, 3]
        p = np.einsum("kji,kj->ki", T[:, :3, :3], d)
        return p + rng.standard_normal(p.shape) * self.monitor_noise_mm

    def _measure_realistic(self, which, q, params, rng):
        from . import realistic as tr

        q = np.atleast_2d(np.asarray(q, float))
        inst = tr.Instant(np.asarray(params, float) - self.robot.true_model.params.values, None, np.eye(4),
                          np.eye(4), self.body_points)
        sides = tr.approach_sides(len(q), q.shape[1], rng)
        fn = tr.measure_sphere if which == "sphere" else tr.measure_monitor
        return fn(self, q, inst, sides, rng)[0]

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
        ``timeline_extra_s`` extends the thermal timeline past the end (idle cooling). A cell with
        effects runs :func:`robocal.sim.thermal.realistic.simulate_realistic` instead."""
        if not self.effects.is_ideal:
            from .realistic import simulate_realistic

            return simulate_realistic(self, schedule, rng, q_sphere=q_sphere, timeline_step_s=timeline_step_s,
                                      timeline_extra_s=timeline_extra_s)
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
            "effects": self.effects.as_dict(),
        }
