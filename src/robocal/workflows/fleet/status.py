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

* **performance**: the trend of the worst-pose ISO 9283 AP or RP over the robot's performance tests
  (``robocal iso9283 evaluate --db``) crosses ``ap_tolerance_mm`` / ``rp_tolerance_mm``: the
  least-squares line through the tests, evaluated at ``now`` (with one test, that test's value),
  exceeds the tolerance;
* **verification**: the last quick verification (``robocal verify --db``) did not end in ``ok``.
  Every robot's last verification is listed.

A drift plot per flagged robot (the drifting parameters and the accuracy metrics over time) is
written with :func:`robocal.report.history_plot.plot_history`.
"""

from __future__ import annotations

import math
from datetime import datetime, timezone
from pathlib import Path

import numpy as np

__all__ = ["drift_trend", "fleet_status", "trend_at"]

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


def trend_at(times, values, now) -> float:
    """The least-squares line through ``values`` (N,) at ``times`` (N,) ``datetime64`` evaluated at
    ``now`` (aware datetime); the single value with one point (or several at one time: their mean);
    NaN with none. Same unit as ``values``."""
    t = np.asarray(times, dtype="datetime64[us]")
    v = np.asarray(values, dtype=float)
    ok = np.isfinite(v)
    t, v = t[ok], v[ok]
    if len(v) == 0:
        return math.nan
    x = (t - t[0]).astype(float) / _DAY_US
    if len(v) < 2 or np.ptp(x) <= 0:
        return float(np.mean(v))
    b, a = np.polyfit(x, v, 1)
    x_now = (np.datetime64(now.astimezone(timezone.utc).replace(tzinfo=None), "us") - t[0]).astype(float) / _DAY_US
    return float(a + b * x_now)


def _performance(store, robot, now, ap_tol, rp_tol) -> dict:
    """The ISO 9283 trend and the last verification of one robot (see the module docstring)."""
    out = {"iso_tests": 0, "iso": {}, "performance_drifting": False, "last_verification": None,
           "verification_failed": False, "perf_reasons": []}
    for sym, tol in (("AP", ap_tol), ("RP", rp_tol)):
        s = store.iso_figure_history(robot, sym)
        if not len(s):
            continue
        out["iso_tests"] = max(out["iso_tests"], len(s))
        at_now = trend_at(s.times, s.values, now)
        slope = drift_trend(s.times, s.values, now)[0]
        item = {"last_mm": float(s.values[-1]), "trend_now_mm": at_now,
                "slope_mm_per_day": None if not math.isfinite(slope) else slope, "n": len(s), "tolerance_mm": tol,
                "over": bool(tol is not None and at_now > tol)}
        out["iso"][sym] = item
        if item["over"]:
            out["performance_drifting"] = True
            out["perf_reasons"].append(f"ISO 9283 {sym} trend {at_now:.4f} mm now (last test {item['last_mm']:.4f} mm, "
                                       f"{len(s)} tests; tolerance {tol:g} mm)")
    ver = store.verifications(robot)
    if ver:
        v = ver[-1]
        out["last_verification"] = {"time": v["time"].isoformat(), "decision": v["decision"],
                                    "statistic": v["statistic"], "threshold": v["threshold"], "suspect": v["suspect"],
                                    "instrument": v["instrument"]}
        if v["decision"] != "ok":
            out["verification_failed"] = True
            out["perf_reasons"].append(f"last verification ({v['time']:%Y-%m-%d}): {v['decision']}"
                                       + (f" ({v['suspect']})" if v["suspect"] else ""))
    return out


def _guarded_status(store, robot, kind, now, *limits) -> dict:
    """:func:`_robot_status`, or a stale row naming why this robot cannot be read (an id written by
    other software outside the valid set): one robot never stops the status run."""
    from ...store import HistoryInputError

    try:
        return _robot_status(store, robot, kind, now, *limits)
    except HistoryInputError as exc:
        return {"robot": robot, "calibrations": 0, "last_calibration": None, "age_days": None, "stale": True,
                "drifting": False, "drift": [], "reasons": [f"cannot be checked: {exc}"]}


def _plot(store, row, kind, plot_dir: Path) -> str:
    from ...report.history_plot import plot_history

    robot = row["robot"]
    names = [d["parameter"] for d in row["drift"][:6]]
    params = store.parameter_history(robot, names, kind=kind) if names else {}
    metrics = {m: store.metric_history(robot, m, kind=kind) for m in store.metric_names(robot)
               if m.endswith("rms_after") or m.endswith("rms_before")}
    events = [(c.started_at, c.kind) for c in store.cycles(robot, kind=kind, status="committed")]
    from ...io.output_paths import path_under, safe_file_stem

    path = path_under(plot_dir, f"{safe_file_stem(robot)}_drift.png")  # an id from the database is data
    plot_history(params, metrics, path, f"{robot}: " + "; ".join(row["reasons"][:2]), events=events)
    return str(path)


def fleet_status(db, *, max_age_days: float = 90.0, tolerance_mm: float = 0.1, tolerance_deg: float = 0.01,
                 kind: str = "geometric_calibration", now=None, plot_dir=None, ap_tolerance_mm: float | None = None,
                 rp_tolerance_mm: float | None = None) -> dict:
    """Every robot of the history database ``db`` (path or URL) with ``stale``, ``drifting``,
    ``performance_drifting`` and ``verification_failed`` (see the module docstring) and the
    reasons; ``flagged`` lists the robots with any. now: aware datetime (default: the current UTC
    time). plot_dir: a folder for ``<robot>_drift.png`` per flagged robot (None: no plots).
    ap_tolerance_mm, rp_tolerance_mm [mm]: the ISO 9283 AP/RP tolerance (None: not checked)."""
    from ...store import HistoryStore

    for name, v in (("max_age_days", max_age_days), ("tolerance_mm", tolerance_mm), ("tolerance_deg", tolerance_deg),
                    ("ap_tolerance_mm", ap_tolerance_mm or 1.0), ("rp_tolerance_mm", rp_tolerance_mm or 1.0)):
        if not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
            raise ValueError(f"{name} must be a positive number, got {v!r}")
    now = now or datetime.now(timezone.utc)
    if now.tzinfo is None:
        raise ValueError("now must carry a time zone (UTC)")
    now = now.astimezone(timezone.utc)
    with HistoryStore.open(db, create=False) as store:
        rows = [_guarded_status(store, r, kind, now, max_age_days, tolerance_mm, math.radians(tolerance_deg))
                for r in store.robots()]
        from ...store import HistoryInputError

        for row in rows:
            try:
                perf = _performance(store, row["robot"], now, ap_tolerance_mm, rp_tolerance_mm)
            except HistoryInputError:  # an id other software wrote: _guarded_status named it already
                continue
            row["reasons"] += perf.pop("perf_reasons")
            row.update(perf)
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
    flagged = [r["robot"] for r in rows
               if r["stale"] or r["drifting"] or r["performance_drifting"] or r["verification_failed"]]
    return {"database": where, "now": now.isoformat(), "kind": kind, "max_age_days": max_age_days,
            "tolerance_mm": tolerance_mm, "tolerance_deg": tolerance_deg, "ap_tolerance_mm": ap_tolerance_mm,
            "rp_tolerance_mm": rp_tolerance_mm, "robots": rows, "flagged": flagged}
