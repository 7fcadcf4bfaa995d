"""Files of thermal drift compensation (docs/thermal.md, "Files").

* the sensor calibration, ``robocal-thermal-sensor/1`` JSON (:func:`sensor_json`,
  :func:`write_sensor_json`, :func:`read_sensor_json`): ``T_sensor_base`` (4, 4) and the sphere centre ``P_e`` (3,) [mm];
* the thermal cell set-up of a run directory, ``robocal-thermal-setup/1`` JSON
  (:func:`setup_json`, :func:`write_setup_json`, :func:`read_setup_json`): the robot-held sensor on the flange;
* sphere files: measurement files of sphere centres in the sensor frame (:func:`read_sphere_file`);
* a run directory (:data:`RUN_FILES`): cold and per-cycle sphere and monitor measurement files,
  ``cycles.csv`` (:func:`write_cycles`, :func:`read_cycles`) and the set-up; read with the
  consistency checks the command line needs by :func:`read_run` and :func:`read_run_dir`;
* the truth of a simulated run (:func:`read_truth_json`), for checking a sensor calibration.

Taught programs (``robocal-program/1``) are in :mod:`robocal.io.programs.joint_table`. Every problem raises
:class:`ThermalFileError` (a :class:`~robocal.io.header.FileFormatError`) with a one-line message
naming the file and, where known, the line; a missing file or directory raises
``FileNotFoundError``.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

from .atomic import atomic_write_text
from .header import FileFormatError, header_value, read_text
from .measurements import Measurements, read_measurements
from .table import data_rows

__all__ = [
    "SENSOR_FORMAT", "SETUP_FORMAT", "RUN_FILES", "COLD_MATCH_TOL_RAD", "ThermalFileError", "sensor_json",
    "write_sensor_json", "read_sensor_json", "setup_json", "write_setup_json", "read_setup_json", "read_truth_json", "read_sphere_file", "write_cycles",
    "read_cycles", "read_run", "run_dir_robot", "read_run_dir",
]

SENSOR_FORMAT = "robocal-thermal-sensor/1"
SETUP_FORMAT = "robocal-thermal-setup/1"
#: Files of a run directory (``robocal.sim.thermal.simulator.write_run``) the screening reads, plus the set-up.
RUN_FILES = ("sphere_cold.csv", "sphere.csv", "monitor_cold.csv", "monitor.csv", "cycles.csv", "setup.json")
#: Joints of a current sphere pose and its cold reference must agree to this (0.0006 deg).
COLD_MATCH_TOL_RAD = 1e-5


class ThermalFileError(FileFormatError):
    """A file of the thermal commands is malformed; the message names the file and line."""


# ---------------------------------------------------------------------------------------------- JSON files
def _nan_none(x):
    a = np.asarray(x, float)
    return [None if not math.isfinite(v) else float(v) for v in a.ravel()] if a.ndim else (
        None if not math.isfinite(float(a)) else float(a))


def sensor_json(cal, model, source: str) -> dict:
    """The ``robocal-thermal-sensor/1`` content for a :class:`~robocal.thermal.SystemCalibration`
    ``cal`` of ``model`` from the sphere file ``source`` (lengths mm, angles deg)."""
    return {
        "format": SENSOR_FORMAT,
        "robot": model.name,
        "method": cal.method,
        "source": str(source),
        "n_poses": int(cal.n_poses),
        "length_unit": "mm",
        "T_sensor_base": np.asarray(cal.T_sensor_base).tolist(),
        "P_e_mm": np.asarray(cal.P_e).tolist(),
        "std": {"rotation_deg": _nan_none(np.degrees(cal.std_rotation_rad)),
                "translation_mm": _nan_none(cal.std_translation_mm), "P_e_mm": _nan_none(cal.std_P_e_mm)},
        "residual_rms_mm": float(cal.rms_mm),
        "residual_max_mm": float(np.linalg.norm(cal.residuals_mm, axis=1).max()),
    }


def write_sensor_json(path, cal, model, source: str, *, overwrite: bool = False) -> Path:
    """Write :func:`sensor_json` to ``path`` (atomically; an existing file only with ``overwrite``)."""
    return _write_json(path, sensor_json(cal, model, source), overwrite)


def write_setup_json(path, robot: str, T_flange_sensor, sphere_diameter_mm: float, *,
                     overwrite: bool = False) -> Path:
    """Write :func:`setup_json` to ``path`` (atomically; an existing file only with ``overwrite``)."""
    return _write_json(path, setup_json(robot, T_flange_sensor, sphere_diameter_mm), overwrite)


def _write_json(path, data: dict, overwrite: bool) -> Path:
    return atomic_write_text(path, json.dumps(data, indent=1) + "\n", overwrite=overwrite)


def _load_json(path, what: str) -> dict:
    """The JSON object in ``path``; ``what`` names the kind of file in the messages."""
    path = Path(path)
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise FileNotFoundError(f"{path}: no such {what} file") from None
    except IsADirectoryError:
        raise ThermalFileError(path, f"is a directory, expected a {what} JSON file") from None
    except (OSError, UnicodeDecodeError, ValueError) as exc:
        raise ThermalFileError(path, f"cannot read the {what} JSON: {exc}") from None
    if not isinstance(data, dict):
        raise ThermalFileError(path, f"the {what} JSON must be an object")
    return data


def _check_json_format(path, data: dict, fmt: str, what: str) -> None:
    """``data`` is of format ``fmt`` (if it says) and in mm."""
    got = data.get("format", fmt)
    if got != fmt:
        raise ThermalFileError(path, f"format {got!r} is not supported; expected {fmt!r}")
    if data.get("length_unit", "mm") != "mm":
        raise ThermalFileError(path, f"length_unit {data.get('length_unit')!r} is not supported; the {what} JSON is "
                                     "in mm")


def _transform(path, data: dict, key: str) -> np.ndarray:
    """``data[key]`` as a rigid (4, 4) transform [mm]."""
    if key not in data:
        raise ThermalFileError(path, f"missing key {key!r} (a 4x4 transform in mm)")
    try:
        T = np.asarray(data[key], dtype=float)
    except (TypeError, ValueError):
        raise ThermalFileError(path, f"{key!r} is not a 4x4 array of numbers") from None
    if T.shape != (4, 4) or not np.all(np.isfinite(T)):
        raise ThermalFileError(path, f"{key!r} must be a finite 4x4 transform, got shape {T.shape}")
    R = T[:3, :3]
    if not np.allclose(T[3], [0, 0, 0, 1]) or not np.allclose(R @ R.T, np.eye(3), atol=1e-6) or np.linalg.det(R) < 0:
        raise ThermalFileError(path, f"{key!r} is not a rigid transform (rotation not orthonormal or last row not "
                                     "0 0 0 1)")
    return T


def read_sensor_json(path, model=None) -> dict:
    """``{"T_sensor_base": (4, 4), "P_e": (3,), "robot": str, ...}`` from a sensor JSON
    (``robocal thermal calibrate-sensor --out``); lengths in mm. With ``model`` the robot must match."""
    data = _load_json(path, "sensor calibration")
    _check_json_format(path, data, SENSOR_FORMAT, "sensor")
    T = _transform(path, data, "T_sensor_base")
    if "P_e_mm" not in data:
        raise ThermalFileError(path, "missing key 'P_e_mm' (the sphere centre on the flange, mm)")
    try:
        P = np.asarray(data["P_e_mm"], dtype=float)
    except (TypeError, ValueError):
        raise ThermalFileError(path, "'P_e_mm' is not 3 numbers") from None
    if P.shape != (3,) or not np.all(np.isfinite(P)):
        raise ThermalFileError(path, f"'P_e_mm' must be 3 finite numbers [mm], got shape {P.shape}")
    robot = data.get("robot")
    if model is not None and robot and robot != model.name:
        raise ThermalFileError(path, f"the sensor was calibrated for robot {robot!r}, not {model.name!r}")
    return {**data, "T_sensor_base": T, "P_e": P}


def setup_json(robot: str, T_flange_sensor, sphere_diameter_mm: float) -> dict:
    """The ``robocal-thermal-setup/1`` content of a thermal cell (what the user knows of it): the
    robot's name, the robot-held sensor ``T_flange_sensor`` (4, 4) [mm] and the sphere diameter [mm]."""
    return {"format": SETUP_FORMAT, "robot": robot, "length_unit": "mm",
            "T_flange_sensor": np.asarray(T_flange_sensor).tolist(),
            "sphere_diameter_mm": sphere_diameter_mm,
            "note": "T_flange_sensor: the robot-held sensor (monitored points) on the flange, mm"}


def read_setup_json(path) -> dict:
    """The set-up JSON of a run directory with ``T_flange_sensor`` as a (4, 4) array [mm]."""
    data = _load_json(path, "thermal set-up")
    _check_json_format(path, data, SETUP_FORMAT, "set-up")
    return {**data, "T_flange_sensor": _transform(path, data, "T_flange_sensor")}


def read_truth_json(path) -> dict:
    """``{"T_sensor_base": (4, 4), "P_e": (3,)}`` [mm] from a JSON with ``T_sensor_base`` and
    ``P_e_mm`` (e.g. a simulated run's ``truth.json``)."""
    data = _load_json(path, "truth")
    truth = {"T_sensor_base": _transform(path, data, "T_sensor_base"),
             "P_e": np.asarray(data.get("P_e_mm"), float)}
    if truth["P_e"].shape != (3,):
        raise ThermalFileError(path, "'P_e_mm' must be 3 numbers [mm]")
    return truth


# ---------------------------------------------------------------------------------------------- sphere files
def read_sphere_file(path, model, *, what: str = "sphere") -> Measurements:
    """A measurement file of sphere centres (sensor frame, one ``x, y, z`` target) for ``model``."""
    p = Path(path)
    if p.is_dir():
        raise ThermalFileError(p, f"is a directory, expected a {what} measurement file")
    meas = read_measurements(p, robot=model)
    if meas.n_targets != 1:
        raise ThermalFileError(p, f"a {what} file has one point per row (x, y, z), got targets {list(meas.targets)}")
    return meas


# ---------------------------------------------------------------------------------------------- cycles.csv
def write_cycles(path, times_s, load, idle_s, *, overwrite: bool = False) -> Path:
    """``cycles.csv`` of a run: ``cycle,time_s,load,idle_after_s``, one row per cycle (1-based):
    the measurement instant [s], the relative motor load (0-1), the idle time after it [s]."""
    lines = ["cycle,time_s,load,idle_after_s"]
    lines += [f"{c + 1},{float(t)!r},{float(ld)!r},{float(idle)!r}" for c, (t, ld, idle) in
              enumerate(zip(times_s, load, idle_s))]
    return atomic_write_text(path, "\n".join(lines) + "\n", overwrite=overwrite)


def read_cycles(path) -> np.ndarray:
    """The measurement times (C,) [s] of ``cycles.csv`` (its ``time_s`` column)."""
    rows = data_rows(read_text(path, ThermalFileError, what="cycles").splitlines(), 0)
    if not rows:
        raise ThermalFileError(path, "empty (expected a header 'cycle,time_s,...' and one row per cycle)")
    head_line, head = rows[0]
    if "time_s" not in head:
        raise ThermalFileError(path, f"no 'time_s' column (header {head})", head_line)
    j = head.index("time_s")
    out = []
    for line, cells in rows[1:]:
        try:
            t = float(cells[j])
        except (IndexError, ValueError):
            raise ThermalFileError(path, "'time_s' is not a number", line) from None
        if not math.isfinite(t):
            raise ThermalFileError(path, "'time_s' is not finite", line)
        out.append(t)
    if not out:
        raise ThermalFileError(path, "no cycles")
    return np.array(out)


# ---------------------------------------------------------------------------------------------- run directory
def _check_run_dir(directory, setup=None) -> tuple:
    """``(directory, set-up path)`` after checking that the run directory holds its files."""
    d = Path(directory)
    if not d.exists():
        raise FileNotFoundError(f"{d}: no such run directory")
    if not d.is_dir():
        raise ThermalFileError(d, "not a directory (expected a run directory as written by 'robocal thermal "
                                  "simulate')")
    setup_path = Path(setup) if setup is not None else d / "setup.json"
    missing = [f for f in RUN_FILES[:-1] if not (d / f).is_file()]
    if setup is None and not setup_path.is_file():
        missing.append("setup.json")
    if missing:
        raise FileNotFoundError(f"{d}: missing {', '.join(missing)} (a run directory holds {', '.join(RUN_FILES)}; "
                                "see docs/thermal.md)")
    return d, setup_path


def run_dir_robot(directory, setup=None) -> str:
    """The robot a run directory is for: the ``# robot:`` of ``sphere_cold.csv``, else the set-up's."""
    d, setup_path = _check_run_dir(directory, setup)
    robot = header_value(d / "sphere_cold.csv", "robot") or read_setup_json(setup_path).get("robot")
    if not robot:
        raise ThermalFileError(d / "sphere_cold.csv", "no '# robot:' header; give the robot")
    return robot


def read_run(directory, robot=None) -> dict:
    """The measurement files and ``cycles.csv`` of a run directory, checked for consistency.

    robot: a :class:`~robocal.kinematics.RobotModel` (joint columns checked against it) or None.
    Returns ``q_sphere`` (m, n), ``sphere_cold`` (m, 3), ``sphere`` (C, m, 3), ``sphere_ids``
    (m,), ``q_monitor`` (K, n), ``monitor_cold`` (K, 3), ``monitor`` (C, K, 3), ``times_s`` (C,)
    -- mm / rad / s. Every cycle must repeat the cold poses in order.
    """
    d = Path(directory)
    meas = {}
    for name in RUN_FILES[:4]:
        meas[name] = read_measurements(d / name, robot=robot)
        if meas[name].n_targets != 1:
            raise ThermalFileError(d / name, f"expected one point per row (x, y, z), got targets "
                                             f"{list(meas[name].targets)}")
    times = read_cycles(d / "cycles.csv")
    C = len(times)
    for kind in ("sphere", "monitor"):
        cold, cur = meas[f"{kind}_cold.csv"], meas[f"{kind}.csv"]
        m = cold.n_poses
        if cur.n_poses != C * m:
            raise ThermalFileError(d / f"{kind}.csv", f"{cur.n_poses} rows, expected {C} cycles (cycles.csv) x {m} "
                                                     f"poses ({kind}_cold.csv) = {C * m}")
        if not np.allclose(cur.joints, np.tile(cold.joints, (C, 1)), atol=COLD_MATCH_TOL_RAD, rtol=0):
            raise ThermalFileError(d / f"{kind}.csv", f"every cycle must repeat the poses of {kind}_cold.csv in the "
                                                     "same order (joints differ)")
    sc, mc = meas["sphere_cold.csv"], meas["monitor_cold.csv"]
    return {"q_sphere": sc.joints, "sphere_cold": sc.points[:, 0],
            "sphere": meas["sphere.csv"].points[:, 0].reshape(C, -1, 3), "sphere_ids": sc.pose_ids,
            "q_monitor": mc.joints, "monitor_cold": mc.points[:, 0],
            "monitor": meas["monitor.csv"].points[:, 0].reshape(C, -1, 3), "times_s": times}


def read_run_dir(directory, model, *, setup=None) -> dict:
    """Read a run directory (``robocal thermal simulate``: :data:`RUN_FILES`) for ``model`` (a
    :class:`~robocal.kinematics.RobotModel`; :func:`run_dir_robot` names the robot it is for).

    setup: path of the set-up JSON (default ``<directory>/setup.json``). Returns the arrays of
    :func:`read_run` plus ``model``, ``T_flange_sensor`` (4, 4) [mm] and ``setup`` (the set-up JSON).
    """
    d, setup_path = _check_run_dir(directory, setup)
    su = read_setup_json(setup_path)
    return {"model": model, **read_run(d, robot=model), "T_flange_sensor": su["T_flange_sensor"], "setup": su}
