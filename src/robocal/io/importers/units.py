"""Length units of tracker exports: declared by the user, by the file, or detected from the spread.

A point cloud measured in a robot workspace spans roughly 100 mm to 10 m. Read in the wrong unit
it spans < 10 units (metres taken as millimetres) or > 100 000 units (millimetres taken as metres),
so the spread of the points tells the two apart, and every assumption is said out loud: as a note
returned with the data and as a :class:`UnitAssumptionWarning`.
"""

from __future__ import annotations
from ...errors import RobocalWarning

import re
import warnings

import numpy as np

from ..header import FileFormatError

__all__ = ["LENGTH_FACTORS", "UnitAssumptionWarning", "length_unit_from_text", "resolve_length_unit"]

#: File length unit -> millimetres per unit.
LENGTH_FACTORS = {"mm": 1.0, "m": 1000.0, "in": 25.4}
_WORDS = {
    "mm": "mm", "millimeter": "mm", "millimeters": "mm", "millimetre": "mm", "millimetres": "mm",
    "m": "m", "meter": "m", "meters": "m", "metre": "m", "metres": "m",
    "in": "in", "inch": "in", "inches": "in",
}
_UNITS_LINE = re.compile(r"\b(?:units?|einheit(?:en)?|unit[ée]s?)\b[^:=A-Za-z]*[:=]?\s*([A-Za-z]+)", re.I)

# Spread of a plausible robot-workspace point cloud [mm], and the band that is ambiguous.
_SPAN_MIN_MM = 10.0  # below: metres read as millimetres
_SPAN_MAX_MM = 1.0e5  # above (100 m): millimetres read as metres
_DETECT_M_BELOW = 10.0  # undeclared: a spread below 10 units is metres
_DETECT_MM_FROM = 100.0  # undeclared: a spread of 100 units or more is millimetres


class UnitAssumptionWarning(RobocalWarning):
    """An importer assumed a unit or found a declared unit implausible; the message says which."""


def length_unit_from_text(text: str) -> str | None:
    """``"mm"``, ``"m"`` or ``"in"`` for a unit word (``"Millimeters"``, ``"mm"``, ``"metre"``) or a
    units line (``"Units: Millimeters"``, ``"// Length units = m"``); ``None`` if none is named."""
    word = text.strip().lower()
    if word in _WORDS:
        return _WORDS[word]
    m = _UNITS_LINE.search(text)
    if m:
        return _WORDS.get(m.group(1).lower())
    return None


def _span(points: np.ndarray) -> float:
    """Largest extent of the points along x, y or z (file units)."""
    return float(np.max(np.ptp(points, axis=0))) if len(points) else 0.0


def _check_known(path, unit: str) -> str:
    if unit not in LENGTH_FACTORS:
        raise FileFormatError(path, f"unknown length unit {unit!r}; valid: {', '.join(LENGTH_FACTORS)}")
    return unit


def resolve_length_unit(path, points, user_unit: str | None = None, file_unit: str | None = None,
                        file_where: str = "the file") -> tuple[str, list[str]]:
    """The length unit of ``points`` (N, 3) [file units] and notes saying what was assumed.

    user_unit: unit the user declared (trusted; an implausible spread gives a note and a warning).
    file_unit: unit the file declares (``file_where`` names where); an implausible spread is a
        :class:`FileFormatError` (pass ``user_unit`` to override).
    Neither: a spread below 10 units is taken as metres, 100 units or more as millimetres (note +
    :class:`UnitAssumptionWarning`); in between, or a single point, is an error asking to declare.
    """
    points = np.asarray(points, dtype=float).reshape(-1, 3)
    span = _span(points)
    notes: list[str] = []
    warn = True
    if user_unit is not None:
        unit = _check_known(path, user_unit)
        span_mm = span * LENGTH_FACTORS[unit]
        if len(points) > 1 and not _SPAN_MIN_MM <= span_mm <= _SPAN_MAX_MM:
            notes.append(f"length unit {unit!r} as declared, although the points span {span_mm:.4g} mm "
                         "(a robot workspace spans 100 mm - 10 m): check the unit")
    elif file_unit is not None:
        unit = _check_known(path, file_unit)
        span_mm = span * LENGTH_FACTORS[unit]
        if len(points) > 1 and not _SPAN_MIN_MM <= span_mm <= _SPAN_MAX_MM:
            raise FileFormatError(path, f"{file_where} declares length unit {unit!r}, but then the points span "
                                        f"{span_mm:.4g} mm (a robot workspace spans 100 mm - 10 m); "
                                        "declare the unit explicitly (length_unit='mm' or 'm') if it is right")
        notes.append(f"length unit {unit!r} as declared in {file_where}")
        warn = False
    else:
        unit = _detect(path, span, len(points))
        notes.append(f"length unit not declared: assumed {'metres' if unit == 'm' else 'millimetres'} "
                     f"(the points span {span:.4g} units; a robot workspace spans 100 mm - 10 m, so metres "
                     f"span < {_DETECT_M_BELOW:g} units); declare length_unit to silence this")
    if warn and notes:
        warnings.warn(f"{path}: {notes[-1]}", UnitAssumptionWarning, stacklevel=3)
    return unit, notes


def _detect(path, span: float, n: int) -> str:
    if n < 2 or span == 0.0:
        raise FileFormatError(path, "cannot tell metres from millimetres with fewer than two distinct points; "
                                    "declare the length unit (length_unit='mm' or 'm')")
    if span < _DETECT_M_BELOW:
        return "m"
    if span >= _DETECT_MM_FROM:
        return "mm"
    raise FileFormatError(path, f"the points span {span:.4g} units: too small for millimetres of a robot "
                                "workspace (100 mm - 10 m) and too large for metres; declare the length unit "
                                "(length_unit='mm' or 'm')")
