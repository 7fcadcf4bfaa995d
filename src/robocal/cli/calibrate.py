"""``robocal calibrate`` and ``robocal correct``: geometric calibration from a measurement file, and
corrected joint targets for a nominal-model controller."""

from __future__ import annotations

import sys

import click

from ._common import EXIT_FAILED_RESULT, _names, _report_verdict, _step_printer, _user_error


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
@click.option("--seed", default=0, show_default=True, help="Seed of the calibration/held-out split.")
@click.option("--loss", type=click.Choice(["linear", "huber", "cauchy"]), default="linear", show_default=True,
              help="Loss per pose (huber/cauchy down-weight outlier poses).")
@click.option("--sigma", "sigma_mm", type=float, default=None,
              help="Measurement noise per coordinate [mm] (default: estimated from the residuals).")
@click.option("--tool", nargs=3, type=float, default=None, metavar="X Y Z",
              help="Initial target point in the flange frame [mm] (default 0 0 0).")
@click.option("--overwrite", is_flag=True, help="Replace existing output files.")
@click.option("--force", is_flag=True,
              help="Write the calibrated robot files even when the result fails the sanity gates (exit code 3).")
@click.option("--drop-duplicates", is_flag=True,
              help="Drop repeated pose ids and repeated rows (keeping the first) instead of refusing the file.")
def calibrate(robot, data, out_dir, free, free_all, fix, holdout, seed, loss, sigma_mm, tool, overwrite, force,
              drop_duplicates):
    """Calibrate ROBOT (name or robot file) from the measurement file DATA."""
    from ..workflows.calibrate import run_calibration

    try:
        r = run_calibration(robot, data, out_dir, free=_names(free) or None, free_all=free_all, fix=_names(fix),
                            holdout=holdout, seed=seed, loss=loss, sigma_mm=sigma_mm, tool=tool, overwrite=overwrite,
                            progress=_step_printer, force=force,
                            drop_duplicates=drop_duplicates)
    except (ValueError, KeyError, OSError) as exc:
        raise _user_error(exc) from None
    res = r["result"]
    click.echo(r["calibration_result"].summary())
    click.echo("")
    click.echo(f"{'position error [mm]':<30}{'RMS':>9}{'mean':>9}{'p95':>9}{'max':>9}")
    rows = [("calibration poses, before", res["residuals"]["before"]),
            ("calibration poses, after", res["residuals"]["after"])]
    if res.get("validation"):
        rows += [("held-out poses, before", res["validation"]["before"]),
                 ("held-out poses, after", res["validation"]["after"])]
    for label, s in rows:
        click.echo(f"{label:<30}{s['rms']:9.4f}{s['mean']:9.4f}{s['p95']:9.4f}{s['max']:9.4f}")
    for note in r["notes"]:
        click.echo(f"note: {note}")
    click.echo("wrote " + ", ".join(str(p) for p in r["files"].values()))
    if not r["verdict"].ok:
        _report_verdict(r["verdict"])
        sys.exit(EXIT_FAILED_RESULT)


@click.command()
@click.argument("robot_file")
@click.argument("targets", type=click.Path(dir_okay=False))
@click.option("--out", "out_file", required=True, type=click.Path(dir_okay=False),
              help="CSV file for the corrected joint targets.")
@click.option("--nominal", default=None,
              help="Nominal robot the controller runs (default: the robot named in ROBOT_FILE).")
@click.option("--frame", type=click.Choice(["world", "base"]), default=None,
              help="Frame of the targets (default: the targets file's '# frame:', else world).")
@click.option("--overwrite", is_flag=True, help="Replace an existing output file.")
def correct(robot_file, targets, out_file, nominal, frame, overwrite):
    """Corrected joint targets: joints that put the calibrated ROBOT_FILE on the Cartesian TARGETS.

    TARGETS is a CSV file (robocal-targets/1): header lines '# format: robocal-targets/1',
    '# length_unit: mm|m', '# angle_unit: deg|rad', optional '# orientation: <convention>' and
    '# frame: world|base', then columns name,x,y,z[,rx,ry,rz | qw,qx,qy,qz][,<controller joints>]
    (joints: taught values that seed the solver).
    """
    from ..workflows.calibrate import run_correct

    try:
        r = run_correct(robot_file, targets, out_file, nominal=nominal, frame=frame, overwrite=overwrite)
    except (ValueError, KeyError, OSError) as exc:
        raise _user_error(exc) from None
    c = r["corrected"]
    click.echo(c.summary())
    bad = [n for n, ok in zip(r["names"], c.converged) if not ok]
    if bad:
        click.echo(f"not reached: {', '.join(bad)} (see the status column)", err=True)
    click.echo(f"wrote {r['file']}")
    if bad:
        sys.exit(2)

