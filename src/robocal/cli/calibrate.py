"""``robocal calibrate`` and ``robocal correct``: geometric calibration from a measurement file, and
corrected joint targets for a nominal-model controller."""

from __future__ import annotations

import math
import sys
from pathlib import Path

import click

from ._common import EXIT_TARGETS_NOT_REACHED, _names, _step_printer, _user_error, allow_unconverged_option
from .calibrate_table import parameter_table, statistics_table
from .calibrate_inputs import finish_calibration, import_options, read_export
from ._grammar import POINT
from ._json import json_option, set_json_result
from .simulate_execute import BASE_HELP, CONFIG_DAT_HELP, TOOL_HELP, frame_option
from .swarm_progress import swarm_progress_bar


@click.command()
@json_option
@click.argument("robot")
@click.argument("data", type=click.Path(dir_okay=False))
@click.option("--out", "out_dir", required=True, type=click.Path(file_okay=False),
              help="Folder for result.json, calibrated_robot.toml/.urdf and report.html (created if needed).")
@click.option("--free", "free", multiple=True, metavar="NAMES",
              help="Parameters to identify (comma separated, repeatable), e.g. --free a2,a3,theta2. "
                   "Default: every parameter the robot file does not list as fixed.")
@click.option("--free-all", is_flag=True,
              help="Identify every kinematic parameter (ignore the robot file's fixed lists).")
@click.option("--frames-only", is_flag=True,
              help="Hold the whole geometry; fit only the base (instrument) frame and the tool frame / target "
                   "points: a calibrated robot moved to a new cell.")
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
@click.option("--noise", "sigma_mm", type=float, default=None, metavar="MM",
              help="Measurement noise per coordinate [mm] (default: estimated from the residuals).")
@click.option("--tool", type=POINT, default=None, metavar="X,Y,Z",
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
def calibrate(robot, data, out_dir, free, free_all, frames_only, fix, holdout, seed, method, particles, generations, loss, sigma_mm, tool, overwrite,
              rotation_weight, no_orientation, prior, prior_sigma, train_ids, holdout_ids, max_iterations,
              allow_unconverged, no_report, force, drop_duplicates, elastic, payload, **imp):
    """Calibrate ROBOT (name or robot file) from the measurement file DATA.

    DATA is robocal's measurement file, or with --format a tracker export paired with --joints.
    Orientation columns (rx, ry, rz or qw..qz) are used: a 6-D fit with a tool frame. Exit codes:
    0 done, 1 error, 3 the result failed the sanity gates (docs/reliability.md), 4 the solver did not
    converge (no calibrated robot file unless --allow-unconverged).
    """
    from .. import CalibrationOptions, calibrate as calibrate_in_memory, load_robot
    from .._api.calibration import _read
    from ..workflows.calibration.calibrate import check_calibration_outputs
    from ..workflows.outputs import ensure_writable_dir

    def step(i, n, text):
        _step_printer(i, 5 if no_report else n, text)

    try:
        check_calibration_outputs(out_dir, overwrite=overwrite, report=not no_report,
                                  inputs={"ROBOT": robot, "DATA": data, "--joints": imp.get("joints_file")})
        meas = read_export(robot, data, imp)
        options = CalibrationOptions(
            free=tuple(_names(free)) if free else None, free_all=free_all, frames_only=frames_only, fix=tuple(_names(fix)), holdout=holdout, seed=seed,
            method=method, loss=loss, noise_mm=sigma_mm, tool_mm=tool, rotation_weight=rotation_weight,
            use_orientation=not no_orientation, prior_sigma=prior_sigma if prior else None, train_ids=train_ids,
            holdout_ids=holdout_ids, max_iterations=max_iterations, drop_duplicates=drop_duplicates,
            particles=particles, generations=generations, elastic=elastic, payload=payload)
        if meas is None:
            meas = _read(load_robot(robot), data, options, step)
        ensure_writable_dir(out_dir)  # before the long work
        result = calibrate_in_memory(robot, meas, options=options, progress=step,
                                     swarm_progress=swarm_progress_bar(method, generations), name=data)
        r = result._write(out_dir, overwrite=overwrite, report=not no_report, force=force, progress=step,
                          allow_unconverged=allow_unconverged)
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
    for row in (res.get("identifiability") or {}).get("parallel_axes", []):
        click.echo(f"parallel axes: {row['joints'][0]} || {row['joints'][1]} ({row['beta']} "
                   f"{'free' if row['beta_free'] else 'held'}: Hayati's tilt of the parallel pair)")
    click.echo("")
    rows = [("calibration poses, before", res["residuals"]["before"]),
            ("calibration poses, after", res["residuals"]["after"])]
    if res.get("validation"):
        rows += [("held-out poses, before", res["validation"]["before"]),
                 ("held-out poses, after", res["validation"]["after"])]
    for line in statistics_table("position error [mm]", rows):
        click.echo(line)
    orient = res.get("orientation")
    if orient:
        rows = [(f"{split} poses, {state}", orient[key][state])
                for key, split in (("train", "calibration"), ("holdout", "held-out")) if orient.get(key)
                for state in ("nominal", "baseline", "calibrated")]
        click.echo("")
        for line in statistics_table("orientation error [deg]", rows):
            click.echo(line)
    for row in res.get("elastic", {}).get("not_identifiable", []):
        if row["name"].startswith("compliance."):
            click.echo(f"not identifiable: {row['name']}: {row['why']}")
    for row in res.get("elastic", {}).get("not_identified", []):
        click.echo(f"not identified: {row['name']}: {row['why']}")
    set_json_result({**res, "files": r["files"]})
    finish_calibration(r, allow_unconverged)


@click.command()
@json_option
@click.argument("robot_file")
@click.argument("targets", type=click.Path(dir_okay=False))
@click.option("--out", "out_file", required=True, type=click.Path(dir_okay=False),
              help="Corrected targets (CSV) or, for a robot program, the corrected program (a new file).")
@click.option("--nominal", default=None,
              help="Nominal robot the controller runs (default: the robot named in ROBOT_FILE).")
@click.option("--frame", type=click.Choice(["world", "base"]), default=None,
              help="Targets CSV only: frame of the targets: world (the calibrated robot file's world = instrument frame) or base (the robot base frame); required when the file has no '# frame:' line.")
@click.option("--overwrite", is_flag=True, help="Replace existing output files.")
@click.option("--payload", default=None, metavar="KG@X,Y,Z",
              help="A robot file with an [elastic] section: compensate the deflection under this payload, mass [kg] "
                   "@ centre of mass [mm] in the flange frame (default: the robot's own weight only).")
@click.option("--tool", "tool", default=None, metavar="X,Y,Z[,A,B,C]", help="Programs: " + TOOL_HELP)
@click.option("--base", "base", default=None, metavar="X,Y,Z[,A,B,C]", help="Programs: " + BASE_HELP)
@click.option("--config-dat", type=click.Path(exists=True, dir_okay=False), default=None, help=CONFIG_DAT_HELP)
@click.option("--joint-targets", type=click.Choice(["keep", "correct"]), default="keep", show_default=True,
              help="Programs: keep taught joint targets (home positions...) or correct offline-generated ones "
                   "(never changing the arm configuration).")
@click.option("--max-joint-change", type=float, default=1.0, show_default=True, metavar="DEG",
              help="Programs with --joint-targets correct: the largest joint change allowed [deg].")
def correct(robot_file, targets, out_file, nominal, frame, overwrite, payload, tool, base, config_dat, joint_targets,
            max_joint_change):
    """Correct targets with the calibrated model ROBOT_FILE ("program filtering").

    TARGETS is a robot program (KRL .src/.dat, RAPID .mod, FANUC .ls, UR .script; decided by the
    suffix): the same program is written to --out with corrected targets, everything else
    unchanged, and a per-target report to <out>.report.csv. Or TARGETS is a CSV file
    (robocal-targets/1): header lines '# format: robocal-targets/1', '# length_unit: mm|m',
    '# angle_unit: deg|rad', optional '# orientation: <convention>' and '# frame: world|base', then
    columns name,x,y,z[,rx,ry,rz | qw,qx,qy,qz][,<controller joints>] (joints seed the solver).
    Programs: Cartesian targets are corrected on their own arm configuration (KUKA S/T, ABB confdata,
    FANUC CONFIG; UR: nearest the current joints) with the program's tool and base frames; taught
    joint targets are kept (--joint-targets correct changes offline ones). The report prints the
    joints each correction assumes and its predicted accuracy (1 sigma, from result.json next to
    ROBOT_FILE). Exit code 5 when a target is not reached.
    """
    from ..io.programs import SUFFIXES

    if Path(targets).suffix.lower() in SUFFIXES:
        return _correct_program(robot_file, targets, out_file, nominal, frame, overwrite, payload,
                                dict(tool=frame_option(tool, "tool"), base=frame_option(base, "base"),
                                     config_dat=None if config_dat is None else
                                     Path(config_dat).read_text(encoding="latin-1"),
                                     joint_targets=joint_targets, max_joint_change=math.radians(max_joint_change)))
    if tool is not None or base is not None or config_dat is not None:
        raise click.ClickException("--tool, --base and --config-dat are for robot programs; a targets CSV file "
                                   "gives its frame in '# frame:'")
    from ..workflows.calibration.calibrate import run_correct
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
    set_json_result({"file": r["file"], "frame": r["frame"], "nominal": r["nominal"], "not_reached": bad,
                     "targets": [dict(row, name=n) for n, row in zip(r["names"], c.report)]})
    if bad:
        sys.exit(EXIT_TARGETS_NOT_REACHED)



def _correct_program(robot_file, program, out_file, nominal, frame, overwrite, payload=None, options=None):
    from ..workflows.calibration.correct_program import UNKNOWN_TOLERANCE, run_correct_program

    if frame is not None:
        raise click.ClickException("--frame is for targets CSV files; program targets are in the robot base frame")
    try:
        r = run_correct_program(robot_file, program, out_file, nominal=nominal, overwrite=overwrite, payload=payload,
                                **(options or {}))
    except (ValueError, KeyError, OSError) as exc:
        raise _user_error(exc) from None
    click.echo(f"{'target':<16}{'kind':<10}{'status':<19}{'corr. [mm]':>11}{'[deg]':>8}{'sigma [mm]':>11}"
               f"  joints assumed [deg]")
    for row in r["rows"]:
        sig = "" if row["sigma_mm"] != row["sigma_mm"] else f"{row['sigma_mm']:.4f}"
        click.echo(f"{row['target']:<16}{row['kind']:<10}{row['status']:<19}{row['cartesian_correction_mm']:>11.4f}"
                   f"{row['orientation_correction_deg']:>8.4f}{sig:>11}  {row['joints_deg']}"
                   + (f"  ({row['note']})" if row["note"] else ""))
    for s in r["skipped"]:
        click.echo(f"not read: line {s.line}: {s.reason}")
    if r["warnings"]:
        worst = max(u for _, u in r["warnings"])
        names = ", ".join(n for n, _ in r["warnings"])
        points = ", ".join(f"{k} = ({', '.join(f'{v:.3f}' for v in p)})" for k, p in r["identified_points"].items())
        click.echo(f"Warning: the TCP of {names} depends on parameters the calibration could not determine "
                   f"({', '.join(r['unknown_parameters'])}): up to {worst:.3f} mm (1 sigma at "
                   f"{UNKNOWN_TOLERANCE['mm']} mm / {math.degrees(UNKNOWN_TOLERANCE['rad']):.2f} deg each) is unknown. "
                   f"Measure the actual tool (robocal tcp) or calibrate with reflectors at known places on the "
                   f"flange; or use an identified point as the tool: {points} [mm, flange frame].", err=True)
    if r["base_parameters"]:
        click.echo(f"note: targets are taken in the calibrated base frame ([base] of {robot_file}): "
                   f"{', '.join(r['base_parameters'])} cannot be told apart from the base placement, so the cell's "
                   "frames (base / work object) must be measured in that frame.")
    kept = sum(row["status"] == "kept" for row in r["rows"])
    click.echo(f"{r['n_corrected']}/{r['n_targets']} targets corrected, {kept} joint target(s) kept; "
               f"wrote {r['file']} and {r['report']}")
    set_json_result({k: r[k] for k in ("file", "report", "n_corrected", "n_targets", "rows") if k in r})
    if r["n_failed"]:
        click.echo(f"{r['n_failed']} target(s) not corrected (see the status column)", err=True)
        sys.exit(EXIT_TARGETS_NOT_REACHED)
