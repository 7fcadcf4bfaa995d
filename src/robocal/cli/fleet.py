"""``robocal fleet ...``: many robots at once on Dask (docs/fleet.md).

Thin: parse, open the Dask client (:mod:`robocal.workflows.fleet_cluster`), call the workflow,
print. dask is imported only when a fleet command runs.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

import click

from ._common import EXIT_FAILED_RESULT, _user_error

__all__ = ["fleet"]

fleet = click.Group(
    "fleet",
    help="Many robots at once on Dask (a local cluster, or --scheduler tcp://host:8786): calibrate a fleet, "
         "run studies, list the robots that need attention (docs/fleet.md).",
    context_settings={"help_option_names": ["-h", "--help"]},
)

_SCHEDULER = click.option("--scheduler", default=None, metavar="ADDRESS",
                          help="An existing Dask cluster's scheduler (tcp://host:8786); default: a local cluster.")
_WORKERS = click.option("--workers", type=int, default=None, metavar="N",
                        help="Worker processes of the local cluster (default: one per CPU).")


def _client(scheduler, workers):
    from ..workflows.fleet_cluster import FleetClusterError, fleet_client

    try:
        return fleet_client(scheduler, workers)
    except FleetClusterError as exc:
        raise click.ClickException(str(exc)) from None


def _history_target(db, no_history, out_dir):
    if no_history:
        return None
    from ..store import HISTORY_DB_ENV

    return db or os.environ.get(HISTORY_DB_ENV) or str(Path(out_dir) / "history.sqlite")


@fleet.command("calibrate")
@click.argument("fleet_file", metavar="FLEET.toml", type=click.Path(dir_okay=False))
@click.option("--out", "out_dir", required=True, type=click.Path(file_okay=False),
              help="Folder for <id>/ per robot, summary.json, summary.html and summary.png.")
@_SCHEDULER
@_WORKERS
@click.option("--db", default=None, metavar="PATH_OR_URL",
              help="History database every result is recorded in (default: $ROBOCAL_HISTORY_DB, else "
                   "OUT/history.sqlite).")
@click.option("--no-history", is_flag=True, help="Do not record the results in a history database.")
@click.option("--no-report", is_flag=True, help="No report.html per robot (the plots take longer than the solve).")
def calibrate_cmd(fleet_file, out_dir, scheduler, workers, db, no_history, no_report):
    """Calibrate every robot of FLEET.toml, one Dask task per robot.

    Writes OUT/<id>/ (the files of `robocal calibrate`), OUT/summary.json (status ok or failed with
    the reason, per robot), OUT/summary.html and .png. Robots whose inputs are unchanged since an
    earlier run into OUT are skipped (content hash): a crashed run resumes. Exit code 3 when any
    robot failed.
    """
    from ..workflows.fleet import run_fleet_calibration
    from ..workflows.fleet_cluster import FleetClusterError

    target = _history_target(db, no_history, out_dir)
    bar = None
    try:
        with _client(scheduler, workers) as client:
            label = f"robots ({len(client.scheduler_info().get('workers', {}))} workers)"
            with click.progressbar(length=1, label=label, file=sys.stderr, show_pos=True) as bar:
                def progress(done, total, row):
                    bar.length = total
                    bar.update(1)

                r = run_fleet_calibration(fleet_file, out_dir, client=client, db=target, report=not no_report,
                                          progress=progress)
    except (ValueError, KeyError, OSError, FleetClusterError) as exc:
        raise _user_error(exc) from None
    s = r["summary"]
    c = s["counts"]
    for row in s["robots"]:
        if row["status"] != "ok":
            click.echo(f"FAILED {row['id']}: {row['reason']}", err=True)
        elif row.get("outlier"):
            click.echo(f"outlier {row['id']}: accuracy after calibration {row.get('holdout_rms_after_mm')} mm "
                       f"(modified z {row.get('outlier_z')})", err=True)
    click.echo(f"{c['robots']} robots: {c['ok']} ok, {c['failed']} failed, {c['skipped']} unchanged (skipped), "
               f"{c['outliers']} outlier(s); {s['wall_seconds']:.1f} s")
    click.echo("wrote " + ", ".join(str(p) for p in r["files"].values())
               + (f"; history {s['history']}" if s["history"] else ""))
    if c["failed"]:
        sys.exit(EXIT_FAILED_RESULT)


@fleet.command("status")
@click.option("--db", required=True, metavar="PATH_OR_URL",
              help="History database: an SQLite file or a URL (postgresql+psycopg://user@host/db).")
@click.option("--max-age", "max_age_days", type=float, default=90.0, show_default=True, metavar="DAYS",
              help="A robot whose last calibration is older is stale.")
@click.option("--tolerance", "tolerance_mm", type=float, default=0.1, show_default=True, metavar="MM",
              help="Flag a length parameter whose drift trend since the first calibration exceeds this.")
@click.option("--tolerance-deg", type=float, default=0.01, show_default=True, metavar="DEG",
              help="Flag an angle parameter whose drift trend exceeds this.")
@click.option("--kind", default="geometric_calibration", show_default=True,
              type=click.Choice(["geometric_calibration", "thermal_compensation", "tool_recalibration", "measurement"]),
              help="Which cycles count as calibrations.")
@click.option("--plots", "plot_dir", default="drift-plots", show_default=True, type=click.Path(file_okay=False),
              help="Folder for <robot>_drift.png per flagged robot.")
@click.option("--no-plots", is_flag=True, help="Write no drift plots.")
@click.option("--json", "as_json", is_flag=True, help="Print JSON instead of a table.")
def status_cmd(db, max_age_days, tolerance_mm, tolerance_deg, kind, plot_dir, no_plots, as_json):
    """Robots whose last calibration is older than --max-age or whose drift trend crosses the
    tolerance, from the history database (SQLite or PostgreSQL). Exit code 3 when any is flagged."""
    import json

    from ..store import HistoryError
    from ..workflows.fleet_status import fleet_status

    try:
        r = fleet_status(db, max_age_days=max_age_days, tolerance_mm=tolerance_mm, tolerance_deg=tolerance_deg,
                         kind=kind, plot_dir=None if no_plots else plot_dir)
    except (ValueError, OSError, HistoryError) as exc:
        raise _user_error(exc) from None
    if as_json:
        click.echo(json.dumps(r, indent=2))
    else:
        click.echo(f"{len(r['robots'])} robots in {r['database']}: {len(r['flagged'])} need attention "
                   f"(stale after {max_age_days:g} days; drift tolerance {tolerance_mm:g} mm, {tolerance_deg:g} deg)")
        for row in r["robots"]:
            state = ", ".join(s for s, on in (("STALE", row["stale"]), ("DRIFTING", row["drifting"])) if on) or "ok"
            age = "-" if row["age_days"] is None else f"{row['age_days']:.1f} d"
            click.echo(f"  {row['robot']:<24} {state:<16} calibrations {row['calibrations']:>3}  last {age:>9}")
            for reason in row["reasons"]:
                click.echo(f"      {reason}")
            if row.get("plot"):
                click.echo(f"      plot: {row['plot']}")
    if r["flagged"]:
        sys.exit(EXIT_FAILED_RESULT)
