"""robocal's own robot programs, format ``robocal-program/1`` (docs/thermal.md, "Files"): a taught
program as a table of joint values, written and corrected by ``robocal thermal``.

A CSV file of joint values with a units header, like the measurement files::

    # format: robocal-program/1
    # robot: kuka_kr150_r3100
    # angle_unit: deg
    point,A1,A2,A3,A4,A5,A6
    P01,12.5,-90.0,95.0,0.0,30.0,0.0

Inside robocal (:class:`JointProgram`) joints are radians (mm for prismatic joints) in the robot
model's controller joint order. Every problem raises :class:`JointProgramFileError` naming the
file and line; a missing file raises ``FileNotFoundError``. (Controller languages: KRL, RAPID,
FANUC TP, UR script are the other modules of :mod:`robocal.io.programs`.)
"""

from __future__ import annotations

import csv
import difflib
import io
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ...transforms import ANGLE_UNITS, LENGTH_UNITS
from ..atomic import atomic_write_text
from ..header import FileFormatError, declared_unit, read_header_block, read_text
from ..plausibility import angle_unit_problem
from ..table import check_field_counts, csv_cells, data_rows, number_columns

__all__ = ["JOINT_PROGRAM_FORMAT", "JointProgram", "JointProgramFileError", "read_joint_program",
           "write_joint_program"]

JOINT_PROGRAM_FORMAT = "robocal-program/1"

_KEY_ORDER = ("format", "robot", "angle_unit", "length_unit")


class JointProgramFileError(FileFormatError):
    """A program file is malformed; the message names the file and line."""


@dataclass
class JointProgram:
    """A taught program: ``joints`` (n, n_joints) [rad | mm prismatic] in the model's controller
    joint order, ``names`` (n,) point names, ``joint_names`` (n_joints,) the controller joints,
    ``metadata`` (header values, e.g. ``angle_unit``)."""

    joints: np.ndarray
    names: tuple
    joint_names: tuple
    metadata: dict = field(default_factory=dict)

    def __len__(self) -> int:
        return len(self.joints)


# ---------------------------------------------------------------------------------------------- reading
def _check_header(md: dict, where: dict, model, fail) -> tuple:
    """``(angle_unit, length_unit or None)`` of a program header for ``model``."""
    for key in ("format", "robot", "angle_unit"):
        if not md.get(key):
            fail(f"header is missing '# {key}: ...' (a program file starts with "
                 f"'# format: {JOINT_PROGRAM_FORMAT}', '# robot: <name>', '# angle_unit: deg|rad')")
    if md["format"] != JOINT_PROGRAM_FORMAT:
        fail(f"format {md['format']!r} is not supported; expected {JOINT_PROGRAM_FORMAT!r}", where["format"])
    au = declared_unit(md, where, "angle_unit", ANGLE_UNITS, fail)
    if "length_unit" not in md and model.prismatic_joints.any():
        fail(f"robot {model.name!r} has prismatic joints: declare '# length_unit: mm|m'")
    lu = declared_unit(md, where, "length_unit", LENGTH_UNITS, fail)
    file_robot = md["robot"]
    if file_robot != model.name and not (file_robot.endswith(".toml") or "/" in file_robot):
        fail(f"program is for robot {file_robot!r} but robot model {model.name!r} was given", where["robot"])
    return au, lu


def _joint_columns(cols: list, line: int, model, fail) -> list:
    """The joint columns of the column row ``cols`` (after an optional ``point`` column), checked
    against the model's controller joints (close-name hints for a misspelt one)."""
    if len(set(cols)) != len(cols):
        dup = sorted({c for c in cols if cols.count(c) > 1})
        fail(f"column(s) {dup} given twice", line)
    jcols = cols[1:] if cols and cols[0] == "point" else cols
    expected = list(model.controller_joints)
    unmatched = [c for c in expected if c not in jcols]
    for c in jcols:
        if c not in expected:
            close = [e for e in unmatched if e.lower() == c.lower()] or difflib.get_close_matches(c, unmatched, n=2) \
                or (unmatched if len(unmatched) == 1 else [])
            hint = f"; did you mean {', '.join(close)}?" if close else ""
            fail(f"column {c!r} is not a joint of robot {model.name!r} ({', '.join(expected)}){hint}"
                 + ("; 'point' (names) must be the first column" if c == "point" else ""), line)
    if unmatched:
        fail(f"missing joint column(s) {unmatched} of robot {model.name!r} (its controller joints are {expected})",
             line)
    return jcols


def _point_names(rows: list, has_names: bool, fail) -> list:
    """The point names: the ``point`` column, else ``"1" .. "n"``; non-empty and unique."""
    names = [cells[0] for _, cells in rows] if has_names else [str(n + 1) for n in range(len(rows))]
    for n, (line, _) in zip(names, rows):
        if not n:
            fail("empty point name", line)
    if len(set(names)) != len(names):
        dup = sorted({n for n in names if names.count(n) > 1})
        fail(f"point name(s) {dup[:5]} given twice")
    return names


def _internal_joints(vals, rows, names, au, lu, model, fail) -> np.ndarray:
    """File values (n, n_joints) in the model's joint order -> rad / mm, checked for degrees
    declared as radians and against the joint limits (a unit mistake usually shows there)."""
    pris, expected = model.prismatic_joints, model.controller_joints
    af, lf = ANGLE_UNITS[au], LENGTH_UNITS[lu or "mm"]
    q = np.where(pris, vals * lf, vals * af)
    revolute = np.abs(q[:, ~pris])
    problem = angle_unit_problem(revolute, au, what="revolute joint values")
    if problem:
        r = int(np.unravel_index(np.argmax(revolute), revolute.shape)[0]) if au == "rad" else 0
        fail(problem, rows[r][0])
    lo, hi = model.limits[:, 0], model.limits[:, 1]
    bad = (q < lo - 1e-9) | (q > hi + 1e-9)
    if bad.any():
        r, j = np.argwhere(bad)[0]
        s, u = (1.0 / lf, lu or "mm") if pris[j] else (1.0 / af, au)
        fail(f"point {names[r]!r}: joint {expected[j]} = {vals[r, j]:g} {u} is outside its limits "
             f"[{lo[j] * s:.6g}, {hi[j] * s:.6g}] {u} (check '# angle_unit')", rows[r][0])
    return q


def read_joint_program(path, model) -> JointProgram:
    """Read a ``robocal-program/1`` file for ``model`` (a :class:`~robocal.kinematics.RobotModel`).

    Header ``# format:``, ``# robot:``, ``# angle_unit: deg|rad`` (required), ``# length_unit:
    mm|m`` (required only with prismatic joints), other ``# key: value`` lines are kept; then a
    column row: an optional ``point`` column (point names) and the controller joint columns (any
    order); one row per point. Values are checked against the joint limits (a unit mistake
    usually shows there). Returns joints (n, n_joints) [rad | mm] in the model's order.
    """
    path = Path(path)
    text = read_text(path, JointProgramFileError, what="program")

    def fail(msg, line=None):
        raise JointProgramFileError(path, msg, line)

    lines = text.splitlines()
    md, where, i = read_header_block(lines, fail)
    au, lu = _check_header(md, where, model, fail)
    if i >= len(lines):
        fail("no column header row after the '#' header block")
    cols = csv_cells(lines[i])
    jcols = _joint_columns(cols, i + 1, model, fail)
    rows = data_rows(lines, i + 1)
    check_field_counts(rows, len(cols), i + 1, fail)
    if not rows:
        fail("no program points (data rows)")
    names = _point_names(rows, cols[0] == "point", fail)
    vals = number_columns(rows, [cols.index(c) for c in jcols],
                          lambda problem, ln, j: fail(f"column {cols[j]!r}: {problem}", ln))
    vals = vals[:, [jcols.index(n) for n in model.controller_joints]]
    q = _internal_joints(vals, rows, names, au, lu, model, fail)
    md["angle_unit"] = au
    if lu:
        md["length_unit"] = lu
    return JointProgram(q, tuple(names), tuple(model.controller_joints), md)


# ---------------------------------------------------------------------------------------------- writing
def write_joint_program(path, program: JointProgram, model, *, overwrite: bool = False,
                        metadata: dict | None = None) -> Path:
    """Write ``program`` as ``robocal-program/1`` (atomically; an existing file only with
    ``overwrite``), in the units of ``program.metadata`` (default deg / mm), exact round trip."""
    md = dict(program.metadata)
    md.update({str(k): str(v) for k, v in (metadata or {}).items()})
    md["format"] = JOINT_PROGRAM_FORMAT
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
