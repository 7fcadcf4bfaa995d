"""Tool-frame repeatability study with the cross-laser method (thesis 5.2, issue 4 acceptance).

A simulated UR10-class cell: cross-laser sensor with mounting errors (beta != 90 deg, a gap
between the beams, tilted against the base), calibrated by the simulated pin procedure
(:func:`robocal.tcp.sensor.calibrate_sensor`); a cylindrical tool bent by random collisions;
after each collision the tool frame is recalibrated (:func:`robocal.tcp.cross_laser.recalibrate_tool`)
and compared with the truth. Each collision is recalibrated by every variant (with and without
the beta correction, and with the thesis's step-3 centring) on identical robot-noise streams.
"""

from __future__ import annotations

import math

import numpy as np

from ...io.barrier_events import write_events_csv
from ...robots import load_robot
from ...sim.tool.light_barrier import CrossLaserSensor, CylinderTool, LightBarrierCell, simulate_sensor_calibration_points
from ...tcp.cross_laser import CrossLaserSettings, recalibrate_tool
from ...transforms import rotation_angle, transforms_from

__all__ = ["DEFAULT_VARIANTS", "tcp_repeatability_study", "format_study_table"]

#: name -> settings overrides; every collision is recalibrated by each variant
DEFAULT_VARIANTS = {
    "beta_corrected": {},
    "no_beta_correction": {"beta_correction": False},
    "thesis_step3": {"step3_center": "nominal"},
    "thesis_step3_no_beta": {"step3_center": "nominal", "beta_correction": False},
}

UR10_Q_SEED = np.array([0.0, -1.2, 1.6, -1.97, -1.57, 0.0])


def _summary(runs):
    e = np.array([r["tcp_error_mm"] for r in runs])
    a = np.array([r["axis_error_deg"] for r in runs])
    c = np.array([r["cycle_time_s"] for r in runs])
    return {"n": len(runs),
            "tcp_rms_mm": float(np.sqrt(np.mean(e ** 2))),
            "tcp_max_mm": float(e.max()),
            "axis_rms_deg": float(np.sqrt(np.mean(a ** 2))),
            "axis_max_deg": float(a.max()),
            "cycle_mean_s": float(c.mean()),
            "cycle_max_s": float(c.max())}


def tcp_repeatability_study(*, collisions: int = 10, seed: int = 0, robot: str | None = "ur10",
                            repeatability_mm: float = 0.1, io_rate_hz: float = 1000.0, latency_s: float = 0.002,
                            tool_radius_mm: float = 3.0, tool_length_mm: float = 180.0, tip: str = "spherical",
                            beta_deg: float = 88.0, tilt_deg: float = 2.0, gap_mm: float = 0.3, yaw_deg: float = 0.5,
                            sensor_origin_mm=(-850.0, -170.0, 200.0), collision_tilt_deg=(1.0, 3.0),
                            collision_offset_mm=(0.5, 3.0), sensor_calibration: str = "simulated",
                            settings: CrossLaserSettings | None = None, variants: dict | None = None,
                            events_path=None, sensor_path=None, progress=None) -> dict:
    """Recalibrate the tool after ``collisions`` random collisions and compare with the truth.

    Cell: sensor nominally aligned with the base at ``sensor_origin_mm``, ``beta_deg`` between
    the beams, ``gap_mm`` between them, tilted ``tilt_deg`` (about a horizontal axis at 30 deg)
    and turned ``yaw_deg``; robot repeatability ``repeatability_mm`` (ISO 9283), I/O at
    ``io_rate_hz`` with ``latency_s``; tool a ``tip`` cylinder of ``tool_radius_mm`` and
    ``tool_length_mm`` on the flange Z axis; collisions tilt it uniformly in
    ``collision_tilt_deg`` and shift it in ``collision_offset_mm``. ``robot``: a robot name whose
    numerical IK checks that every motion is reachable (``None``: no check).
    ``sensor_calibration``: ``"simulated"`` (pin procedure + ``calibrate_sensor``) or ``"truth"``.
    ``variants``: name -> settings overrides (default :data:`DEFAULT_VARIANTS`).
    ``events_path``: write the first recalibration's events (first variant) there;
    ``sensor_path``: write the sensor calibration used (JSON, the keys of ``robocal tcp
    sensor-calibrate --json``) there.
    Seeds: ``numpy.random.SeedSequence(seed)`` spawns the sensor-calibration, collision and
    per-collision robot-noise streams; every variant sees the same noise stream per collision.
    ``progress(done, total)``: called after each recalibration (``total`` = collisions x variants).

    Returns a dict: ``config``, ``sensor`` (calibration vs truth), ``collisions`` (the damage),
    ``variants`` name -> {``settings``, ``runs`` (per collision: tcp/axis errors, cycle time,
    residuals), ``summary`` (tcp_rms_mm, tcp_max_mm, axis_rms_deg, axis_max_deg, cycle_mean_s,
    cycle_max_s)}, ``reachability`` (worst IK position error over all motions, or None).
    """
    if collisions < 1:
        raise ValueError("collisions must be >= 1")
    settings = settings or CrossLaserSettings()
    variants = DEFAULT_VARIANTS if variants is None else variants
    ss = np.random.SeedSequence(seed)
    s_cal, s_col, s_runs = ss.spawn(3)
    run_seeds = s_runs.spawn(collisions)
    cell_kw = dict(io_rate_hz=io_rate_hz, latency_s=latency_s, repeatability_mm=repeatability_mm)

    T_nom_sensor = transforms_from(np.eye(3), np.asarray(sensor_origin_mm, float))
    sensor = CrossLaserSensor.build(T_nom_sensor, beta_deg=beta_deg, gap_mm=gap_mm, tilt_deg=tilt_deg,
                                    tilt_axis_deg=30.0, yaw_deg=yaw_deg)
    truth = sensor.true_frame()
    cal, cal_d, cal_time = _calibrate_sensor(sensor, T_nom_sensor, truth, sensor_calibration, s_cal, cell_kw)
    if sensor_path is not None:
        _write_sensor_json(sensor_path, cal_d)

    model = load_robot(robot) if robot else None
    tool0 = CylinderTool(transforms_from(np.eye(3), [0.0, 0.0, tool_length_mm]), tool_radius_mm, tool_length_mm, tip)
    rng_col = np.random.default_rng(s_col)
    damage = [tool0.collided(rng_col, tilt_deg=collision_tilt_deg, offset_mm=collision_offset_mm)
              for _ in range(collisions)]

    out_variants = {}
    reach = []
    count = {"done": 0, "total": collisions * len(variants)}

    def tick():
        count["done"] += 1
        if progress is not None:
            progress(count["done"], count["total"])
    for vname, over in variants.items():
        events_note = None
        if events_path is not None and not out_variants:
            events_note = f"simulated cross-laser recalibration, seed {seed}, variant {vname}"
        runs = _run_variant(sensor, cal, tool0, damage, _replace(settings, over), model, run_seeds, cell_kw,
                            reach, events_path, events_note, tick)
        out_variants[vname] = {"settings": over, "runs": runs, "summary": _summary(runs)}

    return {
        "config": {"collisions": collisions, "seed": seed, "robot": robot, "repeatability_mm": repeatability_mm,
                   "io_rate_hz": io_rate_hz, "latency_s": latency_s, "tool_radius_mm": tool_radius_mm,
                   "tool_length_mm": tool_length_mm, "tip": tip, "beta_deg": beta_deg, "tilt_deg": tilt_deg,
                   "gap_mm": gap_mm, "yaw_deg": yaw_deg, "radius_mm": settings.radius_mm,
                   "delta_z_mm": settings.delta_z_mm, "circle_speed_mm_s": settings.circle_speed_mm_s},
        "sensor": _sensor_report(sensor_calibration, cal_time, cal_d, truth),
        "collisions": [{"tilt_deg": info["tilt_deg"], "offset_mm": np.asarray(info["offset_mm"]).tolist(),
                        "T_flange_tool_true": bent.T_flange_tool.tolist()} for bent, info in damage],
        "variants": out_variants,
        "reachability": {"checked": model is not None,
                         "worst_position_error_mm": float(max(reach)) if reach else None},
    }


def _calibrate_sensor(sensor, T_nom_sensor, truth, mode: str, seed, cell_kw: dict):
    """The sensor calibration the recalibrations use: ``"simulated"`` (pin procedure +
    ``calibrate_sensor``) or ``"truth"``. Returns ``(calibration, its JSON dict, time [s])``."""
    if mode == "simulated":
        from ...tcp.sensor import calibrate_sensor

        pts, cal_time = simulate_sensor_calibration_points(sensor, T_nom_sensor, np.random.default_rng(seed),
                                                           **cell_kw)
        cal = calibrate_sensor(pts)
        return cal, cal.to_dict(), cal_time
    if mode == "truth":
        cal_d = {k: np.asarray(v).tolist() if not np.isscalar(v) else float(v) for k, v in truth.items()}
        return truth, cal_d, 0.0
    raise ValueError("sensor_calibration must be 'simulated' or 'truth'")


def _write_sensor_json(path, cal_d: dict) -> None:
    """The sensor calibration as JSON (the keys of ``robocal tcp sensor-calibrate --json``)."""
    import json

    from ...io.atomic import atomic_write_text

    atomic_write_text(path, json.dumps(cal_d, indent=2) + "\n", overwrite=True)


def _sensor_report(mode: str, cal_time, cal_d: dict, truth: dict) -> dict:
    """The sensor calibration against the truth: origin [mm], axis [deg], beta and gap errors."""
    cal_T = np.asarray(cal_d["T_base_sensor"], float)
    return {
        "calibration": mode,
        "calibration_time_s": float(cal_time),
        "origin_error_mm": float(np.linalg.norm(cal_T[:3, 3] - truth["origin_mm"])),
        "x_axis_error_deg": math.degrees(math.acos(min(1.0, float(cal_T[:3, 0] @ truth["x_axis"])))),
        "z_axis_error_deg": math.degrees(math.acos(min(1.0, float(cal_T[:3, 2] @ truth["z_axis"])))),
        "beta_deg": float(cal_d["beta_deg"]), "beta_true_deg": float(truth["beta_deg"]),
        "gap_mm": float(cal_d["gap_mm"]), "gap_true_mm": float(truth["gap_mm"]),
    }


def _run_variant(sensor, cal, tool0, damage, settings, model, run_seeds, cell_kw: dict, reach: list,
                 events_path, events_note, tick=lambda: None):
    """Recalibrate every bent tool of ``damage`` with ``settings``, each on its own robot-noise
    stream; worst IK errors are appended to ``reach``; with ``events_note`` the first
    recalibration's events are written to ``events_path``. Returns the per-collision runs."""
    runs = []
    for i, (bent, _) in enumerate(damage):
        cell = LightBarrierCell(sensor, bent, np.random.default_rng(run_seeds[i]), robot_model=model,
                                q_seed=UR10_Q_SEED if model is not None and model.n_joints == 6 else None, **cell_kw)
        res = recalibrate_tool(cell, cal, tool0.T_flange_tool, settings)
        if events_note is not None and i == 0:
            write_events_csv(events_path, res.records, note=events_note)
        reach.extend(cell.reach_errors_mm)
        runs.append(_run_summary(res, bent.T_flange_tool))
        tick()
    return runs


def _run_summary(res, T_true) -> dict:
    """One recalibration against the true tool frame: TCP [mm] and axis/rotation [deg] errors."""
    return {
        "tcp_error_mm": float(np.linalg.norm(res.tcp_flange_mm - T_true[:3, 3])),
        "tcp_error_vec_mm": (res.tcp_flange_mm - T_true[:3, 3]).tolist(),
        "axis_error_deg": math.degrees(math.acos(min(1.0, float(res.axis_flange @ T_true[:3, 2])))),
        "rotation_error_deg": math.degrees(float(rotation_angle(res.T_flange_tool[:3, :3].T @ T_true[:3, :3]))),
        "cycle_time_s": res.cycle_time_s,
        "psi_deg": math.degrees(res.psi_rad), "theta_deg": math.degrees(res.theta_rad),
        "residuals": res.residuals,
    }


def _replace(settings: CrossLaserSettings, over: dict) -> CrossLaserSettings:
    from dataclasses import replace

    return replace(settings, **over)


def format_study_table(result: dict) -> str:
    """A small text table of :func:`tcp_repeatability_study`'s summaries."""
    c = result["config"]
    s = result["sensor"]
    lines = [f"cross-laser tool recalibration: {c['collisions']} collisions, seed {c['seed']}, robot {c['robot']}, "
             f"repeatability {c['repeatability_mm']} mm, I/O {c['io_rate_hz']:g} Hz, tool r = {c['tool_radius_mm']} mm, "
             f"beta = {c['beta_deg']} deg, sensor tilt {c['tilt_deg']} deg",
             f"sensor calibration ({s['calibration']}): origin error {s['origin_error_mm']:.3f} mm, "
             f"X axis {s['x_axis_error_deg']:.3f} deg, beta {s['beta_deg']:.3f} deg (true {s['beta_true_deg']:.3f})",
             "",
             f"{'variant':<22} {'TCP RMS mm':>10} {'TCP max mm':>10} {'axis RMS deg':>12} {'axis max deg':>12} "
             f"{'cycle max s':>11}"]
    for name, v in result["variants"].items():
        m = v["summary"]
        lines.append(f"{name:<22} {m['tcp_rms_mm']:>10.3f} {m['tcp_max_mm']:>10.3f} {m['axis_rms_deg']:>12.3f} "
                     f"{m['axis_max_deg']:>12.3f} {m['cycle_max_s']:>11.2f}")
    r = result.get("reachability") or {}
    if r.get("checked"):
        lines.append("")
        lines.append(f"reachability ({c['robot']} IK): worst position error {r['worst_position_error_mm']:.2e} mm")
    return "\n".join(lines)
