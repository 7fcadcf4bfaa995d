"""Files of the ``robocal thermal`` commands (docs/thermal.md, "Command line").

* taught programs, ``robocal-program/1`` (:func:`read_program`, :func:`write_program`): a CSV of
  joint values with a units header, like the measurement files;
* the sensor calibration, ``robocal-thermal-sensor/1`` JSON (:func:`sensor_json`,
  :func:`read_sensor_json`): ``T_sensor_base`` and the sphere centre ``P_e_mm``;
* the thermal cell set-up of a run directory, ``robocal-thermal-setup/1`` JSON
  (:func:`setup_json`, :func:`read_setup_json`): the robot-held sensor on the flange;
* a run directory as :func:`robocal.sim.thermal.write_run` writes it (:func:`read_run_dir`), with
  the consistency checks the command line needs;
* sphere files: selecting poses by id pattern (:func:`select_poses`) and matching a cold
  reference by joints (:func:`match_cold_reference`).

Every problem raises ``ValueError`` (or ``FileNotFoundError``) with a one-line message naming the
file and, where known, the line.
"""

from __future__ import annotations

import csv
import difflib
import fnmatch
import io
import json
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..io.atomic import atomic_write_text
from ..io.header import KEY_RE, FileFormatError, read_header_block
from ..io.measurements import Measurements, read_measurements
from ..transforms import ANGLE_UNITS, LENGTH_UNITS

__all__ = [
    "PROGRAM_FORMAT", "SENSOR_FORMAT", "SETUP_FORMAT", "RUN_FILES", "Program", "ProgramFileError", "read_program",
    "write_program", "sensor_json", "read_sensor_json", "setup_json", "read_setup_json", "read_run_dir",
    "select_poses", "match_cold_reference", "read_sphere_file", "COLD_MATCH_TOL_RAD",
]

PROGRAM_FORMAT = "robocal-program/1"
SENSOR_FORMAT = "robocal-thermal-sensor/1"
SETUP_FORMAT = "robocal-thermal-setup/1"
#: Files of a run directory (``write_run``) the screening reads, plus the set-up.
RUN_FILES = ("sphere_cold.csv", "sphere.csv", "monitor_cold.csv", "monitor.csv", "cycles.csv", "setup.json")
#: Joints of a current sphere pose and its cold reference must agree to this (0.0006 deg).
COLD_MATCH_TOL_RAD = 1e-5

_KEY_ORDER = ("format", "robot", "angle_unit", "length_unit")
_RAD_LOOKS_LIKE_DEG = 4.0 * math.pi


# ---------------------------------------------------------------------------------------------- programs
class ProgramFileError(FileFormatError):
    """A program file is malformed; the message names the file and line."""


@dataclass
class Program:
    """A taught program: ``joints`` (n, n_joints) [rad | mm prismatic] in the model's controller
    joint order, ``names`` (n,) point names, ``metadata`` (header values, e.g. ``angle_unit``)."""

    joints: np.ndarray
    names: tuple
    joint_names: tuple
    metadata: dict = field(default_factory=dict)

    def __len__(self) -> int:
        return len(self.joints)


def read_program(path, model) -> Program:
    """Read a ``robocal-program/1`` file for ``model`` (see docs/thermal.md).

    Header ``# format:``, ``# robot:``, ``# angle_unit: deg|rad`` (required), ``# length_unit:
    mm|m`` (required only with prismatic joints), other ``# key: value`` lines are kept; then a
    header row: an optional ``point`` column (point names) and the controller joint columns (any
    order); one row per point. Values are checked against the joint limits (a unit mistake
    usually shows there)."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8-sig")
    except FileNotFoundError:
        raise FileNotFoundError(f"{path}: no such program file") from None
    except IsADirectoryError:
        raise ValueError(f"{path}: is a directory, expected a program file") from None
    except UnicodeDecodeError as exc:
        raise ProgramFileError(path, f"not a UTF-8 text file ({exc.reason} at byte {exc.start})") from None

    def fail(msg, line=None):
        raise ProgramFileError(path, msg, line)

    lines = text.splitlines()
    md, where, i = read_header_block(lines, fail)
    for key in ("format", "robot", "angle_unit"):
        if not md.get(key):
            fail(f"header is missing '# {key}: ...' (a program file starts with '# format: {PROGRAM_FORMAT}', "
                 "'# robot: <name>', '# angle_unit: deg|rad')")
    if md["format"] != PROGRAM_FORMAT:
        fail(f"format {md['format']!r} is not supported; expected {PROGRAM_FORMAT!r}", where["format"])
    au = md["angle_unit"]
    if au not in ANGLE_UNITS:
        fail(f"unknown angle_unit {au!r}; valid: {', '.join(ANGLE_UNITS)}", where["angle_unit"])
    pris = model.prismatic_joints
    lu = md.get("length_unit")
    if lu is None and pris.any():
        fail(f"robot {model.name!r} has prismatic joints: declare '# length_unit: mm|m'")
    if lu is not None and lu not in LENGTH_UNITS:
        fail(f"unknown length_unit {lu!r}; valid: {', '.join(LENGTH_UNITS)}", where["length_unit"])
    file_robot = md["robot"]
    if file_robot != model.name and not (file_robot.endswith(".toml") or "/" in file_robot):
        fail(f"program is for robot {file_robot!r} but robot model {model.name!r} was given", where["robot"])

    if i >= len(lines):
        fail("no column header row after the '#' header block")
    hline = i + 1
    cols = [c.strip() for c in next(csv.reader([lines[i]]))]
    if len(set(cols)) != len(cols):
        dup = sorted({c for c in cols if cols.count(c) > 1})
        fail(f"column(s) {dup} given twice", hline)
    has_names = bool(cols) and cols[0] == "point"
    jcols = cols[1:] if has_names else cols
    expected = list(model.controller_joints)
    unmatched = [c for c in expected if c not in jcols]
    for c in jcols:
        if c not in expected:
            close = [e for e in unmatched if e.lower() == c.lower()] or difflib.get_close_matches(c, unmatched, n=2) \
                or (unmatched if len(unmatched) == 1 else [])
            hint = f"; did you mean {', '.join(close)}?" if close else ""
            fail(f"column {c!r} is not a joint of robot {model.name!r} ({', '.join(expected)}){hint}"
                 + ("; 'point' (names) must be the first column" if c == "point" else ""), hline)
    missing = [c for c in expected if c not in jcols]
    if missing:
        fail(f"missing joint column(s) {missing} of robot {model.name!r} (its controller joints are {expected})", hline)

    rows, row_lines = [], []
    for k in range(i + 1, len(lines)):
        raw = lines[k]
        if not raw.strip() or raw.lstrip().startswith("#"):
            continue
        fields = [f.strip() for f in next(csv.reader([raw]))]
        if len(fields) != len(cols):
            fail(f"{len(fields)} fields, expected {len(cols)} (one per column of line {hline})", k + 1)
        rows.append(fields)
        row_lines.append(k + 1)
    if not rows:
        fail("no program points (data rows)")
    off = 1 if has_names else 0
    names = [r[0] for r in rows] if has_names else [str(n + 1) for n in range(len(rows))]
    for n, ln in zip(names, row_lines):
        if not n:
            fail("empty point name", ln)
    if len(set(names)) != len(names):
        dup = sorted({n for n in names if names.count(n) > 1})
        fail(f"point name(s) {dup[:5]} given twice")
    vals = np.empty((len(rows), len(jcols)))
    for r, (row, ln) in enumerate(zip(rows, row_lines)):
        for j, cell in enumerate(row[off:]):
            try:
                v = float(cell)
            except ValueError:
                what = f"{cell!r} is not a number" if cell else "empty cell"
                fail(f"column {jcols[j]!r}: {what}", ln)
            if not math.isfinite(v):
                fail(f"column {jcols[j]!r}: {cell!r} is not a finite number", ln)
            vals[r, j] = v
    vals = vals[:, [jcols.index(n) for n in expected]]
    af, lf = ANGLE_UNITS[au], LENGTH_UNITS[lu or "mm"]
    q = np.where(pris, vals * lf, vals * af)
    if au == "rad":
        big = (np.abs(vals) > _RAD_LOOKS_LIKE_DEG) & ~pris
        if big.any():
            r, j = np.argwhere(big)[0]
            fail(f"joint {expected[j]} = {vals[r, j]:g} rad is more than two turns: the values look like degrees; "
                 "declare '# angle_unit: deg'", row_lines[r])
    lo, hi = model.limits[:, 0], model.limits[:, 1]
    bad = (q < lo - 1e-9) | (q > hi + 1e-9)
    if bad.any():
        r, j = np.argwhere(bad)[0]
        s, u = (1.0 / lf, lu or "mm") if pris[j] else (1.0 / af, au)
        fail(f"point {names[r]!r}: joint {expected[j]} = {vals[r, j]:g} {u} is outside its limits "
             f"[{lo[j] * s:.6g}, {hi[j] * s:.6g}] {u} (check '# angle_unit')", row_lines[r])
    md["angle_unit"] = au
    if lu:
        md["length_unit"] = lu
    return Program(q, tuple(names), tuple(expected), md)


def write_program(path, program: Program, model, *, overwrite: bool = False, metadata: dict | None = None) -> Path:
    """Write ``program`` as ``robocal-program/1`` (atomically; an existing file only with
    ``overwrite``), in the units of ``program.metadata`` (default deg / mm), exact round trip."""
    md = dict(program.metadata)
    md.update({str(k): str(v) for k, v in (metadata or {}).items()})
    md["format"] = PROGRAM_FORMAT
    md["robot"] = md.get("robot") or model.name
    au = md.get("angle_unit", "deg")
    pris = model.prismatic_joints
    lu = md.get("length_unit") or ("mm" if pris.any() else None)
    md["angle_unit"] = au
    if lu:
        md["length_unit"] = lu
    notes = md.pop("note", None)
    lines = []
    for key in list(_KEY_ORDER) + sorted(k for k in md if k not in _KEY_ORDER):
        if key in md:
            value = " ".join(str(md[key]).split())
            lines.append(f"# {key}: {value}")
    if notes:
        lines += [f"# note: {n}".rstrip() for n in notes.splitlines()]
    q = np.asarray(program.joints, float)
    vals = np.where(pris, q / LENGTH_UNITS[lu or "mm"], q / ANGLE_UNITS[au])
    buf = io.StringIO()
    buf.write("\n".join(lines) + "\n")
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(["point", *model.controller_joints])
    for n, row in zip(program.names, vals.tolist()):
        w.writerow([n, *(repr(v) for v in row)])
    return atomic_write_text(path, buf.getvalue(), overwrite=overwrite)


# ---------------------------------------------------------------------------------------------- JSON files
def _nan_none(x):
    a = np.asarray(x, float)
    return [None if not math.isfinite(v) else float(v) for v in a.ravel()] if a.ndim else (
        None if not math.isfinite(float(a)) else float(a))


def sensor_json(cal, model, source: str) -> dict:
    """The ``robocal-thermal-sensor/1`` content for a :class:`~robocal.thermal.SystemCalibration`."""
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


def _load_json(path, what):
    path = Path(path)
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise FileNotFoundError(f"{path}: no such {what} file") from None
    except IsADirectoryError:
        raise ValueError(f"{path}: is a directory, expected a {what} JSON file") from None
    except (OSError, UnicodeDecodeError, ValueError) as exc:
        raise ValueError(f"{path}: cannot read the {what} JSON: {exc}") from None
    if not isinstance(data, dict):
        raise ValueError(f"{path}: the {what} JSON must be an object")
    return data


def _transform(path, data, key):
    if key not in data:
        raise ValueError(f"{path}: missing key {key!r} (a 4x4 transform in mm)")
    try:
        T = np.asarray(data[key], dtype=float)
    except (TypeError, ValueError):
        raise ValueError(f"{path}: {key!r} is not a 4x4 array of numbers") from None
    if T.shape != (4, 4) or not np.all(np.isfinite(T)):
        raise ValueError(f"{path}: {key!r} must be a finite 4x4 transform, got shape {T.shape}")
    R = T[:3, :3]
    if not np.allclose(T[3], [0, 0, 0, 1]) or not np.allclose(R @ R.T, np.eye(3), atol=1e-6) or np.linalg.det(R) < 0:
        raise ValueError(f"{path}: {key!r} is not a rigid transform (rotation not orthonormal or last row not 0 0 0 1)")
    return T


def read_sensor_json(path, model=None) -> dict:
    """``{"T_sensor_base": (4, 4), "P_e": (3,), "robot": str, ...}`` from a sensor JSON
    (``robocal thermal calibrate-sensor --out``); lengths in mm. With ``model`` the robot must match."""
    data = _load_json(path, "sensor calibration")
    fmt = data.get("format", SENSOR_FORMAT)
    if fmt != SENSOR_FORMAT:
        raise ValueError(f"{path}: format {fmt!r} is not supported; expected {SENSOR_FORMAT!r}")
    if data.get("length_unit", "mm") != "mm":
        raise ValueError(f"{path}: length_unit {data.get('length_unit')!r} is not supported; the sensor JSON is in mm")
    T = _transform(path, data, "T_sensor_base")
    if "P_e_mm" not in data:
        raise ValueError(f"{path}: missing key 'P_e_mm' (the sphere centre on the flange, mm)")
    try:
        P = np.asarray(data["P_e_mm"], dtype=float)
    except (TypeError, ValueError):
        raise ValueError(f"{path}: 'P_e_mm' is not 3 numbers") from None
    if P.shape != (3,) or not np.all(np.isfinite(P)):
        raise ValueError(f"{path}: 'P_e_mm' must be 3 finite numbers [mm], got shape {P.shape}")
    robot = data.get("robot")
    if model is not None and robot and robot != model.name:
        raise ValueError(f"{path}: the sensor was calibrated for robot {robot!r}, not {model.name!r}")
    return {**data, "T_sensor_base": T, "P_e": P}


def setup_json(cell) -> dict:
    """The ``robocal-thermal-setup/1`` content of a simulated cell (what the user knows of it)."""
    from ..sim.thermal import SPHERE_DIAMETER_MM

    return {"format": SETUP_FORMAT, "robot": cell.model.name, "length_unit": "mm",
            "T_flange_sensor": np.asarray(cell.T_flange_sensor).tolist(),
            "sphere_diameter_mm": SPHERE_DIAMETER_MM,
            "note": "T_flange_sensor: the robot-held sensor (monitored points) on the flange, mm"}


def read_setup_json(path) -> dict:
    data = _load_json(path, "thermal set-up")
    fmt = data.get("format", SETUP_FORMAT)
    if fmt != SETUP_FORMAT:
        raise ValueError(f"{path}: format {fmt!r} is not supported; expected {SETUP_FORMAT!r}")
    if data.get("length_unit", "mm") != "mm":
        raise ValueError(f"{path}: length_unit {data.get('length_unit')!r} is not supported; the set-up JSON is in mm")
    return {**data, "T_flange_sensor": _transform(path, data, "T_flange_sensor")}


# ---------------------------------------------------------------------------------------------- run directory
def _file_robot(path) -> str | None:
    """The ``# robot:`` of a measurement file (None if absent); no full parse."""
    try:
        with open(path, encoding="utf-8-sig") as fh:
            for raw in fh:
                s = raw.strip()
                if s and not s.startswith("#"):
                    break
                m = KEY_RE.match(s)
                if m and m.group(1).lower() == "robot":
                    return m.group(2).strip()
    except (OSError, UnicodeDecodeError):
        return None
    return None


def read_run_dir(directory, robot=None, *, setup=None) -> dict:
    """Read a run directory (``write_run`` + ``setup.json``) with consistency checks.

    robot: a :class:`RobotModel`, a name / robot file, or None (the robot named in
    ``sphere_cold.csv``). setup: path of the set-up JSON (default ``<directory>/setup.json``).
    Returns ``model``, ``q_sphere`` (m, n), ``sphere_cold`` (m, 3), ``sphere`` (C, m, 3),
    ``sphere_ids`` (m,), ``q_monitor`` (K, n), ``monitor_cold`` (K, 3), ``monitor`` (C, K, 3),
    ``times_s`` (C,), ``T_flange_sensor`` (4, 4) -- mm / rad / s.
    """
    from ..robots import load_robot

    d = Path(directory)
    if not d.exists():
        raise FileNotFoundError(f"{d}: no such run directory")
    if not d.is_dir():
        raise ValueError(f"{d}: not a directory (expected a run directory as written by 'robocal thermal simulate')")
    setup_path = Path(setup) if setup is not None else d / "setup.json"
    missing = [f for f in RUN_FILES[:-1] if not (d / f).is_file()]
    if setup is None and not setup_path.is_file():
        missing.append("setup.json")
    if missing:
        raise FileNotFoundError(f"{d}: missing {', '.join(missing)} (a run directory holds {', '.join(RUN_FILES)}; "
                                "see docs/thermal.md)")
    su = read_setup_json(setup_path)
    if robot is None:
        robot = _file_robot(d / "sphere_cold.csv") or su.get("robot")
        if not robot:
            raise ValueError(f"{d / 'sphere_cold.csv'}: no '# robot:' header; give the robot")
    model = load_robot(robot) if isinstance(robot, (str, Path)) else robot
    sc = read_measurements(d / "sphere_cold.csv", robot=model)
    s = read_measurements(d / "sphere.csv", robot=model)
    mc = read_measurements(d / "monitor_cold.csv", robot=model)
    mo = read_measurements(d / "monitor.csv", robot=model)
    for name, meas in (("sphere_cold.csv", sc), ("sphere.csv", s), ("monitor_cold.csv", mc), ("monitor.csv", mo)):
        if meas.n_targets != 1:
            raise ValueError(f"{d / name}: expected one point per row (x, y, z), got targets {list(meas.targets)}")
    times = _read_cycles(d / "cycles.csv")
    C = len(times)
    for name, cold, cur in (("sphere", sc, s), ("monitor", mc, mo)):
        m = cold.n_poses
        if cur.n_poses != C * m:
            raise ValueError(f"{d / (name + '.csv')}: {cur.n_poses} rows, expected {C} cycles (cycles.csv) x {m} poses "
                             f"({name}_cold.csv) = {C * m}")
        if not np.allclose(cur.joints, np.tile(cold.joints, (C, 1)), atol=COLD_MATCH_TOL_RAD, rtol=0):
            raise ValueError(f"{d / (name + '.csv')}: every cycle must repeat the poses of {name}_cold.csv in the same "
                             "order (joints differ)")
    return {"model": model, "q_sphere": sc.joints, "sphere_cold": sc.points[:, 0],
            "sphere": s.points[:, 0].reshape(C, -1, 3), "sphere_ids": sc.pose_ids,
            "q_monitor": mc.joints, "monitor_cold": mc.points[:, 0], "monitor": mo.points[:, 0].reshape(C, -1, 3),
            "times_s": times, "T_flange_sensor": su["T_flange_sensor"], "setup": su}


def _read_cycles(path) -> np.ndarray:
    lines = [(k + 1, ln) for k, ln in enumerate(Path(path).read_text(encoding="utf-8-sig").splitlines())
             if ln.strip() and not ln.lstrip().startswith("#")]
    if not lines:
        raise ValueError(f"{path}: empty (expected a header 'cycle,time_s,...' and one row per cycle)")
    head = [c.strip() for c in lines[0][1].split(",")]
    if "time_s" not in head:
        raise ValueError(f"{path}, line {lines[0][0]}: no 'time_s' column (header {head})")
    j = head.index("time_s")
    out = []
    for ln, raw in lines[1:]:
        f = raw.split(",")
        try:
            t = float(f[j])
        except (IndexError, ValueError):
            raise ValueError(f"{path}, line {ln}: 'time_s' is not a number") from None
        if not math.isfinite(t):
            raise ValueError(f"{path}, line {ln}: 'time_s' is not finite")
        out.append(t)
    if not out:
        raise ValueError(f"{path}: no cycles")
    return np.array(out)


# ---------------------------------------------------------------------------------------------- sphere files
def read_sphere_file(path, model, *, what: str = "sphere") -> Measurements:
    """A measurement file of sphere centres (sensor frame, one ``x, y, z`` target) for ``model``."""
    p = Path(path)
    if p.is_dir():
        raise ValueError(f"{p}: is a directory, expected a {what} measurement file")
    meas = read_measurements(p, robot=model)
    if meas.n_targets != 1:
        raise ValueError(f"{p}: a {what} file has one point per row (x, y, z), got targets {list(meas.targets)}")
    return meas


def select_poses(meas: Measurements, patterns, path="") -> Measurements:
    """The poses whose id matches any of the shell-style ``patterns`` (``c020-p0[1-6]``, ``p03``)."""
    pats = [p for v in patterns for p in str(v).replace(",", " ").split()]
    if not pats:
        return meas
    keep = [i for i, pid in enumerate(meas.pose_ids) if any(fnmatch.fnmatchcase(pid, p) for p in pats)]
    if not keep:
        ex = ", ".join(meas.pose_ids[:3])
        raise ValueError(f"{path}: no pose id matches {', '.join(pats)} (ids are like {ex})")
    return meas.subset(keep)


def match_cold_reference(q, cold: Measurements, path="", ids=None) -> np.ndarray:
    """The cold sphere centre (m, 3) for each pose of ``q`` (m, n): the row of ``cold`` at the
    same joints (within :data:`COLD_MATCH_TOL_RAD`)."""
    q = np.asarray(q, float)
    d = np.abs(q[:, None, :] - cold.joints[None]).max(axis=2)          # (m, N)
    best = d.argmin(axis=1)
    bad = np.flatnonzero(d[np.arange(len(q)), best] > COLD_MATCH_TOL_RAD)
    if bad.size:
        who = ids[bad[0]] if ids is not None else str(bad[0] + 1)
        raise ValueError(f"{path}: no cold reference at the joints of sphere pose {who!r} "
                         f"({bad.size} pose(s) unmatched); the cold file must contain every pose measured now")
    return cold.points[best, 0]
