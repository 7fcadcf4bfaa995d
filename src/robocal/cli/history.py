"""``robocal history ROBOT``: the robot's calibration and maintenance cycles and its parameter drift.

Thin: opens the history database, asks the store, prints (and plots). Errors are one line.
"""

from __future__ import annotations

import json
import math
from datetime import datetime, timezone
from pathlib import Path
from types import SimpleNamespace

import click
import numpy as np

from ..report.units import display_unit

from ..store import (
    HistoryError,
    HistoryInputError,
    HistoryStore,
    default_history_target,
)

# Metrics shown as table columns first (when present), then the others alphabetically.
_PREFERRED_METRICS = ("residual_rms_before", "residual_rms_after", "lambda", "cycle_time")
_MAX_METRIC_COLUMNS = 4


def _since(value):
    if value is None:
        return None
    s = value.strip()
    try:
        t = datetime.fromisoformat(s[:-1] + "+00:00" if s.endswith("Z") else s)
    except ValueError:
        raise click.ClickException(f"--since {value!r} is not an ISO 8601 time (e.g. 2024-05-01 or 2024-05-01T06:00Z)") from None
    return t if t.tzinfo is not None else t.replace(tzinfo=timezone.utc)


def _fmt(v, signed=False) -> str:
    if v is None or (isinstance(v, float) and not math.isfinite(v)):
        return "-"
    return f"{v:+.4g}" if signed else f"{v:.4g}"


def _table(headers, rows, right) -> list:
    cols = list(zip(headers, *rows)) if rows else [(h,) for h in headers]
    widths = [max(len(str(x)) for x in col) for col in cols]
    out = []
    for r in [headers, *rows]:
        cells = [str(x).rjust(w) if right[i] else str(x).ljust(w) for i, (x, w) in enumerate(zip(r, widths))]
        out.append("  " + "  ".join(cells).rstrip())
    return out


def _metric_columns(cycles) -> list:
    names = {n for c in cycles for n in c.metrics}
    ordered = [n for n in _PREFERRED_METRICS if n in names] + sorted(names - set(_PREFERRED_METRICS))
    return ordered[:_MAX_METRIC_COLUMNS]


def _num(v):
    return None if v is None or not math.isfinite(float(v)) else float(v)


def _series_json(s) -> dict:
    """A series in its display unit (angles in deg, as the console and the plot)."""
    k, unit = display_unit(s.unit)
    return {"unit": unit, "times": [str(t) + "Z" for t in s.times.astype("datetime64[us]")],
            "values": [_num(k * v) for v in s.values], "std": [_num(k * v) for v in s.std],
            "cycle_ids": [int(i) for i in s.cycle_ids], "kinds": list(s.kinds)}


@click.command("history")
@click.argument("robot")
@click.option("--db", "db", default=None, metavar="PATH_OR_URL",
              help="History database: an SQLite file or a URL (default: $ROBOCAL_HISTORY_DB or robocal-history.sqlite).")
@click.option("--params", "params", default=None, metavar="NAMES",
              help="Comma-separated parameter names to show and plot (default: all stored).")
@click.option("--kind", "kinds", multiple=True,
              type=click.Choice(["geometric_calibration", "thermal_compensation", "tool_recalibration", "measurement"]),
              help="Only cycles of this kind (repeatable).")
@click.option("--since", default=None, metavar="TIME", help="Only cycles started at or after TIME (ISO 8601; UTC if no zone).")
@click.option("--plots", "plot_dir", default=None, type=click.Path(file_okay=False), metavar="DIR",
              help="Folder for <robot>_drift.png: parameter deltas and metrics over time (created if needed; as "
                   "'fleet status --plots').")
@click.option("--plot", "plot_file", default=None, type=click.Path(dir_okay=False), hidden=True,
              help="Deprecated: write the drift plot to this file (.png, .svg, .pdf); use --plots DIR.")
@click.option("--overwrite", is_flag=True, help="Replace an existing drift plot.")
@click.option("--json", "as_json", is_flag=True, help="Print JSON instead of tables.")
def history_cmd(robot, db, params, kinds, since, plot_dir, plot_file, overwrite, as_json):
    """Print (and plot) ROBOT's calibration and maintenance history and its parameter drift."""
    names = None
    if params is not None:
        names = [p.strip() for p in params.split(",") if p.strip()]
        if not names:
            raise click.ClickException("--params: give one or more parameter names separated by commas")
    if plot_dir is not None and plot_file is not None:
        raise click.UsageError("give --plots DIR (the deprecated --plot FILE is its older form), not both")
    plot_path = plot_file
    if plot_dir is not None:
        from ..io.output_paths import path_under, safe_file_stem

        name = f"{safe_file_stem(robot)}_drift.png"  # the robot id is data: never a path of its own
        path_under(plot_dir, name)
        plot_path = Path(plot_dir) / name
    _check_plot_path(plot_path, {"--db": db}, overwrite, option="--plot" if plot_file is not None else "--plots")
    try:
        view = _read_history(db or default_history_target(), robot, names, list(kinds) or None, _since(since))
    except (HistoryError, HistoryInputError) as exc:
        raise click.ClickException(str(exc)) from None
    if plot_path is not None:
        if plot_dir is not None:
            try:
                Path(plot_dir).mkdir(parents=True, exist_ok=True)
            except OSError as exc:
                raise click.ClickException(f"--plots {plot_dir}: {exc.strerror or exc}") from None
        _plot(view, robot, plot_path)
    if as_json:
        click.echo(json.dumps(_history_json(view, robot, plot_path), indent=2))
        return
    _echo_cycles(view, robot)
    click.echo("")
    _echo_drift(view)
    _echo_performance(view)
    if plot_path is not None:
        click.echo("")
        click.echo(f"plot: {plot_path}")


def _check_plot_path(plot_path, inputs=None, overwrite: bool = False, option: str = "--plots") -> None:
    from ..io.output_paths import check_outputs

    if plot_path is None:
        return
    try:
        check_outputs(plot_path, inputs, overwrite=overwrite)
    except FileExistsError as exc:
        raise click.ClickException(f"{option} {exc}") from None
    if option == "--plots":
        return
    pp = Path(plot_path)
    if pp.suffix.lower() not in (".png", ".svg", ".pdf"):
        raise click.ClickException(f"--plot {plot_path}: give a .png, .svg or .pdf file name")
    if not pp.parent.exists():
        raise click.ClickException(f"--plot {plot_path}: folder {pp.parent} does not exist")


def _read_history(target, robot, names, kind, since_t) -> SimpleNamespace:
    """Everything the command shows, read in one session of the store: cycles, parameter series
    (``names`` or every stored one), metric series, metric columns, the store's URL."""
    with HistoryStore.open(target, create=False) as store:
        cycles = store.cycles(robot, kind=kind, since=since_t)
        stored = store.parameter_names(robot)
        names = stored if names is None else names
        series = store.parameter_history(robot, names, kind=kind, since=since_t) if names else {}
        metric_series = {}
        for m in store.metric_names(robot):
            s = store.metric_history(robot, m, kind=kind, since=since_t)
            if len(s):
                metric_series[m] = s
        iso = {}
        for sym in ("AP", "RP"):
            s = store.iso_figure_history(robot, sym, since=since_t)
            if len(s):
                iso[sym] = s
        verifications = store.verifications(robot, since=since_t)
        return SimpleNamespace(cycles=cycles, stored=stored, series=series, metric_series=metric_series,
                               metric_columns=_metric_columns(cycles), where=store.url, iso=iso,
                               verifications=verifications)


def _plot(view, robot, plot_path) -> None:
    from ..report.history_plot import plot_history

    # ISO 9283 AP/RP first (one panel each), then the table's metrics, then the others
    plot_metrics = {f"ISO 9283 {k} (worst pose)": s for k, s in view.iso.items()}
    iso_names = {"iso9283.AP", "iso9283.RP", "verify.rms", "verify.T"} if view.iso or view.verifications else set()
    plot_metrics |= {m: view.metric_series[m] for m in view.metric_columns
                     if m in view.metric_series and m not in iso_names}
    plot_metrics |= {m: s for m, s in view.metric_series.items() if m not in plot_metrics and m not in iso_names}
    events = [(c.started_at, c.kind) for c in view.cycles if c.status == "committed"]
    outcomes = [(v["time"], v["decision"]) for v in view.verifications]
    try:
        plot_history(view.series, plot_metrics, plot_path, f"{robot}: drift over time", events=events,
                     verifications=outcomes)
    except ValueError as exc:
        raise click.ClickException(f"drift plot: {exc}") from None
    except OSError as exc:
        raise click.ClickException(f"{plot_path}: {exc}") from None


def _history_json(view, robot, plot_path) -> dict:
    out = {
        "robot": robot, "database": view.where,
        "cycles": [{"id": c.id, "kind": c.kind, "status": c.status, "started_at": c.started_at.isoformat(),
                    "finished_at": c.finished_at.isoformat() if c.finished_at else None, "notes": c.notes,
                    "metrics": {n: {"value": q.value, "unit": q.unit} for n, q in c.metrics.items()},
                    "n_measurements": c.n_measurements, "n_parameters": c.n_parameters,
                    "n_corrections": c.n_corrections} for c in view.cycles],
        "parameters": {n: _series_json(s) for n, s in view.series.items()},
        "metrics": {n: _series_json(s) for n, s in view.metric_series.items()},
        "iso9283": {n: _series_json(s) for n, s in view.iso.items()},
        "verifications": [dict(v, time=v["time"].isoformat()) for v in view.verifications],
    }
    if plot_path is not None:
        out["plot"] = str(plot_path)
    return out


def _echo_cycles(view, robot) -> None:
    cycles, mcols = view.cycles, view.metric_columns
    n_failed = sum(c.status == "failed" for c in cycles)
    click.echo(f"History of robot {robot!r} in {view.where}: {len(cycles)} cycles"
               + (f" ({len(cycles) - n_failed} committed, {n_failed} failed)" if n_failed else ""))
    if not cycles:
        click.echo("  (no cycles match)")
        return
    units = {}
    for c in cycles:
        for n, q in c.metrics.items():
            units.setdefault(n, q.unit)
    headers = ["id", "started (UTC)", "kind", "status", "meas", "params", "corr"] + [f"{m} [{units[m]}]" for m in mcols]
    rows = [[c.id, c.started_at.strftime("%Y-%m-%d %H:%M:%S"), c.kind, c.status, c.n_measurements,
             c.n_parameters, c.n_corrections] + [_fmt(c.metrics[m].value) if m in c.metrics else "-" for m in mcols]
            for c in cycles]
    click.echo("")
    click.echo("cycles")
    for line in _table(headers, rows, [True, False, False, False, True, True, True] + [True] * len(mcols)):
        click.echo(line)


def _echo_drift(view) -> None:
    if not view.series:
        click.echo("parameter drift: no parameters stored" + (" for the selected cycles" if view.stored else ""))
        return
    click.echo("parameter drift (Δ from nominal over committed cycles; mm and deg)")
    rows = []
    for n, s in view.series.items():
        k, unit = display_unit(s.unit)
        v = k * np.asarray(s.values, dtype=float)
        if len(v) == 0:
            rows.append([n, unit, 0, "-", "-", "-", "-", "-"])
            continue
        rows.append([n, unit, len(v), _fmt(v[0], True), _fmt(v[-1], True), _fmt(v[-1] - v[0], True),
                     _fmt(float(np.min(v)), True), _fmt(float(np.max(v)), True)])
    for line in _table(["name", "unit", "cycles", "first", "last", "change", "min", "max"], rows,
                       [False, False, True, True, True, True, True, True]):
        click.echo(line)


def _iso_cell(s, cycle_id) -> str:
    """The figure of ``cycle_id`` in the series ``s`` with its uncertainty U (2 std) [mm]."""
    if s is None:
        return "-"
    k = np.flatnonzero(s.cycle_ids == cycle_id)
    if not k.size:
        return "-"
    v, sd = s.values[k[0]], s.std[k[0]]
    return f"{v:.4f}" + (f" ± {2 * sd:.4f}" if math.isfinite(sd) else "")


def _echo_performance(view) -> None:
    """ISO 9283 tests (worst AP and RP over the poses, with the instrument's uncertainty) and the
    quick verifications (decision, statistic, suspect), oldest first."""
    if view.iso:
        click.echo("")
        click.echo("ISO 9283 performance tests (worst pose; U: the instrument's uncertainty)")
        ap, rp = view.iso.get("AP"), view.iso.get("RP")
        base = ap if ap is not None else rp
        rows = []
        for cid, t in zip(base.cycle_ids, base.times):
            rows.append([int(cid), str(t.astype("datetime64[s]")).replace("T", " "), _iso_cell(ap, cid),
                         _iso_cell(rp, cid)])
        for line in _table(["id", "measured (UTC)", "AP [mm]", "RP [mm]"], rows, [True, False, True, True]):
            click.echo(line)
    if view.verifications:
        click.echo("")
        click.echo("verifications")
        rows = []
        for v in view.verifications:
            sus = "-"
            if v["suspect"]:
                val = v["suspect_value"]
                sus = v["suspect"] + ("" if val is None else (f" {math.degrees(val):+.4f} deg" if v["suspect_unit"] == "rad"
                                                              else f" {val:+.4f} mm"))
            rows.append([v["cycle_id"], v["time"].strftime("%Y-%m-%d %H:%M:%S"), v["decision"],
                         f"{v['statistic']:.1f} / {v['threshold']:.1f}", _fmt(v["rms_mm"]), sus,
                         v["instrument"] or "-", _fmt(v["temperature_c"])])
        for line in _table(["id", "measured (UTC)", "decision", "T / threshold", "rms [mm]", "suspect", "instrument",
                            "temp [degC]"], rows, [True, False, False, True, True, False, False, True]):
            click.echo(line)
