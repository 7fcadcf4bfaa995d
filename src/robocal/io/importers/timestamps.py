"""Time stamps in tracker exports and controller logs, as seconds on one of three clocks.

- ``"seconds"``: a plain number (seconds, or milliseconds when the column says ``[ms]``),
- ``"datetime"``: a date and time, ISO 8601 (``2024-03-12 10:15:02.125``, ``T`` allowed, an
  offset such as ``+01:00`` or ``Z`` allowed), German (``12.03.2024 10:15:02,125``) or with
  slashes (``11/10/2022 3:06:48.043 PM``: day first, or month first with AM/PM or where the
  numbers say so, see :func:`slash_order`); without an offset both files are taken to be on the
  same clock (seconds since 1970 as if UTC),
- ``"clock"``: a time of day (``10:15:02.125``), seconds since midnight.

Only stamps on the same kind of clock can be compared (see :mod:`.pairing`). A leading apostrophe
(``'11.10.2022 15:06:48.043``, the text marker spreadsheet and Leica exports put in front of
stamps) and surrounding quotes are ignored.
"""

from __future__ import annotations

import re
from datetime import datetime, timezone

import numpy as np

from ..header import FileFormatError
from .text import parse_number

__all__ = ["TIME_COLUMNS", "TIME_KINDS", "parse_time", "slash_order", "time_cell", "time_column"]

TIME_KINDS = ("seconds", "datetime", "clock")
#: Accepted names (lower case, unit removed) of a time-stamp column.
TIME_COLUMNS = ("time", "timestamp", "time stamp", "date/time", "datetime", "date time", "zeit", "zeitstempel")
_FRACTION = r"(?:[.,]\d+)?"
_ISO = re.compile(rf"^\d{{4}}-\d{{2}}-\d{{2}}[T ]\d{{2}}:\d{{2}}(?::\d{{2}}{_FRACTION})?(?:Z|[+-]\d{{2}}:?\d{{2}})?$")
_GERMAN = re.compile(rf"^(\d{{1,2}})\.(\d{{1,2}})\.(\d{{4}})[ T]+(\d{{1,2}}:\d{{2}}(?::\d{{2}}{_FRACTION})?)$")
_SLASH = re.compile(rf"^(\d{{1,2}})/(\d{{1,2}})/(\d{{4}})[ T]+(\d{{1,2}}:\d{{2}}(?::\d{{2}}{_FRACTION})?)"
                    r"\s*([AaPp][Mm])?$")
_CLOCK = re.compile(rf"^(\d{{1,2}}):(\d{{2}})(?::(\d{{2}}{_FRACTION}))?$")
_TIME_UNITS = {None: 1.0, "s": 1.0, "sec": 1.0, "ms": 1.0e-3}


def _datetime_seconds(dt: datetime) -> float:
    if dt.tzinfo is None:
        dt = dt.replace(tzinfo=timezone.utc)
    return dt.timestamp()


def _stamp_text(cell: str) -> str:
    """The cell without surrounding blanks, quotes and a leading text-marker apostrophe."""
    text = cell.strip()
    if len(text) > 1 and text[0] == text[-1] and text[0] in "\"'":
        text = text[1:-1].strip()
    return text.lstrip("'").strip()


def slash_order(cells) -> str:
    """``"dmy"`` or ``"mdy"``: the field order of the slash dates among ``cells`` (a column): month
    first when a second field exceeds 12 or the stamps carry AM/PM (US style) and no first field
    exceeds 12; day first otherwise."""
    first = second = 0
    ampm = False
    for cell in cells:
        m = _SLASH.match(_stamp_text(cell))
        if m:
            first, second = max(first, int(m.group(1))), max(second, int(m.group(2)))
            ampm = ampm or bool(m.group(5))
    if first > 12:
        return "dmy"
    return "mdy" if second > 12 or ampm else "dmy"


def _slash_seconds(m, order: str) -> float:
    a, b, year, clock, ampm = m.groups()
    day, month = (a, b) if order == "dmy" else (b, a)
    clock = clock.replace(",", ".")
    h, rest = clock.split(":", 1)
    h = int(h)
    if ampm:
        if not 1 <= h <= 12:
            raise ValueError("hour out of range for AM/PM")
        h = h % 12 + (12 if ampm.lower() == "pm" else 0)
    iso = f"{year}-{int(month):02d}-{int(day):02d}T{h:02d}:{rest}"
    return _datetime_seconds(datetime.fromisoformat(iso))


def parse_time(cell: str, decimal: str = ".", unit: str | None = None,
               slash: str = "dmy") -> tuple[float, str] | None:
    """``(seconds, kind)`` for a time stamp cell, or ``None`` if it is not one.

    unit: the column's unit for plain numbers (``None``/``"s"`` seconds, ``"ms"`` milliseconds).
    slash: field order of slash dates, ``"dmy"`` or ``"mdy"`` (a column's :func:`slash_order`).
    """
    text = _stamp_text(cell)
    number = parse_number(text, decimal)
    if number is not None:
        return number * _TIME_UNITS.get(unit, 1.0), "seconds"
    try:
        if _ISO.match(text):
            return _datetime_seconds(datetime.fromisoformat(text.replace(",", "."))), "datetime"
        m = _GERMAN.match(text)
        if m:
            day, month, year, clock = m.groups()
            clock = clock.replace(",", ".").zfill(len(clock) + (clock.index(":") == 1))
            iso = f"{year}-{int(month):02d}-{int(day):02d}T{clock}"
            return _datetime_seconds(datetime.fromisoformat(iso)), "datetime"
        m = _SLASH.match(text)
        if m:
            return _slash_seconds(m, slash), "datetime"
    except ValueError:  # e.g. month 13
        return None
    m = _CLOCK.match(text)
    if m:
        h, mi, s = int(m.group(1)), int(m.group(2)), float((m.group(3) or "0").replace(",", "."))
        if h < 24 and mi < 60 and s < 61:
            return h * 3600.0 + mi * 60.0 + s, "clock"
    return None


def time_cell(cell: str, decimal: str, unit: str | None, path, line: int, column: str,
              slash: str = "dmy") -> tuple[float, str]:
    """:func:`parse_time` or a :class:`FileFormatError` saying which forms are understood."""
    if unit is not None and unit not in _TIME_UNITS:
        raise FileFormatError(path, f"unknown time unit {unit!r}; valid: s, ms", line, column)
    parsed = parse_time(cell, decimal, unit, slash)
    if parsed is None:
        what = "empty cell" if not cell.strip() else f"{cell!r} is not a time stamp"
        raise FileFormatError(path, f"{what}; expected seconds (12.5), a date and time "
                                    "(2024-03-12 10:15:02.125, 12.03.2024 10:15:02 or 03/12/2024 10:15:02 AM) or a time of day "
                                    "(10:15:02.125)", line, column)
    return parsed


def time_column(table, index: int | None):
    """``(times, kind)`` of column ``index`` of a :class:`~.table.Table` ((N,) [s], one clock), or
    ``(None, None)`` when ``index`` is ``None``."""
    if index is None:
        return None, None
    column, unit = table.columns[index], table.units[index]
    slash = slash_order(row[index] for row in table.rows)
    stamps = [time_cell(row[index], table.decimal, unit, table.path, ln, column, slash)
              for row, ln in zip(table.rows, table.lines)]
    kinds = sorted({k for _, k in stamps})
    if len(kinds) > 1:
        raise FileFormatError(table.path, f"time stamps of different kinds {kinds} in one column", None, column)
    return np.array([s for s, _ in stamps]), kinds[0]
