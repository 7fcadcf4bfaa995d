"""A run of the thermal cell with the out-of-model effects of :mod:`robocal.sim.thermal.effects`.

:func:`simulate_realistic` replaces :meth:`ThermalCell.simulate` when the cell has any effect on.
Per measurement instant t it builds the :class:`Instant` -- the true parameter drift (motor heat
through the parameter directions, plus the hall's uniform expansion of every length), the link
twists of the bent arm, the base and sensor-stand motions and the expanded car body -- and
measures through it:

* sphere: actual joints = commanded + joint noise + backlash; flange = true FK at the drifted
  parameters, moved by the link twists, then by the base motion (world = the cold base frame);
  seen from the moved sensor, ``P_s = T_sensor_base S(t)^-1 T_world_flange P_e``; plus
  distance-dependent noise and occasional outliers;
* monitored point k: the robot-held sensor at the same kind of actual flange pose sees the
  (expanded) body point; noise and outliers likewise.

Every draw comes from the run's generator; with every effect off this module is not used.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...transforms import invert_transforms
from ..robot import as_rng, parameter_kinds
from .deformation import apply_link_twists, link_geometry, link_twists, sag_offsets, small_transform
from .measurement import add_outliers, approach_sides, backlash_offsets, distance_noise
from .response import hall_temperature, motor_temperatures

__all__ = ["RealismState", "Instant", "realism_state", "instants", "measure_sphere", "measure_monitor",
           "simulate_realistic"]


@dataclass(frozen=True)
class RealismState:
    """What a realistic cell draws once: ``geometry`` (bending segments, or None), horizontal
    unit axes of the base and sensor-stand tilts (3,), the approach sides of the sphere poses
    (m, n) and monitored poses (K, n), the sensor origin and the car-body centre (3,) [mm]."""

    geometry: object
    base_axis: np.ndarray
    sensor_axis: np.ndarray
    sphere_sides: np.ndarray
    monitor_sides: np.ndarray
    sensor_origin: np.ndarray
    body_centre: np.ndarray


@dataclass(frozen=True)
class Instant:
    """The cell at one moment: ``delta`` (P,) parameter drift [mm | rad]; ``twists`` (n, 6) link
    twists or None; ``base``, ``sensor`` (4, 4): base and sensor-stand motions (world);
    ``body`` (K, 3): the car-body points [mm]; ``temps`` (S,): the motors' rise [K] (for the sag)."""

    delta: np.ndarray
    twists: np.ndarray | None
    base: np.ndarray
    sensor: np.ndarray
    body: np.ndarray
    temps: np.ndarray | None = None


def _horizontal(rng) -> np.ndarray:
    g = rng.uniform(0.0, 2.0 * np.pi)
    return np.array([np.cos(g), np.sin(g), 0.0])


def realism_state(cell, rng) -> RealismState:
    """Draw the cell's fixed realism (``rng``: seed or Generator)."""
    rng = as_rng(rng)
    fx, model = cell.effects, cell.robot.true_model
    geom = link_geometry(model, rng, len(cell.thermal.sources)) if fx.deformation is not None else None
    n = model.n_joints
    return RealismState(geom, _horizontal(rng), _horizontal(rng), approach_sides(len(cell.q_sphere), n, rng),
                        approach_sides(len(cell.q_monitor), n, rng), invert_transforms(cell.T_sensor_base)[:3, 3],
                        cell.body_points.mean(axis=0))


def cold_instant(cell) -> Instant:
    """The cell at the cold start (no drift anywhere)."""
    P = len(cell.model.params)
    return Instant(np.zeros(P), None, np.eye(4), np.eye(4), cell.body_points)


def instants(cell, schedule, times_s, rng) -> tuple:
    """``(instants (list of T), temperatures (T, S) [K], hall (T,) [K])`` at ``times_s``."""
    fx, th, st = cell.effects, cell.thermal, cell.realism
    if fx.heat is not None:
        temps = motor_temperatures(th, schedule, times_s, fx.heat)
    else:
        temps = th.states(schedule, times_s)
    delta = th.drift(temps)
    hall = hall_temperature(times_s, fx.hall, rng) if fx.hall is not None else np.zeros(len(temps))
    twists = None
    if fx.deformation is not None:
        twists = link_twists(st.geometry, temps, fx.deformation, len(cell.robot.true_model.links))
    out = []
    for i, dT in enumerate(hall):
        d, base, sensor, body = delta[i], np.eye(4), np.eye(4), cell.body_points
        if fx.hall is not None:
            h = fx.hall
            lengths = parameter_kinds(cell.model) == "length"
            d = d + np.where(lengths & cell.model.params.free, cell.model.params.values, 0.0) * h.arm_expansion_per_K * dT
            base = small_transform(st.base_axis * h.base_tilt_urad_per_K * 1e-6 * dT, [0.0, 0.0, h.base_lift_mm_per_K * dT])
            sensor = small_transform(st.sensor_axis * h.sensor_tilt_urad_per_K * 1e-6 * dT,
                                     [0.0, 0.0, h.sensor_shift_mm_per_K * dT], st.sensor_origin)
            body = st.body_centre + (1.0 + h.body_expansion_per_K * dT) * (cell.body_points - st.body_centre)
        out.append(Instant(d, None if twists is None else twists[i], base, sensor, body, temps[i]))
    return out, temps, hall


def _world_flange(cell, q, inst: Instant, sides, rng) -> np.ndarray:
    """Actual flange poses (N, 4, 4) in the world (cold base frame) for commanded ``q`` (N, n)."""
    qa = cell.robot.encoder_noise(q, rng)
    if cell.effects.joints is not None:
        qa = qa + backlash_offsets(sides, cell.effects.joints, rng)
    if inst.temps is not None and cell.effects.deformation is not None:
        qa = qa + sag_offsets(cell.robot.true_model, q, cell.realism.geometry, inst.temps, cell.effects.deformation)
    T = cell._flange(qa, cell.robot.true_model.params.values + inst.delta)
    if inst.twists is not None:
        T = apply_link_twists(cell.robot.true_model, qa, T, inst.twists)
    return inst.base @ T


def _errors(cell, p, which: str, rng):
    """Noise and outliers for points ``p`` (N, 3) in a sensor frame; ``(points, outlier mask)``."""
    fx = cell.effects
    if fx.noise is not None:
        nz = fx.noise
        lat, dep, ref = ((nz.sphere_lateral_mm, nz.sphere_depth_mm, nz.sphere_ref_mm) if which == "sphere" else
                         (nz.monitor_lateral_mm, nz.monitor_depth_mm, nz.monitor_ref_mm))
        p = p + distance_noise(p, lat, dep, ref, rng)
    else:
        sigma = cell.sphere_noise_mm if which == "sphere" else cell.monitor_noise_mm
        p = p + rng.standard_normal(p.shape) * sigma
    if fx.outliers is not None:
        o = fx.outliers
        prob, rg = (o.sphere_probability, o.sphere_range_mm) if which == "sphere" else \
            (o.monitor_probability, o.monitor_range_mm)
        return add_outliers(p, prob, rg, rng)
    return p, np.zeros(len(p), bool)


def measure_sphere(cell, q, inst: Instant, sides, rng):
    """Sphere centres (m, 3) in the sensor frame and their outlier mask (m,)."""
    T = _world_flange(cell, q, inst, sides, rng)
    p = T[:, :3, :3] @ cell.P_e + T[:, :3, 3]
    Ts = cell.T_sensor_base @ invert_transforms(inst.sensor)
    return _errors(cell, p @ Ts[:3, :3].T + Ts[:3, 3], "sphere", rng)


def measure_monitor(cell, q, inst: Instant, sides, rng):
    """Monitored points (K, 3) in the robot-held sensor frame and their outlier mask (K,)."""
    T = _world_flange(cell, q, inst, sides, rng) @ cell.T_flange_sensor
    p = np.einsum("kji,kj->ki", T[:, :3, :3], inst.body - T[:, :3, 3])
    return _errors(cell, p, "monitor", rng)


def _sides(stored, q, n_joints, rng):
    return stored if len(stored) == len(q) else approach_sides(len(q), n_joints, rng)


def _tcp_drift(cell, inst_list) -> np.ndarray:
    """Flange-origin drift (T,) [mm] at ``q_tcp`` through the instants (no noise)."""
    model, fx = cell.robot.true_model, cell.effects
    q = np.repeat(cell.q_tcp[None], len(inst_list), axis=0)
    if fx.deformation is not None:
        temps = np.array([i.temps for i in inst_list])
        q = q + sag_offsets(model, q, cell.realism.geometry, temps, fx.deformation)
    X = model.params.values
    T = np.concatenate([cell._flange(q[i:i + 1], X + inst.delta) for i, inst in enumerate(inst_list)])
    if fx.deformation is not None:
        T = apply_link_twists(model, q, T, np.array([i.twists for i in inst_list]))
    base = np.array([i.base for i in inst_list])
    p = np.einsum("tij,tj->ti", base[:, :3, :3], T[:, :3, 3]) + base[:, :3, 3]
    return np.linalg.norm(p - cell._flange(cell.q_tcp[None], X)[0, :3, 3], axis=1)


def simulate_realistic(cell, schedule, rng, *, q_sphere=None, timeline_step_s: float = 60.0,
                       timeline_extra_s: float = 0.0):
    """The realistic counterpart of :meth:`ThermalCell.simulate` (same arguments and result;
    ``run.conditions`` adds ``hall_K`` (C,), ``sphere_outliers`` (C, m), ``monitor_outliers``
    (C, K) and the preset's name)."""
    from .simulator import ThermalRun

    seed = rng if isinstance(rng, (int, np.integer)) and not isinstance(rng, bool) else None
    rng = as_rng(rng)
    fx = cell.effects
    if fx.heat is not None:
        schedule = schedule.with_programs(rng, fx.heat.n_programs, fx.heat.duty_spread)
    q_s = cell.q_sphere if q_sphere is None else np.asarray(q_sphere, float)
    n = cell.robot.true_model.n_joints
    s_sides = _sides(cell.realism.sphere_sides, q_s, n, rng)
    m_sides = cell.realism.monitor_sides
    times = schedule.measurement_times_s
    tl = np.arange(0.0, schedule.duration_s + timeline_extra_s + 1e-9, timeline_step_s)
    all_inst, all_temps, all_hall = instants(cell, schedule, np.concatenate([times, tl]), rng)
    C = len(times)
    cold = cold_instant(cell)
    sphere_cold, _ = measure_sphere(cell, q_s, cold, s_sides, rng)
    monitor_cold, _ = measure_monitor(cell, cell.q_monitor, cold, m_sides, rng)
    sphere = np.empty((C, len(q_s), 3))
    monitor = np.empty((C, len(cell.q_monitor), 3))
    s_out = np.zeros((C, len(q_s)), bool)
    m_out = np.zeros((C, len(cell.q_monitor)), bool)
    for c in range(C):
        monitor[c], m_out[c] = measure_monitor(cell, cell.q_monitor, all_inst[c], m_sides, rng)
        sphere[c], s_out[c] = measure_sphere(cell, q_s, all_inst[c], s_sides, rng)
    delta = np.array([i.delta for i in all_inst[:C]])
    run = ThermalRun(schedule, times, all_temps[:C], delta, q_s.copy(), sphere_cold, sphere, cell.q_monitor.copy(),
                     monitor_cold, monitor, tl, all_temps[C:], _tcp_drift(cell, all_inst[C:]), seed)
    run.conditions = {"preset": fx.name, "hall_K": all_hall[:C], "sphere_outliers": s_out,
                      "monitor_outliers": m_out}
    return run
