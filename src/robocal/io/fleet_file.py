"""Fleet files: the robots of a plant in one TOML file (``robocal-fleet/1``, docs/fleet.md).

::

    format = "robocal-fleet/1"          # optional
    [options]                           # optional: calibration options for every robot
    holdout = 0.2

    [[robot]]
    id = "body-01"                      # letters, digits, '.', '_', '-' (it names the output folder)
    model = "kuka_kr150_r3100"          # a library robot, or a robot file relative to this file
    measurements = "cal/body-01.csv"    # a robocal-measurements/1 file relative to this file
    tool = [0.0, 0.0, 100.0]            # optional: initial target point in the flange frame [mm]
    cell = "line A / cell 3"            # optional: a label
    options = { loss = "huber" }        # optional: this robot's calibration options

A file that is not TOML or has no ``[[robot]]`` table is an error for the whole file
(:class:`FleetFileError`). A malformed robot entry (missing key, wrong type, unknown option,
missing file, repeated id) is recorded as an :class:`EntryProblem` naming the entry and the reason,
and the other robots stay usable: one bad robot never stops the others.
"""

from __future__ import annotations

import math
import os
import re
import stat
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

from .header import FileFormatError, read_text

__all__ = ["FLEET_FORMAT", "CALIBRATION_OPTIONS", "FleetFileError", "FleetEntry", "EntryProblem", "Fleet",
           "read_fleet"]

FLEET_FORMAT = "robocal-fleet/1"
_ID = re.compile(r"^[A-Za-z0-9][A-Za-z0-9._-]{0,99}$")
_ROBOT_KEYS = {"id", "model", "measurements", "tool", "cell", "options"}
_ROBOT_FILE_SUFFIXES = (".toml", ".urdf")

#: Calibration options a fleet file may set (``robocal calibrate``'s, by their library names) and
#: their types: float, int, bool, str, or a list of str.
CALIBRATION_OPTIONS = {
    "holdout": float, "seed": int, "loss": str, "sigma_mm": float, "method": str, "max_iterations": int,
    "free": list, "fix": list, "free_all": bool, "rotation_weight": float, "use_orientation": bool,
    "drop_duplicates": bool, "force": bool, "particles": int, "generations": int, "allow_unconverged": bool,
}


class FleetFileError(FileFormatError):
    """The fleet file as a whole cannot be read (not TOML, no robots, a bad ``[options]`` table)."""


@dataclass(frozen=True)
class FleetEntry:
    """One robot of the fleet, its paths resolved.

    id: the robot's name in the fleet (output folder, history). model: a library robot name or an
    absolute robot file path (``model_is_file``). measurements: absolute path of the measurement
    file. tool: (3,) initial target point [mm] or None. options: calibration options (defaults
    merged in). index: 1-based position in the file.
    """

    id: str
    model: str
    model_is_file: bool
    measurements: Path
    tool: tuple | None
    cell: str | None
    options: dict
    index: int


@dataclass(frozen=True)
class EntryProblem:
    """A robot entry that cannot run: ``index`` (1-based), ``id`` (None when it has none), ``reason``."""

    index: int
    id: str | None
    reason: str

    def label(self) -> str:
        return self.id if self.id is not None else f"robot #{self.index}"


@dataclass(frozen=True)
class Fleet:
    """A read fleet file: the usable ``entries`` and the ``problems`` of the others (file order)."""

    path: Path
    entries: list = field(default_factory=list)
    problems: list = field(default_factory=list)
    options: dict = field(default_factory=dict)


def _check_options(opts, where: str) -> dict:
    """The options table, type-checked; ``ValueError`` naming ``where``, the key and the expectation."""
    if not isinstance(opts, dict):
        raise ValueError(f"{where} must be a table of calibration options, got {type(opts).__name__}")
    out = {}
    for key, value in opts.items():
        kind = CALIBRATION_OPTIONS.get(key)
        if kind is None:
            raise ValueError(f"{where}: unknown option {key!r}; known: {', '.join(sorted(CALIBRATION_OPTIONS))}")
        if kind is float and isinstance(value, int) and not isinstance(value, bool):
            value = float(value)
        ok = isinstance(value, kind) and not (kind is not bool and isinstance(value, bool))
        if kind is list:
            ok = isinstance(value, list) and all(isinstance(v, str) for v in value)
        if kind is float and ok and not math.isfinite(value):
            ok = False
        if not ok:
            expected = {float: "a number", int: "an integer", bool: "true or false", str: "a string",
                        list: "a list of parameter names"}[kind]
            raise ValueError(f"{where}: option {key!r} must be {expected}, got {value!r}")
        out[key] = value
    return out


def _tool(value, where: str):
    if value is None:
        return None
    if (not isinstance(value, list) or len(value) != 3
            or not all(isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) for v in value)):
        raise ValueError(f"{where}: 'tool' must be three numbers [x, y, z] in mm, got {value!r}")
    return tuple(float(v) for v in value)


def _path(base: Path, value, key: str, where: str, real_dirs: dict) -> Path:
    """``value`` (relative to ``base``) as an existing file's resolved path. real_dirs: the resolved
    folders met so far in this fleet file (one ``realpath`` per folder, not per robot: a fleet's files
    mostly share a folder; os.path instead of pathlib: reading 100 robots 4.7 -> 2.6 ms)."""
    if not isinstance(value, str) or not value.strip():
        raise ValueError(f"{where}: {key!r} must be a file name (a string), got {value!r}")
    full = os.path.join(base, value)  # an absolute value stays as it is
    try:
        mode = os.stat(full).st_mode
    except (OSError, ValueError):
        mode = 0
    if not stat.S_ISREG(mode):
        raise ValueError(f"{where}: {key} file {full} not found" + (" (it is a folder)" if stat.S_ISDIR(mode) else ""))
    if os.path.islink(full):
        return Path(os.path.realpath(full))
    folder, name = os.path.split(full)
    real = real_dirs.get(folder)
    if real is None:
        real = real_dirs[folder] = os.path.realpath(folder)
    return Path(os.path.join(real, name))


def _entry(raw, index: int, base: Path, defaults: dict, real_dirs: dict) -> FleetEntry:
    where = f"robot #{index}"
    if not isinstance(raw, dict):
        raise ValueError(f"{where}: expected a [[robot]] table, got {type(raw).__name__}")
    rid = raw.get("id")
    if rid is not None:
        if not isinstance(rid, str) or not _ID.match(rid):
            raise ValueError(f"{where}: 'id' must be 1-100 letters, digits, '.', '_' or '-' (it names a folder), "
                             f"got {rid!r}")
        where = f"robot #{index} ({rid})"
    unknown = sorted(set(raw) - _ROBOT_KEYS)
    if unknown:
        raise ValueError(f"{where}: unknown key(s) {', '.join(map(repr, unknown))}; a [[robot]] has "
                         f"{', '.join(sorted(_ROBOT_KEYS))}")
    for key in ("id", "model", "measurements"):
        if key not in raw:
            raise ValueError(f"{where}: missing {key!r}")
    model = raw["model"]
    if not isinstance(model, str) or not model.strip():
        raise ValueError(f"{where}: 'model' must be a robot name or a robot file, got {model!r}")
    is_file = model.lower().endswith(_ROBOT_FILE_SUFFIXES) or "/" in model or "\\" in model
    if is_file:
        model = str(_path(base, model, "model", where, real_dirs))
    cell = raw.get("cell")
    if cell is not None and not isinstance(cell, str):
        raise ValueError(f"{where}: 'cell' must be a string, got {cell!r}")
    options = defaults | _check_options(raw.get("options", {}), f"{where}: options")
    return FleetEntry(id=rid, model=model, model_is_file=is_file,
                      measurements=_path(base, raw["measurements"], "measurements", where, real_dirs),
                      tool=_tool(raw.get("tool"), where), cell=cell, options=options, index=index)


def read_fleet(path) -> Fleet:
    """Read a fleet file (see the module docstring). Whole-file problems raise
    :class:`FleetFileError`; an entry's problem is recorded in ``Fleet.problems`` (with its id when it
    has one) and that entry left out of ``Fleet.entries``."""
    path = Path(path)
    text = read_text(path, FleetFileError, "fleet file")
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise FleetFileError(path, f"not a valid TOML file: {exc}") from None
    fmt = data.get("format", FLEET_FORMAT)
    if fmt != FLEET_FORMAT:
        raise FleetFileError(path, f"format {fmt!r} is not {FLEET_FORMAT!r}")
    unknown = sorted(set(data) - {"format", "options", "robot"})
    if unknown:
        raise FleetFileError(path, f"unknown top-level key(s) {', '.join(map(repr, unknown))}; "
                                   "a fleet file has format, [options] and [[robot]] tables")
    try:
        defaults = _check_options(data.get("options", {}), "[options]")
    except ValueError as exc:
        raise FleetFileError(path, str(exc)) from None
    robots = data.get("robot")
    if not isinstance(robots, list) or not robots:
        raise FleetFileError(path, "no robots: add one [[robot]] table per robot (id, model, measurements)")
    base = path.resolve().parent
    fleet = Fleet(path=path.resolve(), options=defaults)
    seen, real_dirs = {}, {}
    for i, raw in enumerate(robots, start=1):
        rid = raw.get("id") if isinstance(raw, dict) and isinstance(raw.get("id"), str) else None
        try:
            entry = _entry(raw, i, base, defaults, real_dirs)
        except ValueError as exc:
            fleet.problems.append(EntryProblem(i, rid, f"{path}: {exc}"))
            continue
        if entry.id in seen:
            fleet.problems.append(EntryProblem(i, entry.id, f"{path}: robot #{i}: id {entry.id!r} repeats robot "
                                                            f"#{seen[entry.id]}; ids must be unique"))
            continue
        seen[entry.id] = i
        fleet.entries.append(entry)
    return fleet
