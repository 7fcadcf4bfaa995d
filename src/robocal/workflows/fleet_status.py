"""``robocal fleet status``: which robots of a history database need attention.

For every robot in the database (SQLite or a server by URL) over its committed calibrations of
one kind (default ``geometric_calibration``):

* **stale**: no calibration, or the last one started more than ``max_age_days`` before ``now``;
* **drifting**: the trend of an identified parameter crosses the tolerance. Per parameter, the
  identified changes from nominal ``d(t)`` [mm or rad] of every calibration get a least-squares
  line ``d(t) ~ a + b t``; the trend's drift is ``b (now - t_first)``: how far the line has moved
  since the first calibration, extrapolated to ``now``. A length parameter is flagged when
  ``|b| (now - t_first) > tolerance_mm``, an angle when it exceeds ``tolerance_deg``. It needs two
  calibrations at different times (with two, the line is through both).

A drift plot per flagged robot (the drifting parameters and the accuracy metrics over time) is
written with :func:`robocal.report.history_plot.plot_history`.
"""

from __future__ import annotations

import math
from datetime import datetime, timezone
from pathlib import Path

import numpy as np

__all__ = ["drift_trend", "fleet_status"]

_DAY_US = 86400e6


def drift_trend(times, values, now) -> tuple:
    """(slope per day, drift since the first time extrapolated to ``now``) of the least-squares line
    through ``values`` (N,) at ``times`` (N,) ``datetime64``; (nan, nan) with fewer than two distinct
    times. Same unit as ``values``."""
    t = (np.asarray(times, dtype="datetime64[us]") - np.asarray(times, dtype="datetime64[us]")[0]).astype(float)
    t /= _DAY_US
    v = np.asarray(values, dtype=float)
    ok = np.isfinite(v)
    t, v = t[ok], v[ok]
    if len(t) < 2 or np.ptp(t) <= 0:
        return math.nan, math.nan
    slope = float(np.polyfit(t, v, 1)[0])
    span = (np.datetime64(now.replace(tzinfo=None), "us") - np.asarray(times, dtype="datetime64[us]")[0]).astype(
        float) / _DAY_US
    return slope, slope * float(span)


def _robot_status(store, robot, kind, now, max_age_days, tol_mm, tol_rad) -> dict:
    cycles = store.cycles(robot, kind=kind, status="committed")
    row = {"robot": robot, "calibrations": len(cycles), "last_calibration": None, "age_days": None,
           "stale": True, "drifting": False, "drift": []}
    if not cycles:
        row["reasons"] = [f"no {kind} recorded"]
        return row
    last = max(c.started_at for c in cycles)
    age = (now - last).total_seconds() / 86400.0
    row.update(last_calibration=last.isoformat(), age_days=round(age, 3), stale=bool(age > max_age_days))
    reasons = [f"last {kind} {age:.1f} days ago (limit {max_age_days:g})"] if row["stale"] else []
    names = store.parameter_names(robot)
    series = store.parameter_history(robot, names, kind=kind) if names else {}
    for name, s in series.items():
        if s.unit not in ("mm", "rad") or len(s) < 2:
            continue
        slope, drift = drift_trend(s.times, s.values, now)
        if not math.isfinite(drift):
            continue
        tol = tol_mm if s.unit == "mm" else tol_rad
        item = {"parameter": name, "unit": s.unit, "slope_per_day": slope, "trend_drift": drift,
                "tolerance": tol, "over": bool(abs(drift) > tol), "n": len(s)}
        row["drift"].append(item)
    row["drift"].sort(key=lambda d: -abs(d["trend_drift"]) / d["tolerance"])
    over = [d for d in row["drift"] if d["over"]]
    row["drifting"] = bool(over)
    for d in over[:3]:
        shown = (d["trend_drift"], "mm") if d["unit"] == "mm" else (math.degrees(d["trend_drift"]), "deg")
        tol = (d["tolerance"], "mm") if d["unit"] == "mm" else (math.degrees(d["tolerance"]), "deg")
        reasons.append(f"{d['parameter']} trend {shown[0]:+.4g} {shown[1]} since the first calibration "
                       f"(tolerance {tol[0]:g} {tol[1]})")
    row["reasons"] = reasons
    return row


def _guarded_status(store, robot, kind, now, *limits) -> dict:
    """:func:`_robot_status`, or a stale row naming why this robot cannot be read (an id written by
    other software outside the valid set): one robot never stops the status run."""
    from ..store import HistoryInputError

    try:
        return _robot_status(store, robot, kind, now, *limits)
    except HistoryInputError as exc:
        return {"robot": robot, "calibrations": 0, "last_calibration": None, "age_days": None, "stale": True,
                "drifting": False, "drift": [], "reasons": [f"cannot be checked: {exc}"]}


def _plot(store, row, kind, plot_dir: Path) -> str:
    from ..report.history_plot import plot_history

    robot = row["robot"]
    names = [d["parameter"] for d in row["drift"][:6]]
    params = store.parameter_history(robot, names, kind=kind) if names else {}
    metrics = {m: store.metric_history(robot, m, kind=kind) for m in store.metric_names(robot)
               if m.endswith("rms_after") or m.endswith("rms_before")}
    events = [(c.started_at, c.kind) for c in store.cycles(robot, kind=kind, status="committed")]
    from ..io.output_paths import path_under, safe_file_stem

    path = path_under(plot_dir, f"{safe_file_stem(robot)}_drift.png")  # an id from the database is data
    plot_history(params, metrics, path, f"{robot}: " + "; ".join(row["reasons"][:2]), events=events)
    return str(path)


def fleet_status(db, *, max_age_days: float = 90.0, tolerance_mm: float = 0.1, tolerance_deg: float = 0.01,
                 kind: str = "geometric_calibration", now=None, plot_dir=None) -> dict:
    """Every robot of the history database ``db`` (path or URL) with ``stale`` and ``drifting``
    (see the module docstring) and the reasons; ``flagged`` lists the robots with either. now:
    aware datetime (default: the current UTC time). plot_dir: a folder for ``<robot>_drift.png``
    per flagged robot (None: no plots)."""
    from ..store import HistoryStore

    for name, v in (("max_age_days", max_age_days), ("tolerance_mm", tolerance_mm), ("tolerance_deg", tolerance_deg)):
        if not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
            raise ValueError(f"{name} must be a positive number, got {v!r}")
    now = now or datetime.now(timezone.utc)
    if now.tzinfo is None:
        raise ValueError("now must carry a time zone (UTC)")
    now = now.astimezone(timezone.utc)
    with HistoryStore.open(db, create=False) as store:
        rows = [_guarded_status(store, r, kind, now, max_age_days, tolerance_mm, math.radians(tolerance_deg))
                for r in store.robots()]
        if plot_dir is not None:
            plot_dir = Path(plot_dir)
            for row in rows:
                if (row["drifting"] or row["stale"]) and row["drift"]:
                    plot_dir.mkdir(parents=True, exist_ok=True)
                    try:
                        row["plot"] = _plot(store, row, kind, plot_dir)
                    except (ValueError, OSError) as exc:  # one robot's plot never stops the status run
                        row["plot"], row["plot_error"] = None, str(exc)
        where = store.url
    flagged = [r["robot"] for r in rows if r["stale"] or r["drifting"]]
    return {"database": where, "now": now.isoformat(), "kind": kind, "max_age_days": max_age_days,
            "tolerance_mm": tolerance_mm, "tolerance_deg": tolerance_deg, "robots": rows, "flagged": flagged}
