"""Generic laser-tracker CSV exports (Leica, FARO, API and similar software).

A header row names the columns (found case-insensitively, units in brackets allowed), e.g.::

    Name;X [mm];Y [mm];Z [mm];Time
    P1;1523,412;-402,118;987,004;2024-03-12 10:15:02

Comma, semicolon, tab or whitespace separated; decimal point or decimal comma; UTF-8 or Latin-1.
Orientation columns of a 6-DoF probe (``Rx, Ry, Rz`` with a declared convention, or quaternions
``Q0..Q3`` / ``qw..qz``) are read (:mod:`.orientation`); angles without a declared convention are
dropped with a note saying so. Other columns are ignored. Lengths are in
the unit the user declares, else the unit in the header or a units line above it, else the one the
spread of the points makes plausible (a note and a warning say which; see :mod:`.units`).
"""

from __future__ import annotations

import numpy as np

from .points import TrackerPoints
from .table import read_table
from .orientation import find_orientation_columns, rotations_from_values
from .text import number_cell
from .timestamps import TIME_COLUMNS, time_column
from .units import LENGTH_FACTORS, length_unit_from_text, resolve_length_unit

__all__ = ["read_tracker_csv", "NAME_COLUMNS"]

#: Accepted names (lower case) of the point-name column.
NAME_COLUMNS = ("name", "point", "point name", "pointname", "point id", "id", "label", "target", "punkt", "nr")
_AXES = ("x", "y", "z")


def _axis_index(names) -> list[int] | None:
    found = []
    for axis in _AXES:
        hits = [i for i, n in enumerate(names) if n in (axis, f"pos {axis}", f"{axis} coordinate", f"{axis}-coord")]
        if not hits:
            return None
        found.append(hits[0])
    return found


def read_tracker_csv(path, *, length_unit: str | None = None, delimiter: str | None = "auto",
                     decimal: str | None = None, encoding: str | None = None, orientation: str | None = None,
                     orientation_unit: str | None = None) -> TrackerPoints:
    """Read a tracker CSV export; points come back in mm.

    length_unit: ``"mm"``, ``"m"`` or ``"in"`` as the user knows it; ``None`` takes the header's
        (``X [m]``) or a preamble units line (``Units: Millimeters``), else detects it from the
        spread of the points and says so (``notes``, :class:`~.units.UnitAssumptionWarning`).
    delimiter, decimal, encoding: ``"auto"``/``None`` detect them (see :func:`~.table.read_table`).
    orientation: convention of three orientation-angle columns (a name of
        :data:`~robocal.transforms.POSE_CONVENTIONS`); quaternion columns need none.
    orientation_unit: ``"deg"``/``"rad"`` of those angles when the header does not name it.

    Raises :class:`~robocal.io.header.FileFormatError` naming file, line and column.
    """
    table = read_table(path, lambda names: _axis_index(names) is not None, "e.g. 'Name;X;Y;Z' or "
                       "'Point,X [mm],Y [mm],Z [mm]'", delimiter=delimiter, decimal=decimal, encoding=encoding)
    axes = _axis_index(table.names)
    name_i, time_i = table.index(NAME_COLUMNS), table.index(TIME_COLUMNS)
    points = np.array([[number_cell(row[j], table.decimal, path, ln, table.columns[j]) for j in axes]
                       for row, ln in zip(table.rows, table.lines)])
    ids = tuple(row[name_i] if name_i is not None else str(k + 1) for k, row in enumerate(table.rows))
    for pid, ln in zip(ids, table.lines):
        if not pid:
            table.fail("empty point name", ln, table.columns[name_i])
    times, kind = time_column(table, time_i)

    file_unit, where = _declared_unit(table, axes)
    unit, notes = resolve_length_unit(path, points, length_unit, file_unit, where)
    notes = list(notes)
    if table.encoding != "utf-8":
        notes.append(f"decoded as {table.encoding}")
    if name_i is None:
        notes.append("no point-name column: points numbered 1 .. N in file order")
    R, conv = _orientations(table, path, orientation, orientation_unit, notes)
    return TrackerPoints(ids=ids, points=points * LENGTH_FACTORS[unit], lines=table.lines, path=str(path),
                         times=times, time_kind=kind, length_unit=unit, notes=tuple(notes), rotations=R,
                         orientation=conv)


def _orientations(table, path, orientation, orientation_unit, notes):
    """(rotations (N, 3, 3) or None, convention or None) of the table's orientation columns."""
    cols, kind = find_orientation_columns(table.names)
    if cols is None:
        if orientation is not None:
            table.fail(f"--orientation {orientation} given, but no orientation columns (Rx, Ry, Rz or Q0..Q3 / "
                       f"qw..qz) in the header; columns: {', '.join(table.columns)}", table.header_line)
        return None, None
    values = np.array([[number_cell(row[j], table.decimal, path, ln, table.columns[j]) for j in cols]
                       for row, ln in zip(table.rows, table.lines)])
    units = {table.units[j] for j in cols} - {None}
    if len(units) > 1:
        table.fail(f"orientation columns declare different units {sorted(units)}", table.header_line)
    where = "(" + ", ".join(table.columns[j] for j in cols) + ")"
    R, conv, more = rotations_from_values(path, values, kind, orientation, header_unit=units.pop() if units else None,
                                          angle_unit=orientation_unit, where=where, lines=table.lines)
    notes.extend(more)
    return R, conv


def _declared_unit(table, axes) -> tuple[str | None, str]:
    """The unit the file declares (header brackets or a units line above the header) and where."""
    units = {table.units[j] for j in axes}
    if units != {None}:
        if len(units) != 1:
            table.fail(f"X, Y, Z columns declare different units {sorted(map(str, units))}", table.header_line)
        unit = length_unit_from_text(units.pop() or "")
        if unit is None:
            table.fail(f"unknown length unit in {table.columns[axes[0]]!r}; valid: mm, m, in", table.header_line,
                       table.columns[axes[0]])
        return unit, f"the header (line {table.header_line})"
    for line, text in table.preamble:
        unit = length_unit_from_text(text)
        if unit is not None:
            return unit, f"the units line (line {line})"
    return None, "the file"
