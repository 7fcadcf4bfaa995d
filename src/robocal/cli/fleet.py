"""``robocal fleet ...``: many robots at once on Dask (docs/fleet.md).

Thin: parse, open the Dask client (:mod:`robocal.workflows.fleet.cluster`), call the workflow,
print. dask is imported only when a fleet command runs.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

import click

from ._common import EXIT_FAILED_RESULT, _user_error, allow_unconverged_option, finish_convergence
from ._grammar import POINT
from ._json import json_option, set_json_result

__all__ = ["fleet"]

fleet = click.Group(
    "fleet",
    help="Many robots at once on Dask (a local cluster, or --scheduler tcp://host:8786): calibrate a fleet, "
         "run studies, list the robots that need attention (docs/fleet.md).",
    context_settings={"help_option_names": ["-h", "--help"]},
)

def _security_option(name, metavar, help_text):
    def store(ctx, _param, value):
        ctx.meta.setdefault("robocal_tls", {})[name] = value
        return value
    return click.option(f"--{name.replace('_', '-')}" if name != "security_file" else "--security", metavar=metavar,
                        default=None, type=click.Path(dir_okay=False), expose_value=False, callback=store,
                        help=help_text)


def _SCHEDULER(f):
    """--scheduler and its TLS options (stored in the context, read by :func:`_client`)."""
    for opt in reversed([
        click.option("--scheduler", default=None, metavar="ADDRESS",
                     help="An existing Dask cluster's scheduler (tcp://host:8786, or tls://host:8786 with the TLS "
                          "options); default: a local cluster. The scheduler and its workers must be trusted "
                          "(docs/fleet.md, 'Trust boundary')."),
        _security_option("tls_ca_file", "PEM", "TLS: the cluster's certificate authority (with --scheduler tls://...)."),
        _security_option("tls_cert", "PEM", "TLS: this client's certificate."),
        _security_option("tls_key", "PEM", "TLS: this client's private key (unless the certificate file holds it)."),
        _security_option("security_file", "FILE", "TLS settings as a TOML file: [tls] ca_file, cert, key."),
    ]):
        f = opt(f)
    return f
_WORKERS = click.option("--workers", type=int, default=None, metavar="N",
                        help="Worker processes of the local cluster (default: one per CPU).")


def _client(scheduler, workers):
    from ..workflows.fleet.cluster import FleetClusterError, fleet_client, tls_security

    tls = click.get_current_context().meta.get("robocal_tls", {})
    try:
        security = tls_security(ca_file=tls.get("tls_ca_file"), cert=tls.get("tls_cert"), key=tls.get("tls_key"),
                                security_file=tls.get("security_file"))
        return fleet_client(scheduler, workers, security=security)
    except FleetClusterError as exc:
        raise click.ClickException(str(exc)) from None


def _db_for_workers(target, scheduler):
    """The history URL without its password (which goes to the local workers through the environment;
    a remote cluster's workers must have it from their own environment or a file)."""
    from ..store import PASSWORD_ENV, strip_credentials, url_password

    secret = url_password(target) if target else None
    if secret is None:
        return target
    if scheduler is not None:
        raise click.ClickException("--db: the URL carries a password, which would travel to the workers of --scheduler "
                                   "in clear task payloads: give the URL without it and set ROBOCAL_DB_PASSWORD (or "
                                   "ROBOCAL_DB_PASSWORD_FILE, a file readable on every worker) where the workers run")
    os.environ[PASSWORD_ENV] = secret  # inherited by the local cluster's worker processes, started next
    return strip_credentials(target)


def _history_target(db, no_history, out_dir):
    if no_history:
        return None
    from ..store import HISTORY_DB_ENV

    return db or os.environ.get(HISTORY_DB_ENV) or str(Path(out_dir) / "history.sqlite")


@fleet.command("calibrate")
@json_option
@click.argument("fleet_file", metavar="FLEET.toml", type=click.Path(dir_okay=False))
@click.option("--out", "out_dir", required=True, type=click.Path(file_okay=False),
              help="Folder for <id>/ per robot, summary.json, summary.html and summary.svg.")
@_SCHEDULER
@_WORKERS
@click.option("--db", default=None, metavar="PATH_OR_URL",
              help="History database every result is recorded in (default: $ROBOCAL_HISTORY_DB, else "
                   "OUT/history.sqlite).")
@click.option("--no-history", is_flag=True, help="Do not record the results in a history database.")
@click.option("--no-report", is_flag=True, help="No report.html per robot (the plots take longer than the solve).")
@click.option("--robots-per-task", "per_task", type=click.IntRange(min=1), default=None, metavar="N",
              help="Robots per Dask task, in fixed groups (default: each worker takes the next robot until "
                   "none is left, one long task per worker thread; progress every half second).")
@allow_unconverged_option
def calibrate_cmd(fleet_file, out_dir, scheduler, workers, db, no_history, no_report, per_task, allow_unconverged):
    """Calibrate every robot of FLEET.toml on a Dask cluster, each robot on its own.

    Writes OUT/<id>/ (the files of `robocal calibrate`), OUT/summary.json (status ok or failed with
    the reason, per robot), OUT/summary.html and .svg. Robots whose inputs are unchanged since an
    earlier run into OUT are skipped (content hash): a crashed run resumes. Exit code 3 when some
    robots failed (the last line counts them), 1 when all did; 4 when none failed but some fits did
    not converge (their robot files are not written) unless --allow-unconverged.
    """
    from ..workflows.fleet.calibrate import run_fleet_calibration
    from ..workflows.fleet.cluster import FleetClusterError

    target = _db_for_workers(_history_target(db, no_history, out_dir), scheduler)
    bar = None
    try:
        with _client(scheduler, workers) as client:
            label = f"robots ({len(client.scheduler_info().get('workers', {}))} workers)"
            with _progress_bar(label) as bar:
                def progress(done, total, row):
                    bar.length = total
                    bar.update(1)

                r = run_fleet_calibration(fleet_file, out_dir, client=client, db=target, report=not no_report,
                                          progress=progress, per_task=per_task, allow_unconverged=allow_unconverged)
    except (ValueError, KeyError, OSError, FleetClusterError) as exc:
        raise _user_error(exc) from None
    s = r["summary"]
    c = s["counts"]
    for row in s["robots"]:
        if row["status"] == "failed":
            click.echo(f"FAILED {row['id']}: {row['reason']}", err=True)
        elif row["status"] == "not converged":
            click.echo(f"not converged {row['id']}: {row['reason']}", err=True)
        elif row.get("outlier"):
            click.echo(f"outlier {row['id']}: accuracy after calibration {row.get('holdout_rms_after_mm')} mm "
                       f"(modified z {row.get('outlier_z')})", err=True)
    click.echo(f"{c['robots']} robots: {c['ok']} ok, {c['failed']} failed, {c['not_converged']} not converged, "
               f"{c['skipped']} unchanged (skipped), "
               f"{c['outliers']} outlier(s); {s['wall_seconds']:.1f} s")
    click.echo("wrote " + ", ".join(str(p) for p in r["files"].values())
               + (f"; history {s['history']}" if s["history"] else ""))
    set_json_result({**s, "files": r["files"]})
    _exit_on_failures([row for row in s["robots"] if row["status"] == "failed"], c["robots"])
    bad = [r for r in s["robots"] if r.get("converged") is False]
    if bad:
        from ..workflows.convergence import Convergence

        finish_convergence(Convergence(c["robots"], tuple(f"{r['id']}" for r in bad),
                                       "raise max_iterations in the fleet file's [options], or check those robots' "
                                       "measurements"), allow_unconverged)


def _exit_on_failures(failed, total) -> None:
    """Every robot failed: one ``Error:`` line, exit 1 (nothing usable). Some failed: a last
    ``Error:`` line counting them, exit 3. None: return."""
    if not failed:
        return
    if len(failed) == total:
        raise click.ClickException(f"all {total} robot(s) failed; the first: {failed[0]['id']}: {failed[0]['reason']}")
    click.echo(f"Error: {len(failed)} of {total} robots failed (reasons above)", err=True)
    sys.exit(EXIT_FAILED_RESULT)


@fleet.command("status")
@click.option("--db", required=True, metavar="PATH_OR_URL",
              help="History database: an SQLite file or a URL (postgresql+psycopg://user@host/db).")
@click.option("--max-age", "max_age_days", type=float, default=90.0, show_default=True, metavar="DAYS",
              help="A robot whose last calibration is older [days] is stale.")
@click.option("--distance-tolerance", "tolerance_mm", type=float, default=0.1, show_default=True, metavar="MM",
              help="Flag a length parameter whose drift trend since the first calibration exceeds this [mm].")
@click.option("--angle-tolerance", "tolerance_deg", type=float, default=0.01, show_default=True, metavar="DEG",
              help="Flag an angle parameter whose drift trend exceeds this [deg].")
@click.option("--kind", default="geometric_calibration", show_default=True,
              type=click.Choice(["geometric_calibration", "thermal_compensation", "tool_recalibration", "measurement"]),
              help="Which cycles count as calibrations.")
@click.option("--plots", "plot_dir", default="drift-plots", show_default=True, type=click.Path(file_okay=False),
              help="Folder for <robot>_drift.png per flagged robot.")
@click.option("--no-plots", is_flag=True, help="Write no drift plots.")
@click.option("--ap-tolerance", "ap_tolerance_mm", type=float, default=None, metavar="MM",
              help="Flag a robot whose ISO 9283 AP trend (worst pose, line through its tests, at now) exceeds this [mm].")
@click.option("--rp-tolerance", "rp_tolerance_mm", type=float, default=None, metavar="MM",
              help="Flag a robot whose ISO 9283 RP trend exceeds this [mm].")
@click.option("--at", "at_time", default=None, metavar="ISO_TIME",
              help="Judge ages and trends at this time (ISO 8601 with a zone, e.g. 2026-11-27T00:00Z) instead of now: "
                   "a result that does not depend on the day it is run.")
@click.option("--json", "as_json", is_flag=True, help="Print JSON instead of a table.")
def status_cmd(db, max_age_days, tolerance_mm, tolerance_deg, kind, plot_dir, no_plots, ap_tolerance_mm,
               rp_tolerance_mm, at_time, as_json):
    """Robots whose last calibration is older than --max-age, whose drift trend crosses the
    tolerance, whose ISO 9283 AP/RP trend crosses --ap-tolerance/--rp-tolerance or whose last
    verification was not ok, from the history database (SQLite or PostgreSQL); each robot's last
    verification is listed. Exit code 3 when any is flagged."""
    import json

    from ..store import HistoryError
    from ..store._validate import parse_time
    from ..workflows.fleet.status import fleet_status

    try:
        now = None if at_time is None else parse_time(at_time, "--at")
        r = fleet_status(db, max_age_days=max_age_days, tolerance_mm=tolerance_mm, tolerance_deg=tolerance_deg,
                         kind=kind, now=now, plot_dir=None if no_plots else plot_dir, ap_tolerance_mm=ap_tolerance_mm,
                         rp_tolerance_mm=rp_tolerance_mm)
    except (ValueError, OSError, HistoryError) as exc:
        raise _user_error(exc) from None
    if as_json:
        click.echo(json.dumps(r, indent=2))
    else:
        click.echo(f"{len(r['robots'])} robots in {r['database']}: {len(r['flagged'])} need attention "
                   f"(stale after {max_age_days:g} days; drift tolerance {tolerance_mm:g} mm, {tolerance_deg:g} deg)")
        for row in r["robots"]:
            state = ", ".join(s for s, on in (("STALE", row["stale"]), ("DRIFTING", row["drifting"]),
                                              ("ISO", row["performance_drifting"]),
                                              ("VERIFY", row["verification_failed"])) if on) or "ok"
            age = "-" if row["age_days"] is None else f"{row['age_days']:.1f} d"
            lv = row["last_verification"]
            ver = "-" if lv is None else f"{lv['time'][:10]} {lv['decision']}"
            click.echo(f"  {row['robot']:<24} {state:<16} calibrations {row['calibrations']:>3}  last {age:>9}"
                       f"  last verification {ver}")
            for reason in row["reasons"]:
                click.echo(f"      {reason}")
            if row.get("plot"):
                click.echo(f"      plot: {row['plot']}")
    if r["flagged"]:
        sys.exit(EXIT_FAILED_RESULT)


study = click.Group("study", help="Embarrassingly parallel studies as chunked Dask tasks (task overhead under 5 %): "
                                  "Monte-Carlo uncertainty of a pose plan, pose selection over candidate sets, "
                                  "thermal screening per robot.",
                    context_settings={"help_option_names": ["-h", "--help"]})
fleet.add_command(study)


def _write_json(data, out_file, overwrite: bool = False):
    import json

    from ..io.atomic import atomic_write_text

    if out_file:
        atomic_write_text(out_file, json.dumps(data, indent=2) + "\n", overwrite=overwrite)
        click.echo(f"wrote {out_file}")


_OVERWRITE = click.option("--overwrite", is_flag=True, help="Replace an existing --json file.")


def _check_json_out(out_file, inputs, overwrite: bool) -> None:
    """Before a long study: the --json file is no input and, without --overwrite, does not exist."""
    from ..io.output_paths import check_outputs

    if out_file:
        try:
            check_outputs(out_file, inputs, overwrite=overwrite)
        except FileExistsError as exc:
            raise click.ClickException(str(exc)) from None


def _chunk_line(c):
    click.echo(f"{c['items']} items in {c['tasks']} tasks of {c['chunk_size']} on {c['workers']} workers: "
               f"{1e3 * c['item_seconds']:.1f} ms per item, {1e3 * c['task_overhead_seconds']:.1f} ms overhead per "
               f"task ({100 * c['overhead_share']:.1f} % of a task; limit {100 * c['max_overhead_share']:.0f} %); "
               f"{c['wall_seconds']:.1f} s")


def _progress_bar(label):
    from ._progress import Progress  # a bar on a terminal, a line every few seconds in a log

    return Progress(label, file=sys.stderr)


def _study(label, scheduler, workers, fn, *args, **kwargs):
    from ..workflows.fleet.cluster import FleetClusterError

    try:
        with _client(scheduler, workers) as client, _progress_bar(label) as bar:
            def progress(done, total, _row):
                bar.length = total
                bar.update(1)

            return fn(*args, client=client, progress=progress, **kwargs)
    except (ValueError, KeyError, OSError, FleetClusterError) as exc:
        raise _user_error(exc) from None


@study.command("monte-carlo")
@json_option
@click.argument("robot")
@click.argument("poses", type=click.Path(dir_okay=False))
@click.option("--samples", default=200, show_default=True, type=click.IntRange(1, 100_000),
              help="Virtual robots (each its own true parameters; at most 100,000).")
@click.option("--noise", "noise_mm", metavar="MM", default=0.02, show_default=True, type=click.FloatRange(0.0, min_open=True),
              help="Tracker noise per coordinate [mm], positive.")
@click.option("--check-poses", default=200, show_default=True, type=click.IntRange(1, 100_000),
              help="Random poses where each result is checked (at most 100,000).")
@click.option("--tool", type=POINT, default="0,0,100", show_default=True, metavar="X,Y,Z",
              help="Reflector in the flange frame [mm].")
@click.option("--seed", default=0, show_default=True, help="Seed of the virtual robots and their noise (integer).")
@click.option("--summary", "out_file", default=None, type=click.Path(dir_okay=False), help="Write every sample to this JSON file.")
@_OVERWRITE
@_SCHEDULER
@_WORKERS
def monte_carlo_cmd(robot, poses, samples, noise_mm, check_poses, tool, seed, out_file, overwrite, scheduler, workers):
    """Monte-Carlo accuracy of calibrating ROBOT from the pose plan POSES (a joint program, e.g. from
    `robocal plan-poses`): simulated robots measured at those poses, calibrated, checked against
    their truth."""
    from ..io.programs.joint_table import read_joint_program
    from ..workflows.fleet.study import monte_carlo_plan

    _check_json_out(out_file, {"POSES": poses, "ROBOT": robot}, overwrite)
    try:
        q = read_joint_program(poses, _robot_model(robot)).joints
    except (ValueError, OSError) as exc:
        raise _user_error(exc) from None
    r = _study("samples", scheduler, workers, monte_carlo_plan, robot, q, samples=samples, noise_mm=noise_mm,
               check_poses=check_poses, tool=tool, seed=seed)
    b, a = r["before"], r["after"]
    click.echo(f"{r['robot']}, {r['n_poses']} poses, {samples} virtual robots, {noise_mm} mm noise: position error "
               f"at {check_poses} other poses [mm]")
    click.echo(f"  nominal model     RMS median {_median(r['rms_before_mm']):.4f}  p95 {b['p95']:.4f}")
    click.echo(f"  calibrated model  RMS median {_median(r['rms_after_mm']):.4f}  p95 {a['p95']:.4f}  "
               f"max {a['max']:.4f}  (first-order prediction {r['predicted_model_std_mm']:.4f})")
    if r["unconverged_samples"]:
        click.echo(f"  {len(r['unconverged_samples'])} sample(s) stopped at the solver's iteration limit (kept): "
                   f"{r['unconverged_samples'][:10]}")
    _chunk_line(r["chunking"])
    _write_json(r, out_file, overwrite)
    set_json_result(r)


def _median(v):
    import statistics

    return statistics.median(v)


def _robot_model(robot):
    from ._common import _robot

    return _robot(robot)


@study.command("pose-sets")
@json_option
@click.argument("robot")
@click.option("--sets", default=100, show_default=True, type=click.IntRange(1, 100_000),
              help="Candidate sets (seeds SEED .. SEED+SETS-1; at most 100,000).")
@click.option("--count", default=40, show_default=True, type=click.IntRange(1, 10_000), help="Poses per plan (at most 10,000).")
@click.option("--candidates", default=800, show_default=True, type=click.IntRange(1, 200_000),
              help="Random candidate poses per set (at most 200,000).")
@click.option("--noise", "sigma_mm", metavar="MM", default=0.02, show_default=True, type=click.FloatRange(0.0, min_open=True),
              help="Instrument noise per coordinate [mm], positive.")
@click.option("--tool", type=POINT, default="0,0,100", show_default=True, metavar="X,Y,Z",
              help="Reflector in the flange frame [mm].")
@click.option("--seed", default=0, show_default=True, help="Seed of the first candidate set; the others follow (integer).")
@click.option("--summary", "out_file", default=None, type=click.Path(dir_okay=False), help="Write every set to this JSON file.")
@_OVERWRITE
@_SCHEDULER
@_WORKERS
def pose_sets_cmd(robot, sets, count, candidates, sigma_mm, tool, seed, out_file, overwrite, scheduler, workers):
    """Plan COUNT poses of ROBOT from each of SETS candidate sets; report the best seed
    (`robocal plan-poses --seed <best>` writes that plan)."""
    from ..workflows.fleet.study import pose_set_selection

    _check_json_out(out_file, {"ROBOT": robot}, overwrite)
    r = _study("sets", scheduler, workers, pose_set_selection, robot, sets=sets, count=count, candidates=candidates,
               sigma_mm=sigma_mm, tool=tool, seed=seed)
    s, best = r["spread_mm"], r["best"]
    click.echo(f"{r['robot']}: {sets} candidate sets of {candidates}, {count} poses each; predicted workspace accuracy "
               f"(model error over the working range, noise-free criterion) min {s['min']:.4f} / median "
               f"{s['median']:.4f} / max {s['max']:.4f} mm")
    click.echo(f"best: seed {best['seed']} ({best['workspace_model_std_mm']:.4f} mm): robocal plan-poses {robot} "
               f"--count {count} --candidates {candidates} --seed {best['seed']} --out poses.csv")
    n_within = len(r["within_noise"])
    if r["differences_within_noise"]:
        click.echo(f"differences within noise: {n_within} of {sets} sets, the median among them, are within one "
                   f"campaign's spread of the best (+{100 * best['relative_spread']:.0f} %, up to "
                   f"{r['noise_band_mm']:.4f} mm): the choice among them is noise")
    else:
        click.echo(f"{n_within} of {sets} sets within one campaign's spread of the best (+{100 * best['relative_spread']:.0f} %); "
                   "the best is better than the median beyond noise")
    _chunk_line(r["chunking"])
    _write_json(r, out_file, overwrite)
    set_json_result(r)


@study.command("thermal")
@json_option
@click.argument("runs", nargs=-1, required=True, type=click.Path(file_okay=False))
@click.option("--keep", "n_keep", default=8, show_default=True, help="Parameters to keep per robot.")
@click.option("--summary", "out_file", default=None, type=click.Path(dir_okay=False), help="Write the results to this JSON file.")
@_OVERWRITE
@_SCHEDULER
@_WORKERS
def thermal_cmd(runs, n_keep, out_file, overwrite, scheduler, workers):
    """Thermal parameter screening (`robocal thermal screen`) of each robot's run folder RUNS
    (the robot id is the folder name), one task per robot. Exit code 3 when some robots failed, 1
    when all did."""
    from ..workflows.fleet.study import thermal_screening

    _check_json_out(out_file, {}, overwrite)
    r = _study("robots", scheduler, workers, thermal_screening, [(Path(d).name, d) for d in runs], n_keep=n_keep)
    for row in r["robots"]:
        if row["status"] == "ok":
            lam = row["lambda_percent"]
            click.echo(f"{row['id']}: {', '.join(row['selected'])}  lambda screened {lam.get('screened', float('nan')):.1f} %")
        else:
            click.echo(f"FAILED {row['id']}: {row['reason']}", err=True)
    _write_json(r, out_file, overwrite)
    set_json_result(r)
    _exit_on_failures([row for row in r["robots"] if row["status"] != "ok"], len(r["robots"]))
