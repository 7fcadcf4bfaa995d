"""Controller joint logs: one row per pose with an id or a time stamp and the joint values.

A CSV file (any delimiter, decimal point or comma, see :mod:`.table`) with a header row such as::

    Pose;Time;A1 [deg];A2 [deg];A3 [deg];A4 [deg];A5 [deg];A6 [deg]

Joint columns are recognized by name (``A1``, ``J1``, ``joint_1``, ``axis 1``, ``q1``, any case;
the controllers' own log names: Universal Robots RTDE ``actual_q_0 .. actual_q_5`` (radians,
numbered from 0), KUKA ``$AXIS_ACT.A1`` / ``AxisAct_A1`` / ``AIPos_A1`` (RSI), ABB
``rob1_j1`` / ``Rob1 Joint 1``) or given explicitly (``joint_columns=``, ``--joint-columns``). The angle unit is never guessed: it is declared by the caller or in the
header (``[deg]``, ``[rad]``); a column in ``[mm]`` (or listed in ``prismatic``) is a linear axis.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

import numpy as np

from ...transforms import ANGLE_UNITS
from ..header import FileFormatError
from .table import read_table
from .text import number_cell, split_name_unit
from .timestamps import TIME_COLUMNS, time_column
from .units import LENGTH_FACTORS

__all__ = ["JointLog", "read_joint_log", "ID_COLUMNS"]

#: Accepted names (lower case) of the pose-id column.
ID_COLUMNS = ("id", "pose", "pose id", "point", "point id", "name", "nr", "no", "index", "#", "step", "punkt")
_JOINT_NAME = re.compile(r"^(?:a|j|joint|axis|axle|achse|q)\s*[_ ]?\s*(\d{1,2})$")
#: Controllers' own joint column names (lower case): (pattern, angle unit the controller always logs in or None).
_VENDOR_JOINT_NAMES = (
    (re.compile(r"^actual_q_(\d)$"), "rad"),  # Universal Robots RTDE
    (re.compile(r"^\$?(?:axis_act|axisact|axis_act_meas)[._ ]?a(\d)$"), None),  # KUKA system variable / trace
    (re.compile(r"^(?:aipos|ai_pos|ripos)[._ ]?a(\d)$"), None),  # KUKA RSI
    (re.compile(r"^rob\d?[._ ]?(?:j|joint|axis)[._ ]?(\d)$"), None),  # ABB
)
_ANGLE_WORDS = {"deg": "deg", "°": "deg", "degree": "deg", "degrees": "deg", "rad": "rad", "radian": "rad",
                "radians": "rad"}
_RAD_LOOKS_LIKE_DEG = 4.0 * math.pi  # a revolute joint beyond two turns in rad: the numbers are degrees


@dataclass(frozen=True, eq=False)
class JointLog:
    """Joint values the controller logged.

    joints: (N, n) [rad; mm for linear axes], columns ``joint_names``. prismatic: (n,) bool.
    ids: N pose ids (``"1" .. "N"`` when the file has no id column). times: (N,) [s] or ``None``
    on the clock ``time_kind``. lines: N 1-based line numbers. angle_unit: the file's unit.
    """

    joints: np.ndarray
    joint_names: tuple
    ids: tuple
    lines: tuple
    path: str
    prismatic: np.ndarray
    times: np.ndarray | None = None
    time_kind: str | None = None
    angle_unit: str = "deg"
    notes: tuple = ()

    def __len__(self) -> int:
        return len(self.joints)


def _is_joint_name(name: str) -> bool:
    return bool(_JOINT_NAME.match(name)) or any(p.match(name) for p, _ in _VENDOR_JOINT_NAMES)


def _vendor_columns(names) -> tuple[list[int], str | None]:
    """Columns of the first controller naming scheme that matches (in joint-number order) and
    the angle unit that controller logs in (``None``: not fixed)."""
    for pattern, unit in _VENDOR_JOINT_NAMES:
        hits = [(int(m.group(1)), i) for i, n in enumerate(names) if (m := pattern.match(n))]
        if hits:
            return [i for _, i in sorted(hits)], unit
    return [], None


def _joint_columns(table, joint_columns) -> tuple[list[int], str | None]:
    """Indices of the joint columns and the unit their naming scheme implies (or ``None``)."""
    if joint_columns is None:
        found = [i for i, n in enumerate(table.names) if _JOINT_NAME.match(n)]
        if found:
            return found, None
        found, unit = _vendor_columns(table.names)
        if not found:
            table.fail("no joint columns (A1 .., J1 .., joint_1 .., actual_q_0 ..); name them with --joint-columns "
                       f"(columns: {', '.join(table.columns)})", table.header_line)
        return found, unit
    index = []
    for name in joint_columns:
        key = split_name_unit(name)[0]
        hits = [i for i, n in enumerate(table.names) if n == key]
        if not hits:
            table.fail(f"no column {name!r} (columns: {', '.join(table.columns)})", table.header_line)
        index.append(hits[0])
    return index, None


def _angle_unit(table, cols, linear, declared, scheme_unit=None) -> str:
    header = {table.units[j] for j, lin in zip(cols, linear) if not lin and table.units[j] is not None}
    words = {_ANGLE_WORDS.get(u) for u in header}
    if None in words or len(words) > 1:
        table.fail(f"joint columns declare units {sorted(header)}; expected one of deg, rad", table.header_line)
    from_header = words.pop() if words else scheme_unit
    if declared is not None:
        if declared not in ANGLE_UNITS:
            raise ValueError(f"angle_unit: expected one of {', '.join(ANGLE_UNITS)}, got {declared!r}")
        if from_header is not None and from_header != declared:
            table.fail(f"angle_unit={declared!r} given, but the header says {from_header!r}", table.header_line)
        return declared
    if from_header is None:
        table.fail("the angle unit of the joint columns is not declared: pass angle_unit='deg' or 'rad' "
                   "(or name it in the header, e.g. 'A1 [deg]')", table.header_line)
    return from_header


def read_joint_log(path, *, angle_unit: str | None = None, joint_columns=None, prismatic=(),
                   delimiter: str | None = "auto", decimal: str | None = None,
                   encoding: str | None = None) -> JointLog:
    """Read a controller joint log; joints come back in rad (mm for linear axes).

    angle_unit: ``"deg"`` or ``"rad"``; required unless the header names it (``A1 [deg]``).
    joint_columns: header names of the joint columns in order (default: recognized by name).
    prismatic: names of linear-axis columns (values in mm); a ``[mm]`` column is linear anyway.

    Raises :class:`~robocal.io.header.FileFormatError` naming file, line and column.
    """
    wanted = None if joint_columns is None else {split_name_unit(c)[0] for c in joint_columns}

    def is_header(names):
        return any(wanted is None and _is_joint_name(n) or wanted and n in wanted for n in names)

    table = read_table(path, is_header, "e.g. 'Pose;A1 [deg];A2 [deg];...' or UR RTDE's 'timestamp actual_q_0 ...'; "
                       "name other joint columns with --joint-columns", delimiter=delimiter,
                       decimal=decimal, encoding=encoding)
    cols, scheme_unit = _joint_columns(table, joint_columns)
    lin_names = {p.lower() for p in prismatic}
    linear = [table.units[j] in ("mm", "m") or table.names[j] in lin_names or table.columns[j].lower() in lin_names
              for j in cols]
    unit = _angle_unit(table, cols, linear, angle_unit, scheme_unit)
    raw = np.array([[number_cell(row[j], table.decimal, path, ln, table.columns[j]) for j in cols]
                    for row, ln in zip(table.rows, table.lines)])
    scale = np.array([LENGTH_FACTORS[table.units[j] or "mm"] if lin else ANGLE_UNITS[unit]
                      for j, lin in zip(cols, linear)])
    if unit == "rad":
        big = np.abs(raw) > _RAD_LOOKS_LIKE_DEG
        big[:, linear] = False
        if big.any():
            r, c = np.argwhere(big)[0]
            raise FileFormatError(path, f"joint value {raw[r, c]:g} rad is more than two turns: the values look "
                                        "like degrees; declare angle_unit='deg'", table.lines[r], table.columns[cols[c]])
    id_i, time_i = table.index(ID_COLUMNS), table.index(TIME_COLUMNS)
    ids = tuple(row[id_i] if id_i is not None else str(k + 1) for k, row in enumerate(table.rows))
    times, kind = time_column(table, time_i)
    notes = [f"decoded as {table.encoding}"] if table.encoding != "utf-8" else []
    names = tuple(split_name_unit(table.columns[j], lower=False)[0] for j in cols)
    return JointLog(joints=raw * scale, joint_names=names, ids=ids, lines=table.lines, path=str(path),
                    prismatic=np.array(linear), times=times, time_kind=kind, angle_unit=unit, notes=tuple(notes))
