"""A simulated thermal run as robocal measurement files (docs/measurement-files.md) and back."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from ..io.atomic import atomic_write_text
from ..io.measurements import Measurements, read_measurements, write_measurements

__all__ = ["SPHERE_DIAMETER_MM", "write_run", "read_run"]

#: diameter of the tungsten-carbide sphere on the flange (thesis 5.1.1) [mm]
SPHERE_DIAMETER_MM = 38.1


def _meas(model, q, points, ids, frame, instrument):
    return Measurements(joints=q, points=points, joint_names=model.controller_joints, pose_ids=ids,
                        prismatic=model.prismatic_joints,
                        metadata={"robot": model.name, "frame": frame, "instrument": instrument})


def write_run(directory, cell, run, *, overwrite: bool = False) -> dict:
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
    lines = ["cycle,time_s,load,idle_after_s"]
    lines += [f"{c + 1},{float(t)!r},{float(ld)!r},{float(idle)!r}" for c, (t, ld, idle) in
              enumerate(zip(run.times_s, run.schedule.load, run.schedule.idle_s))]
    out["cycles"] = atomic_write_text(d / "cycles.csv", "\n".join(lines) + "\n", overwrite=overwrite)
    truth = cell.truth()
    truth["delta_true"] = run.delta_true.tolist()
    truth["states_K"] = run.states.tolist()
    out["truth"] = atomic_write_text(d / "truth.json", json.dumps(truth, indent=1), overwrite=overwrite)
    return out


def read_run(directory, robot=None) -> dict:
    """Read the files of :func:`write_run` back: ``{"q_sphere", "sphere_cold", "sphere" (C, m, 3),
    "q_monitor", "monitor_cold", "monitor" (C, K, 3), "times_s" (C,)}`` (arrays, mm / rad / s)."""
    d = Path(directory)
    sc = read_measurements(d / "sphere_cold.csv", robot=robot)
    s = read_measurements(d / "sphere.csv", robot=robot)
    mc = read_measurements(d / "monitor_cold.csv", robot=robot)
    mo = read_measurements(d / "monitor.csv", robot=robot)
    rows = [ln.split(",") for ln in (d / "cycles.csv").read_text().splitlines()[1:] if ln.strip()]
    times = np.array([float(r[1]) for r in rows])
    C = len(times)
    return {"q_sphere": sc.joints, "sphere_cold": sc.points[:, 0], "sphere": s.points[:, 0].reshape(C, -1, 3),
            "q_monitor": mc.joints, "monitor_cold": mc.points[:, 0], "monitor": mo.points[:, 0].reshape(C, -1, 3),
            "times_s": times}
