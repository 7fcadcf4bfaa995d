"""Barrier-events files (format ``robocal-barrier-events/1``): executed motions and the light
barrier state changes seen during them, as recorded by a controller or written by the simulator.

Layout (CSV, mm and s, base frame; every field is described in ``robocal tcp cross-laser --help``)::

    # format: robocal-barrier-events/1
    # length_unit: mm, time_unit: s, angles in motion headers: deg
    # motion: {"id": 0, "t_start_s": ..., "duration_s": ..., "settle_s": ..., "kind": "circle", ...}
    ...
    motion,time_s,barrier,state,x_mm,y_mm,z_mm
    2,1.2345,x,blocked,-850.1,-170.2,390.0

One ``# motion:`` JSON header per executed motion (the programmed :class:`CircleMove` or
:class:`LinearMove`, angles in degrees), then one row per barrier state change. Reading gives
:class:`~robocal.tcp.cross_laser.MotionRecord` s for
:func:`robocal.tcp.cross_laser.evaluate_recording`; malformed content raises
:class:`~robocal.io.header.FileFormatError` (a ``ValueError``) naming the file and line.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

from ..tcp.cross_laser import BarrierEvent, CircleMove, LinearMove, MotionRecord
from .header import FileFormatError, read_text

__all__ = ["EVENTS_FORMAT", "motion_to_dict", "motion_from_dict", "write_events_csv", "read_events_csv"]

EVENTS_FORMAT = "robocal-barrier-events/1"

_COLUMNS = ["motion", "time_s", "barrier", "state", "x_mm", "y_mm", "z_mm"]


# ---------------------------------------------------------------------------------------------
# motion headers
# ---------------------------------------------------------------------------------------------


def _floats(v) -> list:
    return [float(x) for x in v]


def motion_to_dict(motion) -> dict:
    """The ``# motion:`` header fields of a :class:`CircleMove` or :class:`LinearMove` (mm, s,
    angles in degrees, rotations as 3x3 lists)."""
    m = motion
    if m.kind == "circle":
        return {"kind": "circle", "step": int(m.step), "role": m.role,
                "center_mm": _floats(m.center_mm), "radius_mm": float(m.radius_mm),
                "normal": _floats(m.normal), "ref_dir": _floats(m.ref_dir),
                "start_angle_deg": math.degrees(m.start_angle_rad), "sweep_deg": math.degrees(m.sweep_rad),
                "speed_mm_s": float(m.speed_mm_s), "accel_mm_s2": float(m.accel_mm_s2),
                "R_base_flange": [_floats(r) for r in m.R_base_flange]}
    return {"kind": "line", "step": int(m.step), "role": m.role,
            "start_mm": _floats(m.start_mm), "end_mm": _floats(m.end_mm),
            "R_start": [_floats(r) for r in m.R_start], "R_end": [_floats(r) for r in m.R_end],
            "speed_mm_s": float(m.speed_mm_s), "angular_speed_deg_s": math.degrees(m.angular_speed_rad_s),
            "accel_mm_s2": float(m.accel_mm_s2)}


def motion_from_dict(d: dict):
    """Inverse of :func:`motion_to_dict`: a :class:`CircleMove` or :class:`LinearMove`."""
    kind = d.get("kind")
    if kind == "circle":
        return CircleMove(center_mm=d["center_mm"], radius_mm=float(d["radius_mm"]), normal=d["normal"],
                          ref_dir=d["ref_dir"], start_angle_rad=math.radians(float(d["start_angle_deg"])),
                          sweep_rad=math.radians(float(d["sweep_deg"])), speed_mm_s=float(d["speed_mm_s"]),
                          accel_mm_s2=float(d["accel_mm_s2"]), R_base_flange=d["R_base_flange"],
                          step=int(d.get("step", 0)), role=str(d.get("role", "circle")))
    if kind == "line":
        return LinearMove(start_mm=d["start_mm"], end_mm=d["end_mm"], R_start=d["R_start"], R_end=d["R_end"],
                          speed_mm_s=float(d["speed_mm_s"]),
                          angular_speed_rad_s=math.radians(float(d["angular_speed_deg_s"])),
                          accel_mm_s2=float(d["accel_mm_s2"]), step=int(d.get("step", 0)),
                          role=str(d.get("role", "move")))
    raise ValueError(f"unknown motion kind {kind!r} (expected 'circle' or 'line')")


# ---------------------------------------------------------------------------------------------
# writing
# ---------------------------------------------------------------------------------------------


def write_events_csv(path, records, note: str | None = None) -> Path:
    """Write motion records (:class:`~robocal.tcp.cross_laser.MotionRecord`) as a barrier-events
    file; ``note`` becomes ``#`` comment lines. Returns the path."""
    lines = [f"# format: {EVENTS_FORMAT}", "# length_unit: mm, time_unit: s, angles in motion headers: deg"]
    if note:
        lines += [f"# {ln}" for ln in str(note).splitlines()]
    rows = []
    for i, r in enumerate(records):
        head = {"id": i, "t_start_s": float(r.t_start_s), "duration_s": float(r.duration_s),
                "settle_s": float(r.settle_s)}
        head.update(motion_to_dict(r.motion))
        lines.append("# motion: " + json.dumps(head, separators=(",", ":")))
        for e in r.events:
            p = e.flange_mm if e.flange_mm is not None else (math.nan,) * 3
            rows.append(f"{i},{e.time_s:.6f},{e.barrier},{e.state},{p[0]:.6f},{p[1]:.6f},{p[2]:.6f}")
    lines.append(",".join(_COLUMNS))
    Path(path).write_text("\n".join(lines + rows) + "\n", encoding="utf-8")
    return Path(path)


# ---------------------------------------------------------------------------------------------
# reading
# ---------------------------------------------------------------------------------------------


def _comment(body: str, path, ln: int, heads: dict):
    """A ``#`` line: checks ``format:``, parses ``motion:`` into ``heads`` (id -> (header dict,
    motion)); returns the format named on a ``format:`` line, else None."""
    if body.startswith("format:"):
        fmt = body.split(":", 1)[1].strip()
        if fmt != EVENTS_FORMAT:
            raise FileFormatError(path, f"format {fmt!r} not supported (expected {EVENTS_FORMAT})", ln)
        return fmt
    if body.startswith("motion:"):
        try:
            d = json.loads(body.split(":", 1)[1])
            mid = int(d["id"])
            heads[mid] = (d, motion_from_dict(d))
        except (ValueError, KeyError, TypeError) as exc:
            raise FileFormatError(path, f"bad motion header: {exc}", ln) from None
    return None


def _event_row(fields: list, path, ln: int, heads: dict):
    """One data row -> ``(motion id, BarrierEvent)``; every field checked."""
    if len(fields) != 7:
        raise FileFormatError(path, f"expected 7 fields, got {len(fields)}", ln)
    try:
        mid, t = int(fields[0]), float(fields[1])
        xyz = np.array([float(v) for v in fields[4:]])
    except ValueError:
        raise FileFormatError(path, "non-numeric motion, time or position", ln) from None
    if fields[2] not in ("x", "y"):
        raise FileFormatError(path, f"{fields[2]!r} is not x or y", ln, "barrier")
    if fields[3] not in ("blocked", "clear"):
        raise FileFormatError(path, f"{fields[3]!r} is not blocked or clear", ln, "state")
    if mid not in heads:
        raise FileFormatError(path, f"motion {mid} has no '# motion:' header", ln)
    return mid, BarrierEvent(t, fields[2], fields[3], None if np.any(np.isnan(xyz)) else xyz)


def read_events_csv(path) -> list:
    """Read a barrier-events file into :class:`~robocal.tcp.cross_laser.MotionRecord` s, in motion
    id order. Raises :class:`FileFormatError` (a ``ValueError``) naming the file and line."""
    path = Path(path)
    text = read_text(path, FileFormatError, what="barrier-events")
    heads, events, header, fmt = {}, {}, None, None
    for ln, line in enumerate(text.splitlines(), 1):
        s = line.strip()
        if not s:
            continue
        if s.startswith("#"):
            fmt = _comment(s[1:].strip(), path, ln, heads) or fmt
            continue
        fields = [f.strip() for f in s.split(",")]
        if header is None:
            if fields != _COLUMNS:
                raise FileFormatError(path, f"header must be '{','.join(_COLUMNS)}'", ln)
            header = fields
            continue
        mid, event = _event_row(fields, path, ln, heads)
        events.setdefault(mid, []).append(event)
    if fmt is None:
        raise FileFormatError(path, f"missing '# format: {EVENTS_FORMAT}' line")
    if header is None:
        raise FileFormatError(path, f"missing the header line '{','.join(_COLUMNS)}'")
    return [MotionRecord(motion=m, t_start_s=float(d["t_start_s"]), events=tuple(events.get(i, ())),
                         duration_s=float(d.get("duration_s", m.duration_s)), settle_s=float(d.get("settle_s", 0.0)))
            for i, (d, m) in sorted(heads.items())]
