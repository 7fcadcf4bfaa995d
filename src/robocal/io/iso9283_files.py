"""ISO 9283 measurement files (``robocal-iso9283-measurements/1``).

A CSV with a header of ``# key: value`` lines and one row per measured point::

    # format: robocal-iso9283-measurements/1
    # frame: base
    # length_unit: mm
    # orientation: rotvec_deg
    id,time_s,x,y,z,a,b,c
    pose.c01.P1,3.0,1203.1511,0.0114,1101.9983,180.0012,0.0004,-0.0021

``id`` names the plan's measurement (``protocol.json``); a continuously measured path repeats its
id on every sample, in time order. ``x, y, z`` are the measured position in the robot's base frame
(the instrument registered to it), in ``length_unit`` (mm or m). ``a, b, c`` are optional: the
attained orientation as a rotation vector in degrees (``orientation: rotvec_deg``).
"""

from __future__ import annotations

import csv
import io
import math
from pathlib import Path

import numpy as np

from .atomic import atomic_write_text
from .header import FileFormatError

__all__ = ["ISO_MEASUREMENT_FORMAT", "IsoMeasurements", "read_iso_measurements", "write_iso_measurements"]

ISO_MEASUREMENT_FORMAT = "robocal-iso9283-measurements/1"
_LENGTH = {"mm": 1.0, "m": 1000.0}
_MAX_ROWS = 5_000_000


class IsoMeasurements:
    """Measured points grouped by measurement id.

    Attributes
    ----------
    positions : dict[str, ndarray (k, 3)]
        Positions [mm] per id, in file order.
    rotations : dict[str, ndarray (k, 3, 3)] or None
    times : dict[str, ndarray (k,)]
        Time stamps [s].
    path : Path
    """

    def __init__(self, positions, rotations, times, path):
        self.positions, self.rotations, self.times, self.path = positions, rotations, times, Path(path)


def write_iso_measurements(path, rows, *, overwrite: bool = False) -> Path:
    """Write rows (dicts with id, time_s, x, y, z and optionally a, b, c) [mm, deg]."""
    has_rot = all("a" in r for r in rows)
    buf = io.StringIO()
    buf.write(f"# format: {ISO_MEASUREMENT_FORMAT}\n# frame: base\n# length_unit: mm\n")
    if has_rot:
        buf.write("# orientation: rotvec_deg\n")
    cols = ["id", "time_s", "x", "y", "z"] + (["a", "b", "c"] if has_rot else [])
    buf.write(",".join(cols) + "\n")
    for r in rows:
        vals = [r["id"], f"{r['time_s']:.4f}"] + [f"{r[k]:.5f}" for k in ("x", "y", "z")]
        if has_rot:
            vals += [f"{r[k]:.6f}" for k in ("a", "b", "c")]
        buf.write(",".join(vals) + "\n")
    return atomic_write_text(path, buf.getvalue(), overwrite=overwrite)


def read_iso_measurements(path) -> IsoMeasurements:
    """Read a measurement file; :class:`FileFormatError` names the file, line and column."""
    from ..transforms import matrix_from_rotvec

    p = Path(path)
    text = p.read_text(encoding="utf-8-sig")
    meta, lines = {}, text.splitlines()
    start = 0
    for i, line in enumerate(lines):
        s = line.strip()
        if s.startswith("#"):
            if ":" in s:
                k, v = s[1:].split(":", 1)
                meta[k.strip().lower()] = v.strip()
            continue
        if s:
            start = i
            break
    else:
        raise FileFormatError(None, f"{p}: no header row (expected id,time_s,x,y,z[,a,b,c])")
    if meta.get("format", ISO_MEASUREMENT_FORMAT) != ISO_MEASUREMENT_FORMAT:
        raise FileFormatError(None, f"{p}: format {meta['format']!r} is not {ISO_MEASUREMENT_FORMAT!r}")
    frame = meta.get("frame")
    if frame != "base":
        raise FileFormatError(None, f"{p}: '# frame: base' is required (ISO 9283 states its figures in the robot's base "
                              f"frame: register the instrument to the base first); got {frame!r}")
    unit = meta.get("length_unit")
    if unit not in _LENGTH:
        raise FileFormatError(None, f"{p}: '# length_unit:' must be mm or m, got {unit!r}")
    scale = _LENGTH[unit]
    reader = csv.reader(lines[start:])
    header = [h.strip().lower() for h in next(reader)]
    need = ["id", "time_s", "x", "y", "z"]
    missing = [c for c in need if c not in header]
    if missing:
        raise FileFormatError(None, f"{p}, line {start + 1}: missing column(s) {', '.join(missing)} "
                              f"(expected {','.join(need)}[,a,b,c])")
    has_rot = all(c in header for c in ("a", "b", "c"))
    if has_rot and meta.get("orientation") != "rotvec_deg":
        raise FileFormatError(None, f"{p}: columns a,b,c need '# orientation: rotvec_deg' (rotation vector, degrees)")
    idx = {c: header.index(c) for c in header}
    pos, rot, tim = {}, {}, {}
    for n, row in enumerate(reader, start + 2):
        if not row or all(not c.strip() for c in row):
            continue
        if n - start > _MAX_ROWS:
            raise FileFormatError(None, f"{p}: more than {_MAX_ROWS:,} rows, the limit")
        if len(row) != len(header):
            raise FileFormatError(None, f"{p}, line {n}: {len(row)} values for {len(header)} columns")
        vals = {}
        for c in header:
            if c == "id":
                continue
            try:
                v = float(row[idx[c]])
            except ValueError:
                raise FileFormatError(None, f"{p}, line {n}, column '{c}': {row[idx[c]]!r} is not a number") from None
            if not math.isfinite(v):
                raise FileFormatError(None, f"{p}, line {n}, column '{c}': not finite")
            vals[c] = v
        mid = row[idx["id"]].strip()
        pos.setdefault(mid, []).append([vals["x"] * scale, vals["y"] * scale, vals["z"] * scale])
        tim.setdefault(mid, []).append(vals["time_s"])
        if has_rot:
            rot.setdefault(mid, []).append([vals["a"], vals["b"], vals["c"]])
    positions = {k: np.array(v) for k, v in pos.items()}
    times = {k: np.array(v) for k, v in tim.items()}
    rotations = {k: matrix_from_rotvec(np.radians(np.array(v))) for k, v in rot.items()} if has_rot else None
    return IsoMeasurements(positions, rotations, times, p)
