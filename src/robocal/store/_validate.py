"""Input checks for the history store: robot ids, names, units, finite numbers, labels and
indices per row, JSON metadata, UTC times.

Every error is a :class:`HistoryInputError` (a ``ValueError``) whose message names the argument,
and where it helps the row and column, that was wrong.
"""

from __future__ import annotations
from ..errors import InputError

import json
import math
import re
import warnings
from datetime import datetime, timezone

import numpy as np

__all__ = [
    "ALLOWED_UNITS", "CYCLE_KINDS", "HistoryInputError", "check_kind", "check_name", "check_robot_id",
    "check_unit", "format_time", "parse_time", "utc_now",
]


class HistoryInputError(InputError):
    """A value handed to the history store is not acceptable (the message says which and why)."""


CYCLE_KINDS = ("geometric_calibration", "thermal_compensation", "tool_recalibration", "measurement")

#: Units a stored number may carry. Lengths are millimetres and angles radians, as everywhere inside
#: robocal; "1" is dimensionless (ratios such as the λ metric, counts, condition numbers).
ALLOWED_UNITS = {
    "mm": "length",
    "rad": "angle",
    "s": "time",
    "1": "dimensionless",
    "px": "image length",
    "degC": "temperature",
    "mm/s": "speed",
    "%": "percent",
}

#: Metrics with one fixed unit (one unit per quantity, issue 25): the name -> the unit it is stored in.
METRIC_UNITS = {"lambda": "%"}

# Units people are likely to pass, with the conversion the store wants instead.
_UNIT_HINTS = {
    "m": "multiply by 1000 and store in 'mm'",
    "cm": "multiply by 10 and store in 'mm'",
    "um": "divide by 1000 and store in 'mm'",
    "µm": "divide by 1000 and store in 'mm'",
    "micron": "divide by 1000 and store in 'mm'",
    "in": "multiply by 25.4 and store in 'mm'",
    "deg": "convert to radians and store in 'rad'",
    "°": "convert to radians and store in 'rad'",
    "degree": "convert to radians and store in 'rad'",
    "degrees": "convert to radians and store in 'rad'",
    "mrad": "divide by 1000 and store in 'rad'",
    "urad": "divide by 1e6 and store in 'rad'",
    "µrad": "divide by 1e6 and store in 'rad'",
    "arcsec": "convert to radians and store in 'rad'",
    "ms": "divide by 1000 and store in 's'",
    "min": "multiply by 60 and store in 's'",
    "h": "multiply by 3600 and store in 's'",
    "K": "store temperatures in 'degC'",
    "C": "write 'degC'",
    "°C": "write 'degC'",
}

_ROBOT_ID = re.compile(r"[A-Za-z0-9][A-Za-z0-9 _.:#/+\-]{0,99}")
_NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_.\[\]/:+\-]{0,99}")


def check_robot_id(robot) -> str:
    """A robot id: a string of 1-100 characters, letters/digits first, then letters, digits, space,
    ``_ . : # / + -``; no leading or trailing space."""
    if not isinstance(robot, str):
        raise HistoryInputError(f"robot id must be a string, got {type(robot).__name__} {robot!r}")
    if not robot:
        raise HistoryInputError("robot id is empty")
    if robot != robot.strip() or not _ROBOT_ID.fullmatch(robot) or any(s in (".", "..") for s in robot.split("/")):
        raise HistoryInputError(
            f"robot id {robot!r} is not valid: use 1-100 characters, starting with a letter or digit, "
            "then letters, digits, spaces or _ . : # / + - (no leading or trailing space, no '.' or '..' between "
            "slashes)")
    return robot


def check_name(name, what: str) -> str:
    """A parameter or metric name such as ``a2``, ``beta2``, ``base.rx``, ``residual_rms_after``."""
    if not isinstance(name, str):
        raise HistoryInputError(f"{what} name must be a string, got {type(name).__name__} {name!r}")
    if not _NAME.fullmatch(name):
        raise HistoryInputError(
            f"{what} name {name!r} is not valid: use 1-100 characters, a letter or _ first, then letters, "
            "digits or _ . [ ] / : + - (no spaces)")
    return name


def check_kind(kind) -> str:
    if kind not in CYCLE_KINDS:
        raise HistoryInputError(f"cycle kind {kind!r} is not known; valid: {', '.join(CYCLE_KINDS)}")
    return kind


def check_unit(unit, what: str) -> str:
    """One of :data:`ALLOWED_UNITS` (``""`` is read as ``"1"``); a near miss says how to convert."""
    if unit == "" or unit is None:
        return "1"
    if not isinstance(unit, str):
        raise HistoryInputError(f"{what}: unit must be a string, got {type(unit).__name__} {unit!r}")
    if unit in ALLOWED_UNITS:
        return unit
    hint = _UNIT_HINTS.get(unit) or _UNIT_HINTS.get(unit.lower())
    if hint:
        raise HistoryInputError(f"{what}: unit {unit!r} is not stored; {hint} (the history keeps mm and rad)")
    raise HistoryInputError(f"{what}: unknown unit {unit!r}; valid: {', '.join(ALLOWED_UNITS)}")


def check_number(x, what: str, *, allow_none: bool = False) -> float | None:
    """A finite real number (``bool`` is refused, numpy scalars are fine)."""
    if x is None and allow_none:
        return None
    if isinstance(x, (bool, np.bool_)) or not isinstance(x, (int, float, np.integer, np.floating)):
        raise HistoryInputError(f"{what} must be a finite number, got {type(x).__name__} {x!r}")
    v = float(x)
    if not math.isfinite(v):
        raise HistoryInputError(f"{what} must be a finite number, got {v!r}")
    return v


def check_array(a, what: str, *, ndim: int, width: int | None = None, columns=None) -> np.ndarray:
    """A finite float array with ``ndim`` dimensions (and ``width`` columns); errors name the row
    (0-based) and the column."""
    try:
        arr = np.asarray(a, dtype=float)
    except (TypeError, ValueError) as exc:
        raise HistoryInputError(f"{what} is not an array of numbers ({exc})") from None
    if ndim == 2 and arr.ndim == 1 and width is not None and arr.shape[0] == width:
        arr = arr[None, :]
    if arr.ndim != ndim:
        expect = "(N,)" if ndim == 1 else f"(N, {width if width is not None else 'n'})"
        raise HistoryInputError(f"{what} has shape {arr.shape}, expected {expect}")
    if width is not None and arr.shape[-1] != width:
        raise HistoryInputError(f"{what} has shape {arr.shape}, expected (N, {width})")
    bad = np.argwhere(~np.isfinite(arr))
    if bad.size:
        idx = tuple(int(i) for i in bad[0])
        where = f"row {idx[0]}"
        if len(idx) > 1:
            col = columns[idx[1]] if columns is not None else str(idx[1])
            where += f" column {col}"
        raise HistoryInputError(f"{what}: {where} is {float(arr[idx])!r}, expected a finite number")
    return arr


def check_joints(q, what: str, joint_units=None) -> tuple[np.ndarray, list[str]]:
    """Joint vectors ``(N, n)``: revolute in rad, prismatic in mm (``joint_units`` per joint,
    default all ``"rad"``). Revolute values beyond 4π rad look like degrees and are refused."""
    arr = check_array(q, what, ndim=2)
    n = arr.shape[1]
    if n == 0:
        raise HistoryInputError(f"{what} has no joint columns")
    units = ["rad"] * n if joint_units is None else list(joint_units)
    if len(units) != n:
        raise HistoryInputError(f"{what}: {len(units)} joint units for {n} joints")
    for j, u in enumerate(units):
        if u not in ("rad", "mm"):
            raise HistoryInputError(f"{what}: joint {j + 1} unit {u!r} is not stored; use 'rad' (revolute) or 'mm' (prismatic)")
    rev = np.array([u == "rad" for u in units])
    if rev.any():
        big = np.argwhere(np.abs(arr[:, rev]) > 4 * math.pi)
        if big.size:
            r, c = (int(i) for i in big[0])
            j = int(np.flatnonzero(rev)[c])
            raise HistoryInputError(
                f"{what}: row {r} joint {j + 1} = {arr[r, j]:.6g} rad is beyond 4π; degrees? (the history keeps radians)")
    return arr, units


def check_points_mm(p, what: str) -> np.ndarray:
    """Points ``(N, 3)`` in millimetres; a set whose every coordinate is below 10 looks like metres
    and gets a warning."""
    arr = check_array(p, what, ndim=2, width=3, columns="xyz")
    if arr.shape[0] >= 3 and float(np.max(np.abs(arr))) < 10.0:
        warnings.warn(f"{what}: every coordinate is below 10 mm; are these metres? (the history keeps millimetres)",
                      UserWarning, stacklevel=4)
    return arr


def check_labels(x, n: int, what: str) -> list:
    """``None``, one string for all rows, or one string (or None) per row."""
    if x is None or isinstance(x, str):
        out = [x] * n
    else:
        out = list(x)
        if len(out) != n:
            raise HistoryInputError(f"{what}: {len(out)} labels for {n} rows")
    for i, s in enumerate(out):
        if s is not None and (not isinstance(s, str) or len(s) > 255):
            raise HistoryInputError(f"{what} row {i}: expected a string of at most 255 characters, got {s!r}")
    return out


def check_indices(x, n: int, what: str) -> list:
    """``None`` (then 0..n-1) or ``n`` non-negative integers, as a list of ints."""
    if x is None:
        return list(range(n))
    arr = np.asarray(x)
    if arr.shape != (n,) or not (np.issubdtype(arr.dtype, np.integer) or arr.size == 0):
        raise HistoryInputError(f"{what} must be {n} integers, got {arr.dtype} array of shape {arr.shape}")
    if arr.size and arr.min() < 0:
        raise HistoryInputError(f"{what} row {int(np.argmin(arr))} is negative")
    return [int(v) for v in arr]


def to_json(obj, what: str) -> str:
    """``obj`` as sorted-key JSON text; finite numbers only."""
    try:
        return json.dumps(obj, allow_nan=False, sort_keys=True)
    except (TypeError, ValueError) as exc:
        raise HistoryInputError(f"{what} must be JSON data (numbers finite): {exc}") from None


def check_units_list(units, n: int, what: str) -> list:
    """One unit for all ``n`` values or one per value (required), as a list."""
    if units is None:
        raise HistoryInputError(f"{what}: units are required (mm, rad, ...)")
    if isinstance(units, str):
        units = [units] * n
    units = list(units)
    if len(units) != n:
        raise HistoryInputError(f"{what}: {len(units)} units for {n} values")
    return units


def utc_now() -> datetime:
    return datetime.now(timezone.utc)


def parse_time(t, what: str = "time") -> datetime:
    """A timezone-aware ``datetime``, an ISO 8601 string with an offset (or ``Z``), or a
    ``numpy.datetime64`` (read as UTC); naive datetimes are refused (their zone is unknown)."""
    if isinstance(t, np.datetime64):
        t = datetime.fromtimestamp(t.astype("datetime64[us]").astype(np.int64) / 1e6, tz=timezone.utc)
    if isinstance(t, str):
        s = t.strip()
        if s.endswith("Z"):
            s = s[:-1] + "+00:00"
        try:
            t = datetime.fromisoformat(s)
        except ValueError:
            raise HistoryInputError(f"{what} {t!r} is not an ISO 8601 time (e.g. 2024-05-01T12:00:00Z)") from None
    if not isinstance(t, datetime):
        raise HistoryInputError(f"{what} must be a datetime or an ISO 8601 string, got {type(t).__name__} {t!r}")
    if t.tzinfo is None or t.tzinfo.utcoffset(t) is None:
        raise HistoryInputError(f"{what} {t.isoformat()} has no time zone; give one (e.g. tzinfo=timezone.utc or a 'Z' suffix)")
    return t.astimezone(timezone.utc)


def format_time(t: datetime) -> str:
    """UTC ISO 8601 with microseconds and ``+00:00``: fixed width, so text order is time order."""
    return t.astimezone(timezone.utc).isoformat(timespec="microseconds")
