"""A simulated thermal run written as robocal measurement files (docs/measurement-files.md);
:func:`robocal.io.thermal_files.read_run` reads them back."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from ...io.atomic import atomic_write_text
from ...io.measurements import Measurements, write_measurements
from ...io.thermal_files import write_cycles

__all__ = ["SPHERE_DIAMETER_MM", "write_run"]

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
    out["cycles"] = write_cycles(d / "cycles.csv", run.times_s, run.schedule.load, run.schedule.idle_s,
                                 overwrite=overwrite)
    truth = cell.truth()
    truth["delta_true"] = run.delta_true.tolist()
    truth["states_K"] = run.states.tolist()
    out["truth"] = atomic_write_text(d / "truth.json", json.dumps(truth, indent=1), overwrite=overwrite)
    return out
