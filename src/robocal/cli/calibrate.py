"""``robocal calibrate`` and ``robocal correct``: geometric calibration from a measurement file, and
corrected joint targets for a nominal-model controller."""

from __future__ import annotations

import sys
from pathlib import Path

import click

from ._common import EXIT_TARGETS_NOT_REACHED, _names, _step_printer, _user_error, allow_unconverged_option
from .calibrate_table import parameter_table
from .calibrate_inputs import finish_calibration, import_options, read_export
from .swarm_progress import swarm_progress_bar


@click.command()
@click.argument("robot")
@click.argument("data", type=click.Path(dir_okay=False))
@click.option("--out", "out_dir", required=True, type=click.Path(file_okay=False),
              help="Folder for result.json, calibrated_robot.toml/.urdf and report.html (created if needed).")
@click.option("--free", "free", multiple=True, metavar="NAMES",
              help="Parameters to identify (comma separated, repeatable), e.g. --free a2,a3,theta2. "
                   "Default: every parameter the robot file does not list as fixed.")
@click.option("--free-all", is_flag=True,
              help="Identify every kinematic parameter (ignore the robot file's fixed lists).")
@click.option("--fix", "fix", multiple=True, metavar="NAMES",
              help="Parameters to hold at nominal (comma separated, repeatable).")
@click.option("--holdout", default=0.2, show_default=True, help="Fraction of poses held out for validation.")
@click.option("--seed", default=0, show_default=True,
              help="Seed of the calibration/held-out split and, with --method ipso|ipso+lm, of the swarm.")
@click.option("--method", type=click.Choice(["lm", "ipso", "ipso+lm"]), default="lm", show_default=True,
              help="Solver: Levenberg-Marquardt, the improved particle swarm (IPSO, box +-0.01 rad / +-0.5 mm "
                   "around the start), or IPSO then LM.")
@click.option("--particles", default=20, show_default=True, help="IPSO: swarm size.")
@click.option("--generations", default=2000, show_default=True, help="IPSO: number of generations.")
@click.option("--loss", type=click.Choice(["linear", "huber", "cauchy"]), default="linear", show_default=True,
              help="Loss per pose (huber/cauchy down-weight outlier poses).")
@click.option("--sigma", "sigma_mm", type=float, default=None,
              help="Measurement noise per coordinate [mm] (default: estimated from the residuals).")
@click.option("--tool", nargs=3, type=float, default=None, metavar="X Y Z",
              help="Initial target point in the flange frame [mm] (default 0 0 0).")
@click.option("--overwrite", is_flag=True, help="Replace existing output files.")
@click.option("--rotation-weight", "rotation_weight", type=float, default=None, metavar="MM_PER_RAD",
              help="6-D files: how many mm one rad of orientation error counts (default 100 mm/rad: "
                   "0.02 mm and 0.01 deg measurement noise weigh the same).")
@click.option("--no-orientation", is_flag=True, help="Ignore a file's orientation columns (position-only fit).")
@click.option("--prior", is_flag=True,
              help="A weak Gaussian prior on the geometry around nominal (sigma: --prior-sigma).")
@click.option("--prior-sigma", nargs=2, type=float, default=(1.0, 0.5), show_default=True, metavar="MM DEG",
              help="Sigma of the --prior for lengths [mm] and angles [deg].")
@click.option("--train-ids", multiple=True, metavar="IDS",
              help="Calibrate on these pose ids (comma separated, repeatable, or @FILE); default: seeded split.")
@click.option("--holdout-ids", multiple=True, metavar="IDS",
              help="Validate on these pose ids (comma separated, repeatable, or @FILE).")
@click.option("--max-iterations", default=1000, show_default=True,
              help="Iteration limit of the solver; a fit that stops there did not converge (exit 4). Elastic fits "
                   "of real robots need up to ~750.")
@allow_unconverged_option
@click.option("--no-report", is_flag=True, help="Do not write report.html (batch runs: the plots take longer than the solve).")
@click.option("--force", is_flag=True,
              help="Write the calibrated robot files even when the result fails the sanity gates (exit code 3).")
@click.option("--drop-duplicates", is_flag=True,
              help="Drop repeated pose ids and repeated rows (keeping the first) instead of refusing the file.")
@click.option("--elastic", type=click.Choice(["joint", "full"]), default=None,
              help="Identify joint compliance under gravity with the geometry (docs/elastic.md): the robot file's "
                   "mass model if it has one, else lumped gravity parameters; 'full' adds two lateral (bending) "
                   "compliances per joint.")
@click.option("--payload", default=None, metavar="KG@X,Y,Z",
              help="With --elastic: the payload carried during the measurements, mass [kg] @ centre of mass "
                   "[mm] in the flange frame.")
@import_options
def calibrate(robot, data, out_dir, free, free_all, fix, holdout, seed, method, particles, generations, loss, sigma_mm, tool, overwrite,
              rotation_weight, no_orientation, prior, prior_sigma, train_ids, holdout_ids, max_iterations,
              allow_unconverged, no_report, force, drop_duplicates, elastic, payload, **imp):
    """Calibrate ROBOT (name or robot file) from the measurement file DATA.

    DATA is robocal's measurement file, or with --format a tracker export paired with --joints.
    Orientation columns (rx, ry, rz or qw..qz) are used: a 6-D fit with a tool frame. Exit codes:
    0 done, 1 error, 3 the result failed the sanity gates (docs/reliability.md), 4 the solver did not
    converge (no calibrated robot file unless --allow-unconverged).
    """
    from ..workflows.calibrate import run_calibration

    try:
        meas = read_export(robot, data, imp)
        r = run_calibration(robot, data, out_dir, free=_names(free) or None, free_all=free_all, fix=_names(fix),
                            holdout=holdout, seed=seed, loss=loss, sigma_mm=sigma_mm, tool=tool, overwrite=overwrite,
                            progress=_step_printer, rotation_weight=rotation_weight, use_orientation=not no_orientation,
                            prior=prior_sigma if prior else None, train_ids=train_ids, holdout_ids=holdout_ids,
                            measurements=meas, max_iterations=max_iterations,
                            report=not no_report, force=force, drop_duplicates=drop_duplicates,
                            method=method, particles=particles, generations=generations,
                            swarm_progress=swarm_progress_bar(method, generations), elastic=elastic,
                            payload=payload, allow_unconverged=allow_unconverged)
    except (ValueError, KeyError, OSError) as exc:
        raise _user_error(exc) from None
    res = r["result"]
    click.echo(f"measurements: {r['description']}")
    summary = r["calibration_result"].summary().splitlines()
    for line in summary[:2] + [x for x in summary[2:] if "outlier" in x]:  # held parameters: in the table
        click.echo(line)
    click.echo("")
    for line in parameter_table(res):
        click.echo(line)
    click.echo("")
    click.echo(f"{'position error [mm]':<30}{'RMS':>9}{'mean':>9}{'p95':>9}{'max':>9}")
    rows = [("calibration poses, before", res["residuals"]["before"]),
            ("calibration poses, after", res["residuals"]["after"])]
    if res.get("validation"):
        rows += [("held-out poses, before", res["validation"]["before"]),
                 ("held-out poses, after", res["validation"]["after"])]
    for label, s in rows:
        click.echo(f"{label:<30}{s['rms']:9.4f}{s['mean']:9.4f}{s['p95']:9.4f}{s['max']:9.4f}")
    for row in res.get("elastic", {}).get("not_identifiable", []):
        if row["name"].startswith("compliance."):
            click.echo(f"not identifiable: {row['name']}: {row['why']}")
    for row in res.get("elastic", {}).get("not_identified", []):
        click.echo(f"not identified: {row['name']}: {row['why']}")
    finish_calibration(r, allow_unconverged)


@click.command()
@click.argument("robot_file")
@click.argument("targets", type=click.Path(dir_okay=False))
@click.option("--out", "out_file", required=True, type=click.Path(dir_okay=False),
              help="Corrected targets (CSV) or, for a robot program, the corrected program (a new file).")
@click.option("--nominal", default=None,
              help="Nominal robot the controller runs (default: the robot named in ROBOT_FILE).")
@click.option("--frame", type=click.Choice(["world", "base"]), default=None,
              help="Targets CSV only: frame of the targets (default: the file's '# frame:', else world).")
@click.option("--overwrite", is_flag=True, help="Replace existing output files.")
@click.option("--payload", default=None, metavar="KG@X,Y,Z",
              help="A robot file with an [elastic] section: compensate the deflection under this payload, mass [kg] "
                   "@ centre of mass [mm] in the flange frame (default: the robot's own weight only).")
def correct(robot_file, targets, out_file, nominal, frame, overwrite, payload):
    """Correct targets with the calibrated model ROBOT_FILE ("program filtering").

    TARGETS is a robot program (KRL .src/.dat, RAPID .mod, FANUC .ls, UR .script; decided by the
    suffix): the same program is written to --out with corrected targets, everything else
    unchanged, and a per-target report to <out>.report.csv. Or TARGETS is a CSV file
    (robocal-targets/1): header lines '# format: robocal-targets/1', '# length_unit: mm|m',
    '# angle_unit: deg|rad', optional '# orientation: <convention>' and '# frame: world|base', then
    columns name,x,y,z[,rx,ry,rz | qw,qx,qy,qz][,<controller joints>] (joints seed the solver).
    Exit code 2 when a target is not reached.
    """
    from ..io.programs import SUFFIXES

    if Path(targets).suffix.lower() in SUFFIXES:
        return _correct_program(robot_file, targets, out_file, nominal, frame, overwrite, payload)
    from ..workflows.calibrate import run_correct
    try:
        r = run_correct(robot_file, targets, out_file, nominal=nominal, frame=frame, overwrite=overwrite,
                        payload=payload)
    except (ValueError, KeyError, OSError) as exc:
        raise _user_error(exc) from None
    c = r["corrected"]
    click.echo(c.summary())
    bad = [n for n, ok in zip(r["names"], c.converged) if not ok]
    if bad:
        click.echo(f"not reached: {', '.join(bad)} (see the status column)", err=True)
    click.echo(f"wrote {r['file']}")
    if bad:
        sys.exit(EXIT_TARGETS_NOT_REACHED)



def _correct_program(robot_file, program, out_file, nominal, frame, overwrite, payload=None):
    from ..workflows.correct_program import run_correct_program

    if frame is not None:
        raise click.ClickException("--frame is for targets CSV files; program targets are in the robot base frame")
    try:
        r = run_correct_program(robot_file, program, out_file, nominal=nominal, overwrite=overwrite, payload=payload)
    except (ValueError, KeyError, OSError) as exc:
        raise _user_error(exc) from None
    click.echo(f"{'target':<14}{'kind':<10}{'status':<16}{'corr. [mm]':>11}{'[deg]':>9}{'joints [deg]':>13}")
    for row in r["rows"]:
        click.echo(f"{row['target']:<14}{row['kind']:<10}{row['status']:<16}{row['cartesian_correction_mm']:>11.4f}"
                   f"{row['orientation_correction_deg']:>9.4f}{row['max_joint_change_deg']:>13.4f}"
                   + (f"  {row['note']}" if row["note"] else ""))
    for s in r["skipped"]:
        click.echo(f"not read: line {s.line}: {s.reason}")
    click.echo(f"{r['n_corrected']}/{r['n_targets']} targets corrected; wrote {r['file']} and {r['report']}")
    if r["n_corrected"] < r["n_targets"]:
        sys.exit(EXIT_TARGETS_NOT_REACHED)
