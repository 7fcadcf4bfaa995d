"""Time-stamped joint logs (``robocal-joint-log/1``) and image capture times (``robocal-frames/1``):
what a camera self-calibration records from a robot (issue 15; docs/joint-log-files.md).

A joint log is the controller's joint readings streamed with time stamps on the robot's clock::

    # format: robocal-joint-log/1
    # robot: nao_h25
    # angle_unit: deg
    # time_unit: s
    # clock: robot
    time_s,HeadYaw,HeadPitch,LShoulderPitch,...
    0.000,1.2034,-10.5021,45.0012,...

A frames file names every image and its capture time on the camera's clock::

    # format: robocal-frames/1
    # time_unit: s
    # clock: camera
    image,time_s
    img_000.png,1.5213

Units are declared in the header (``angle_unit`` deg | rad, ``length_unit`` mm | m for the joints
listed under ``prismatic``, ``time_unit`` s | ms); the readers return rad, mm and seconds. Time
stamps must increase strictly down a joint log; image names must be unique in a frames file.
Problems raise :class:`JointLogFileError` naming file, line and column.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..transforms import ANGLE_UNITS, LENGTH_UNITS
from .atomic import atomic_write_text
from .header import FileFormatError, declared_unit, read_header_block, read_text
from .importers.joint_log import JointLog
from .plausibility import angle_unit_problem
from .table import check_field_counts, csv_cells, data_rows, number_columns

__all__ = ["JOINT_LOG_FORMAT", "FRAMES_FORMAT", "TIME_UNITS", "JointLogFileError", "Frames", "write_joint_log",
           "read_joint_log_file", "write_frames", "read_frames"]

JOINT_LOG_FORMAT = "robocal-joint-log/1"
FRAMES_FORMAT = "robocal-frames/1"
#: time units -> factor to seconds
TIME_UNITS = {"s": 1.0, "ms": 1.0e-3}
_TIME_COLUMN = "time_s"


class JointLogFileError(FileFormatError):
    """A joint-log or frames file is malformed; the message names file, line and column."""


@dataclass(frozen=True, eq=False)
class Frames:
    """Images and their capture times: ``images`` (N,) file names, ``times`` (N,) [s] on the
    ``clock`` named in the file, ``lines`` (N,) 1-based line numbers, ``path``, ``metadata``."""

    images: tuple
    times: np.ndarray
    lines: tuple
    path: str
    clock: str = "camera"
    metadata: dict | None = None

    def __len__(self) -> int:
        return len(self.images)


def _header_text(fmt: str, items: dict) -> list:
    lines = [f"# format: {fmt}"]
    for key, value in items.items():
        if value is None:
            continue
        for part in str(value).splitlines() or [""]:
            lines.append(f"# {key}: {part}")
    return lines


def write_joint_log(path, times_s, joints, joint_names, *, robot: str | None = None, angle_unit: str = "deg",
                    prismatic=(), length_unit: str = "mm", time_unit: str = "s", clock: str = "robot",
                    notes=(), overwrite: bool = False, decimals: int = 6):
    """Write a ``robocal-joint-log/1`` file atomically.

    times_s (N,) [s], strictly increasing; joints (N, n) [rad; mm for ``prismatic`` joint names];
    joint_names (n,) column names (the robot's controller joints). Returns the path.
    """
    t = np.asarray(times_s, dtype=float).ravel()
    q = np.asarray(joints, dtype=float).reshape(len(t), -1)
    names = [str(n) for n in joint_names]
    if q.shape[1] != len(names):
        raise ValueError(f"joints have {q.shape[1]} columns, but {len(names)} joint names are given")
    if angle_unit not in ANGLE_UNITS or length_unit not in LENGTH_UNITS or time_unit not in TIME_UNITS:
        raise ValueError(f"units: angle {angle_unit!r} (deg | rad), length {length_unit!r} (mm | m), "
                         f"time {time_unit!r} (s | ms)")
    if len(t) and not np.all(np.diff(t) > 0):
        k = int(np.flatnonzero(np.diff(t) <= 0)[0])
        raise ValueError(f"time stamps must increase strictly: row {k + 2} ({t[k + 1]} s) after row {k + 1} ({t[k]} s)")
    if not np.all(np.isfinite(q)) or not np.all(np.isfinite(t)):
        raise ValueError("time stamps and joints must be finite numbers")
    pris = np.array([n in set(prismatic) for n in names], dtype=bool)
    scale = np.where(pris, 1.0 / LENGTH_UNITS[length_unit], 1.0 / ANGLE_UNITS[angle_unit])
    head = _header_text(JOINT_LOG_FORMAT, {
        "robot": robot, "angle_unit": angle_unit,
        "length_unit": length_unit if pris.any() else None,
        "prismatic": ", ".join(n for n, p in zip(names, pris) if p) or None,
        "time_unit": time_unit, "clock": clock, "note": "\n".join(notes) or None})
    rows = [",".join([_TIME_COLUMN] + names)]
    tf = t / TIME_UNITS[time_unit]
    qf = q * scale
    for k in range(len(t)):
        rows.append(",".join([f"{tf[k]:.{decimals}f}"] + [f"{v:.{decimals}f}" for v in qf[k]]))
    return atomic_write_text(path, "\n".join(head + rows) + "\n", overwrite=overwrite)


def _read(path, fmt: str):
    """(values, key_line, lines, column row index, fail) of a file of format ``fmt``."""
    text = read_text(path, JointLogFileError, what=fmt.split("/")[0].replace("robocal-", ""))
    lines = text.splitlines()

    def fail(message, line=None, column=None):
        raise JointLogFileError(path, message, line, column)

    values, key_line, i = read_header_block(lines, fail)
    got = values.get("format")
    if got != fmt:
        first = lines[0].strip()[:60] if lines else ""
        fail(f"'# format: {fmt}' header expected, found "
             + (f"format {got!r}" if got else f"no format line (the file starts with {first!r})"), key_line.get("format", 1))
    if i >= len(lines):
        fail("no column row after the header block")
    return values, key_line, lines, i, fail


def _time_scale(values, key_line, fail) -> float:
    unit = declared_unit(values, key_line, "time_unit", TIME_UNITS, fail)
    if unit is None:
        fail("'# time_unit: s' (or ms) header line missing: time units are never guessed")
    return TIME_UNITS[unit]


def read_joint_log_file(path, robot=None) -> JointLog:
    """Read a ``robocal-joint-log/1`` file: a :class:`~robocal.io.importers.joint_log.JointLog`
    with ``joints`` (N, n) [rad; mm for prismatic joints], ``times`` (N,) [s] (``time_kind``
    ``"seconds"``), ``ids`` ``"1".."N"``. With ``robot`` (a :class:`~robocal.kinematics.RobotModel`)
    the columns must be its controller joints, in any order (they are returned in the robot's order)."""
    values, key_line, lines, i, fail = _read(path, JOINT_LOG_FORMAT)
    au = declared_unit(values, key_line, "angle_unit", ANGLE_UNITS, fail)
    if au is None:
        fail("'# angle_unit: deg' (or rad) header line missing: angle units are never guessed")
    lu = declared_unit(values, key_line, "length_unit", LENGTH_UNITS, fail, default="mm")
    ts = _time_scale(values, key_line, fail)
    columns = csv_cells(lines[i])
    if not columns or columns[0] != _TIME_COLUMN:
        fail(f"the first column must be {_TIME_COLUMN!r}, got {columns[:1]}", i + 1)
    names = columns[1:]
    if not names:
        fail("no joint columns after 'time_s'", i + 1)
    dup = sorted({n for n in names if names.count(n) > 1})
    if dup:
        fail(f"joint column(s) {dup} given twice", i + 1)
    prismatic = [p.strip() for p in values.get("prismatic", "").split(",") if p.strip()]
    unknown = [p for p in prismatic if p not in names]
    if unknown:
        fail(f"'prismatic' names {unknown}, which are not joint columns {names}", key_line.get("prismatic"))
    if robot is not None:
        missing = [c for c in robot.controller_joints if c not in names]
        extra = [c for c in names if c not in robot.controller_joints]
        if missing or extra:
            fail(f"joint columns do not match robot {robot.name}'s controller joints {list(robot.controller_joints)}"
                 + (f"; missing {missing}" if missing else "") + (f"; unknown {extra}" if extra else ""), i + 1)
    rows = data_rows(lines, i + 1)
    if not rows:
        fail("no data rows")
    check_field_counts(rows, len(columns), i + 1, fail)
    raw = number_columns(rows, range(len(columns)), lambda msg, line, j: fail(msg, line, columns[j]))
    row_lines = tuple(ln for ln, _ in rows)
    t = raw[:, 0] * ts
    steps = np.diff(t)
    if np.any(steps <= 0):
        k = int(np.flatnonzero(steps <= 0)[0])
        fail(f"time stamps must increase strictly ({raw[k + 1, 0]:g} after {raw[k, 0]:g})", row_lines[k + 1], _TIME_COLUMN)
    pris = np.array([n in prismatic for n in names], dtype=bool)
    q = raw[:, 1:] * np.where(pris, LENGTH_UNITS[lu], ANGLE_UNITS[au])
    problem = angle_unit_problem(q[:, ~pris], au, what="the joint columns") if (~pris).any() else None
    if problem:
        fail(problem, key_line.get("angle_unit"))
    if robot is not None:
        order = [names.index(c) for c in robot.controller_joints]
        q, names, pris = q[:, order], [names[k] for k in order], pris[order]
        lo, hi = robot.limits[:, 0], robot.limits[:, 1]
        bad = (q < lo - math.radians(1.0)) | (q > hi + math.radians(1.0))
        if bad.any():
            r, j = np.argwhere(bad)[0]
            fail(f"joint value outside {robot.name}'s limits by more than 1 deg (wrong unit or robot?)",
                 row_lines[r], names[j])
    notes = tuple(values["note"].splitlines()) if "note" in values else ()
    return JointLog(joints=q, joint_names=tuple(names), ids=tuple(str(k + 1) for k in range(len(q))),
                    lines=row_lines, path=str(path), prismatic=pris, times=t, time_kind="seconds",
                    angle_unit=au, notes=notes)


def write_frames(path, images, times_s, *, time_unit: str = "s", clock: str = "camera", notes=(),
                 overwrite: bool = False, decimals: int = 6):
    """Write a ``robocal-frames/1`` file atomically: image file names (N,) and capture times (N,) [s]."""
    names = [str(n) for n in images]
    t = np.asarray(times_s, dtype=float).ravel()
    if len(names) != len(t):
        raise ValueError(f"{len(names)} image names but {len(t)} time stamps")
    if len(set(names)) != len(names):
        raise ValueError("image names must be unique")
    if any("," in n or n != n.strip() for n in names):
        raise ValueError("image names must not contain commas or surrounding spaces")
    if time_unit not in TIME_UNITS:
        raise ValueError(f"time_unit {time_unit!r}: expected s or ms")
    head = _header_text(FRAMES_FORMAT, {"time_unit": time_unit, "clock": clock, "note": "\n".join(notes) or None})
    tf = t / TIME_UNITS[time_unit]
    rows = ["image," + _TIME_COLUMN] + [f"{n},{v:.{decimals}f}" for n, v in zip(names, tf)]
    return atomic_write_text(path, "\n".join(head + rows) + "\n", overwrite=overwrite)


def read_frames(path) -> Frames:
    """Read a ``robocal-frames/1`` file (capture times in seconds)."""
    values, key_line, lines, i, fail = _read(path, FRAMES_FORMAT)
    ts = _time_scale(values, key_line, fail)
    columns = csv_cells(lines[i])
    if columns != ["image", _TIME_COLUMN]:
        fail(f"columns must be 'image,{_TIME_COLUMN}', got {','.join(columns)!r}", i + 1)
    rows = data_rows(lines, i + 1)
    if not rows:
        fail("no data rows")
    check_field_counts(rows, 2, i + 1, fail)
    seen = {}
    for line, cells in rows:
        if not cells[0]:
            fail("empty image name", line, "image")
        if cells[0] in seen:
            fail(f"image {cells[0]!r} listed twice (first on line {seen[cells[0]]})", line, "image")
        seen[cells[0]] = line
    t = number_columns(rows, [1], lambda msg, line, j: fail(msg, line, _TIME_COLUMN))[:, 0] * ts
    md = {k: v for k, v in values.items() if k != "format"}
    return Frames(images=tuple(c[0] for _, c in rows), times=t, lines=tuple(ln for ln, _ in rows), path=str(path),
                  clock=values.get("clock", "camera"), metadata=md)
