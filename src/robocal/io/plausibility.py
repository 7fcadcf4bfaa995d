"""Do the numbers of a file fit the units it declares? One checker, one wording, for every reader.

A file that declares ``length_unit: mm`` but holds metres (or the reverse), or ``angle_unit: deg``
with radians in it (or the reverse), gives plausible-looking but wrong results. The checks here
look at the magnitudes after conversion to millimetres / radians:

=====================  ==========================================================================
declared               implausible when
=====================  ==========================================================================
lengths in mm          the largest magnitude is below ``smallest_mm`` (points: 10 mm; a robot's
                       reach: 50 mm): the numbers are metres
lengths in m           the largest magnitude is above ``largest_mm`` (points: 1 km; a robot's
                       reach: 100 m): the numbers are millimetres
angles in rad          a magnitude above two turns (4 pi): the numbers are degrees
angles in deg          at least ``min_rows`` rows (poses), not all zero, every value within one
                       turn in radians (|v| <= 6.28 deg): the numbers are radians
=====================  ==========================================================================

Each check returns ``None`` or the message (one wording); the reader raises it with its file,
line and column (:class:`~robocal.io.header.FileFormatError`).
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["POINT_SMALLEST_MM", "POINT_LARGEST_MM", "REACH_SMALLEST_MM", "REACH_LARGEST_MM", "TWO_TURNS_RAD",
           "length_unit_problem", "angle_unit_problem", "unit_hint"]

POINT_SMALLEST_MM = 10.0
POINT_LARGEST_MM = 1.0e6
REACH_SMALLEST_MM = 50.0
REACH_LARGEST_MM = 1.0e5
TWO_TURNS_RAD = 4.0 * math.pi
_UNIT_NAMES = {"mm": "millimetres", "m": "metres", "deg": "degrees", "rad": "radians"}


def _largest_magnitude(values) -> float | None:
    """max |values| ignoring NaN, without copying a large array; ``None`` when there is none."""
    v = np.asarray(values, dtype=float)
    if v.size == 0:
        return None
    with np.errstate(invalid="ignore"):
        largest = max(float(np.nanmax(v)), -float(np.nanmin(v))) if not np.isnan(v).all() else None
    return largest


def unit_hint(key: str, unit: str, style: str = "header") -> str:
    """How to declare ``unit``: ``'# length_unit: m'`` (header files) or ``length_unit = "m"`` (TOML)."""
    return f"'# {key}: {unit}'" if style == "header" else f'{key} = "{unit}"'


def _message(what: str, evidence: str, other: str, declared: str, key: str, style: str) -> str:
    return (f"{what}: {evidence}: the numbers look like {_UNIT_NAMES[other]}, not the declared {declared}; "
            f"declare {unit_hint(key, other, style)} or convert them")


def length_unit_problem(values_mm, declared: str, *, what: str = "points", smallest_mm: float = POINT_SMALLEST_MM,
                        largest_mm: float = POINT_LARGEST_MM, key: str = "length_unit",
                        style: str = "header") -> str | None:
    """``values_mm``: lengths or distances already converted to mm (any shape); ``declared``:
    ``"mm"`` or ``"m"``. Returns the problem or ``None``."""
    largest = _largest_magnitude(values_mm)
    if largest is None:
        return None
    if declared == "mm" and largest < smallest_mm:
        return _message(what, f"the largest is {largest:.4g} mm (below {smallest_mm:g} mm)", "m", declared, key, style)
    if declared == "m" and largest > largest_mm:
        return _message(what, f"the largest is {largest / 1000.0:.4g} m (above {largest_mm / 1000.0:g} m)", "mm",
                        declared, key, style)
    return None


def angle_unit_problem(values_rad, declared: str, *, what: str = "angles", min_rows: int = 5,
                       key: str = "angle_unit", style: str = "header") -> str | None:
    """``values_rad``: revolute angles already converted to rad, (rows,) or (rows, columns);
    ``declared``: ``"deg"`` or ``"rad"``. Returns the problem or ``None``."""
    v = np.asarray(values_rad, dtype=float)
    n_rows = v.shape[0] if v.ndim else 1
    largest = _largest_magnitude(v)
    if largest is None:
        return None
    if declared == "rad" and largest > TWO_TURNS_RAD:
        return _message(what, f"a value of {largest:.4g} rad is more than two turns", "deg", declared, key, style)
    one_turn_in_deg = math.radians(2.0 * math.pi)
    if declared == "deg" and n_rows >= min_rows and 0.0 < largest <= one_turn_in_deg:
        return _message(what, f"all {v.size} values are within +-{2.0 * math.pi:.2f} deg (largest "
                        f"{math.degrees(largest):.4g} deg)", "rad", declared, key, style)
    return None
