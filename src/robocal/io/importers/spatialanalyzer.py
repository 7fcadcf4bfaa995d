"""SpatialAnalyzer (SA) text exports of points ("Export ASCII": name parts, then X Y Z).

Each data line is up to three name fields (collection, group, point, as chosen in SA's export
dialog) followed by X, Y, Z, separated by tabs, runs of spaces or commas::

    // SA Version 2023.1
    // Working frame: A::TrackerFrame
    // Units: Millimeters
    A	Robot	P001	1523.4120	-402.1180	987.0040

Lines starting with ``//`` or ``#`` are comments; a comment naming units (``Units: Millimeters``)
declares the length unit. A header line ending in ``X Y Z`` is skipped. Extra exported fields after
Z (tolerances, uncertainties, time stamps) need ``name_fields=`` (``--name-fields``) so the columns
can be told apart. Frames (6-DoF) exported as name fields, X Y Z and three angles (or a quaternion)
are read with ``orientation=`` naming the convention the export used (``--orientation``; SA's
"Fixed XYZ" angles are ``rpy``).
"""

from __future__ import annotations

import numpy as np

from ..header import FileFormatError
from .points import TrackerPoints
from .orientation import check_orientation_convention, rotations_from_values
from .text import decode_file, detect_decimal, number_cell, parse_number
from .units import LENGTH_FACTORS, length_unit_from_text, resolve_length_unit

__all__ = ["read_spatialanalyzer"]

_COMMENTS = ("//", "#")
_XYZ = ("X", "Y", "Z")


def _split(line: str) -> list[str]:
    """Tab-separated, comma-separated (when the last three comma fields are numbers) or whitespace."""
    if "\t" in line:
        return [f.strip() for f in line.split("\t") if f.strip()]
    by_comma = [f.strip() for f in line.split(",")]
    if len(by_comma) >= 3 and all(parse_number(f) is not None for f in by_comma[-3:]):
        return by_comma
    return line.split()


def _read_lines(path, encoding):
    """Comment lines and data lines ``(line number, fields)`` of the export."""
    text, used = decode_file(path, encoding)
    comments, data = [], []
    for k, raw in enumerate(text.splitlines()):
        stripped = raw.strip()
        if not stripped:
            continue
        if stripped.startswith(_COMMENTS):
            comments.append((k + 1, stripped.lstrip("/#").strip()))
            continue
        fields = _split(stripped)
        if [f.upper() for f in fields[-3:]] == list(_XYZ):
            continue  # a header line
        data.append((k + 1, fields))
    return comments, data, used


def _name_field_count(path, data, name_fields: int | None, n_values: int = 3) -> int:
    if name_fields is not None:
        if not 0 <= name_fields <= 3:
            raise ValueError(f"name_fields: expected 0 .. 3 (collection, group, point), got {name_fields}")
        return name_fields
    counts = {len(f) for _, f in data}
    if len(counts) != 1:
        line = next(ln for ln, f in data if len(f) != len(data[0][1]))
        raise FileFormatError(path, f"{len(dict(data)[line])} fields, but line {data[0][0]} has "
                                    f"{len(data[0][1])}; expected the same name fields and X Y Z on every line "
                                    "(pass name_fields= if the export has extra columns)", line)
    k = counts.pop() - n_values
    if not 0 <= k <= 3:
        raise FileFormatError(path, f"{k + n_values} fields per line; expected up to 3 name fields (collection, "
                                    f"group, point) and {n_values} values (X Y Z{' and the orientation' if n_values > 3 else ''}); "
                                    "pass --name-fields if the export has extra columns",
                              data[0][0])
    return k


def read_spatialanalyzer(path, *, length_unit: str | None = None, name_fields: int | None = None,
                         encoding: str | None = None, orientation: str | None = None,
                         orientation_unit: str | None = None) -> TrackerPoints:
    """Read an SA point export; points come back in mm in SA's working frame.

    length_unit: ``"mm"``, ``"m"`` or ``"in"``; ``None`` takes a units comment line, else detects
        the unit from the spread of the points and says so (``notes`` and a warning).
    name_fields: number of name fields before X Y Z (0 .. 3); ``None`` infers it from a constant
        field count (fields - 3). ids are the point names, groups ``collection::group``.
    orientation: convention of the angles (or ``quaternion``) exported after X Y Z (SA frames);
        orientation_unit: their unit (deg | rad) unless the values show degrees.

    Raises :class:`~robocal.io.header.FileFormatError` naming file, line and column.
    """
    comments, data, used = _read_lines(path, encoding)
    if not data:
        raise FileFormatError(path, "no data lines; expected '[collection] [group] point X Y Z' per line")
    conv = check_orientation_convention(orientation)
    n_rot = 0 if conv is None else (4 if conv == "quaternion" else 3)
    k = _name_field_count(path, data, name_fields, 3 + n_rot)
    decimal = detect_decimal((c for _, f in data for c in f[k:k + 3]), None)
    ids, groups, rows, lines, rot = [], [], [], [], []
    for ln, fields in data:
        if len(fields) < k + 3 + n_rot:
            raise FileFormatError(path, f"{len(fields)} fields; expected {k} name field(s), X Y Z"
                                        + (" and the orientation" if n_rot else ""), ln)
        rows.append([number_cell(fields[k + j], decimal, path, ln, _XYZ[j]) for j in range(3)])
        rot.append([number_cell(fields[k + 3 + j], decimal, path, ln, f"orientation {j + 1}") for j in range(n_rot)])
        ids.append(fields[k - 1] if k else str(len(ids) + 1))
        groups.append("::".join(fields[:k - 1]) if k > 1 else "")
        lines.append(ln)
    points = np.array(rows)
    file_unit = where = None
    for line, text in comments:
        if length_unit_from_text(text):
            file_unit, where = length_unit_from_text(text), f"the units line (line {line})"
            break
    unit, notes = resolve_length_unit(path, points, length_unit, file_unit, where or "the file")
    notes = list(notes) + ([f"decoded as {used}"] if used != "utf-8" else [])
    R = None
    if n_rot:
        R, conv, more = rotations_from_values(path, np.array(rot), "quaternion" if n_rot == 4 else "euler", conv,
                                              angle_unit=orientation_unit, where="(the fields after X Y Z)",
                                              lines=lines)
        notes += more
    elif len(data[0][1]) > k + 3:
        notes.append(f"{len(data[0][1]) - k - 3} field(s) after X Y Z ignored (frames: pass --orientation to read "
                     "their angles)")
    return TrackerPoints(ids=tuple(ids), points=points * LENGTH_FACTORS[unit], lines=tuple(lines), path=str(path),
                         groups=tuple(groups) if k > 1 else None, length_unit=unit, notes=tuple(notes),
                         rotations=R, orientation=conv)
