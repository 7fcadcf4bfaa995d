"""``robocal thermal ...``: thermal drift compensation commands (thesis ch. 3 and 5.1; docs/thermal.md).

Registered in ``robocal.cli`` with ``main.add_command(thermal)``. Thin: parse, call
:mod:`robocal.workflows.thermal.commands`, print. Files are described in
docs/thermal.md ("Command line"); inside, lengths are mm and angles rad, printed angles are
labelled. Every user error ends in one line ``Error: ...`` and a non-zero exit code; progress
lines go to stderr.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import click
import numpy as np

from ._common import _names, _user_error as _fail, _step_printer as _progress, allow_unconverged_option, finish_convergence
from ._grammar import OPTIONAL_ROBOT, OptionalRobotCommand

__all__ = ["thermal"]

thermal = click.Group(
    "thermal",
    help="Thermal drift compensation: sensor/sphere system calibration, parameter screening, online "
         "compensation of a taught program, and a simulated thermal cell (see docs/thermal.md).",
    context_settings={"help_option_names": ["-h", "--help"]},
)

FILE = click.Path(path_type=str)   # existence and kind are checked by the readers (one-line errors)
_USER_ERRORS = (ValueError, KeyError, OSError)


def _call(workflow, *args, **kwargs) -> dict:
    """``workflow(*args, **kwargs)``; a user error (file, value, name) ends in one line ``Error: ...``."""
    try:
        return workflow(*args, **kwargs)
    except _USER_ERRORS as exc:
        raise _fail(exc) from None


def _echo_json(res) -> None:
    """Print a workflow's result as JSON, without its display-only ``_`` keys."""
    from ..calib.outputs import json_ready

    click.echo(json.dumps(json_ready({k: v for k, v in res.items() if not k.startswith("_")}), indent=2))


def _v(a, fmt="{:.4f}") -> str:
    return "(" + ", ".join("nan" if not np.isfinite(x) else fmt.format(float(x)) for x in np.ravel(a)) + ")"


def _matrix(T, indent="  "):
    for row in np.asarray(T):
        click.echo(indent + " ".join(f"{x:14.6f}" for x in row))


# ---------------------------------------------------------------------------------------------- simulate
@thermal.command("simulate", short_help="Simulate the thermal cell: three heating runs as measurement files.")
@click.option("--seed", default=2024, show_default=True, help="Seed of the cell (true robot, sensors, poses) and runs.")
@click.option("--schedule-seed", default=7, show_default=True, help="Seed of the three production schedules.")
@click.option("--cycles", "n_cycles", default=90, show_default=True, type=click.IntRange(1, 100_000),
              help="Production cycles (~3 min) per run (at most 100,000).")
@click.option("--sphere-poses", "n_sphere", default=20, show_default=True,
              help="Sphere poses measured per cycle (the screening set).")
@click.option("--out", "out_dir", required=True, type=click.Path(path_type=str, file_okay=False),
              help="Folder for run1/, run2/, run3/ and program.csv (created if needed).")
@click.option("--preset", type=click.Choice(["ideal", "realistic"]), default="realistic", show_default=True,
              help="Effects outside the compensation model: realistic (hall, bent links, backlash, noise growing "
                   "with distance, outliers, two-speed heating) or ideal (none); docs/thermal.md 'Realism'.")
@click.option("--overwrite", is_flag=True, help="Replace existing files.")
@click.option("--json", "as_json", is_flag=True, help="Print JSON.")
def simulate_cmd(seed, schedule_seed, n_cycles, n_sphere, preset, out_dir, overwrite, as_json):
    """Simulate the thermal cell (KR150 R3100) heating in production: three runs of N cycles
    (run 1 for screening, runs 2 and 3 with other schedules for evaluation), written as
    measurement files with the hidden truth.

    \b
    OUT/runK/: sphere_cold.csv, sphere.csv (fixed stereo sensor, sphere centres, frame 'sensor'),
      monitor_cold.csv, monitor.csv (robot-held sensor, 34 car-body points), cycles.csv,
      setup.json (robot-held sensor on the flange), truth.json (the cell and the true drifts);
    OUT/program.csv: a taught program (the 34 monitored poses, robocal-program/1).
    """
    from ..workflows.thermal.commands import simulate_thermal_cell

    res = _call(simulate_thermal_cell, out_dir, seed=seed, schedule_seed=schedule_seed, n_cycles=n_cycles,
                n_sphere=n_sphere, preset=preset, overwrite=overwrite, progress=_progress)
    if as_json:
        _echo_json(res)
        return
    _echo_simulated(res)


def _echo_simulated(res) -> None:
    """The console summary of ``simulate``: one row per run."""
    out = Path(res["program"]).parent
    click.echo(f"simulated thermal cell ({res['preset']}): {res['robot']}, seed {res['seed']}, "
               f"{res['sphere_poses']} sphere poses, {res['monitored_points']} monitored points, sphere noise "
               f"{res['_sphere_noise_mm']} mm")
    click.echo(f"{'run':>3}  {'role':<10} {'cycles':>6} {'hours':>6} {'TCP 3h mm':>10} {'TCP end mm':>10} "
               f"{'TCP max mm':>10}  folder")
    for r in res["runs"]:
        t3 = "-" if r["tcp_drift_3h_mm"] is None else f"{r['tcp_drift_3h_mm']:.3f}"
        click.echo(f"{r['run']:>3}  {r['role']:<10} {r['cycles']:>6} {r['hours']:>6.2f} {t3:>10} "
                   f"{r['tcp_drift_end_mm']:>10.3f} {r['tcp_drift_max_mm']:>10.3f}  {r['dir']}")
    click.echo("(TCP: flange drift at a reference pose; '-': the run is shorter than 3 h)")
    click.echo(f"wrote {out}/run1..run3 and {out / 'program.csv'}")


# ---------------------------------------------------------------------------------------------- calibrate-sensor
def _print_cal(cal, pose_ids):
    click.echo(f"{cal.method}: {cal.n_poses} poses, residual RMS {cal.rms_mm:.4f} mm, max "
               f"{np.linalg.norm(cal.residuals_mm, axis=1).max():.4f} mm"
               + ("" if cal.converged else f" (NOT converged: {cal.message})"))
    click.echo("T_sensor_base (robot base in the sensor frame; mm) =")
    _matrix(cal.T_sensor_base)
    click.echo(f"P_e (sphere centre on the flange)   {_v(cal.P_e)} mm")
    if np.all(np.isfinite(cal.std_P_e_mm)):
        click.echo(f"std rotation                        {_v(np.degrees(cal.std_rotation_rad), '{:.5f}')} deg")
        click.echo(f"std translation                     {_v(cal.std_translation_mm)} mm")
        click.echo(f"std P_e                             {_v(cal.std_P_e_mm)} mm")
    else:
        click.echo("std: none (the thesis's method has no statistical model)")
    if cal.R_raw is not None:
        click.echo(f"raw rotation |R R^T - I|_F          {cal.orthonormality_error:.3g}")
    r = np.linalg.norm(cal.residuals_mm, axis=1)
    if len(r) <= 30:
        click.echo("residual per pose (mm): " + ", ".join(f"{p} {x:.4f}" for p, x in zip(pose_ids, r)))


@thermal.command("calibrate-sensor", short_help="Sensor frame and sphere centre on the flange (thesis 3.3).")
@click.argument("robot")
@click.argument("sphere_file", type=FILE)
@click.option("--method", type=click.Choice(["lsq", "thesis", "both"]), default="lsq", show_default=True,
              help="lsq: nonlinear least squares with uncertainties; thesis: the penalty method (3-14 ... 3-19); "
                   "both: run both and compare (--out writes the least-squares result).")
@click.option("--noise", "sigma_mm", type=float, default=None, metavar="MM",
              help="Sensor noise per coordinate [mm] for the standard deviations (default: from the residuals).")
@click.option("--poses", "poses", multiple=True, metavar="IDS",
              help="Use only these pose ids (comma separated, shell patterns such as 'p0*'; repeatable).")
@click.option("--truth", "truth_file", type=FILE, default=None,
              help="JSON with T_sensor_base and P_e_mm (e.g. a simulated run's truth.json): print the errors.")
@click.option("--out", "out_file", type=FILE, default=None,
              help="Write the calibration as a JSON file (robocal-thermal-sensor/1) for 'robocal thermal compensate'.")
@click.option("--overwrite", is_flag=True, help="Replace an existing --out file.")
@click.option("--json", "as_json", is_flag=True, help="Print JSON.")
@allow_unconverged_option
def calibrate_sensor_cmd(robot, sphere_file, method, sigma_mm, poses, truth_file, out_file, overwrite, as_json,
                         allow_unconverged):
    """System calibration (thesis 3.3): the sensor frame T_sensor_base and the sphere centre P_e on
    the flange from N >= 5 poses.

    ROBOT: robot name or robot file (a calibrated robot makes the result more accurate).
    SPHERE_FILE: measurement file (robocal-measurements/1) of sphere centres in the sensor frame
    (columns pose, <joints>, x, y, z), e.g. a simulated run's sphere_cold.csv. Exit code 4 (and no
    --out file) when a fit did not converge, unless --allow-unconverged.
    """
    from ..calib.sanity import Verdict
    from ..workflows.convergence import Convergence
    from ..workflows.thermal.commands import calibrate_sensor
    from .tcp import _exit_if_failed

    res = _call(calibrate_sensor, robot, sphere_file, method=method, sigma_mm=sigma_mm, poses=poses,
                truth_file=truth_file, out_file=out_file, overwrite=overwrite, allow_unconverged=allow_unconverged)
    if as_json:
        _echo_json(res)
    else:
        _echo_sensor_calibration(res, truth_file)
    _exit_if_failed(Verdict(tuple(res["reasons"])))
    finish_convergence(Convergence.from_dict(res["convergence"]), allow_unconverged)


def _echo_sensor_calibration(res, truth_file) -> None:
    """The console report of ``calibrate-sensor``: every method, the comparison, the errors."""
    click.echo(f"system calibration of {res['robot']} from {res['file']} ({len(res['pose_ids'])} poses)")
    for c in res["_calibrations"]:
        click.echo("")
        _print_cal(c, res["pose_ids"])
    if res["comparison"] is not None:
        click.echo("")
        d = res["comparison"]["difference"]
        click.echo(f"thesis vs least squares: rotation {d['rotation_deg']:.5f} deg, T_sensor_base translation "
                   f"{d['translation_mm']:.4f} mm, sensor origin {d['sensor_origin_mm']:.4f} mm, "
                   f"P_e {d['P_e_mm']:.4f} mm")
    if res["errors"]:
        _echo_frame_errors(res["errors"], truth_file)
    if res["note"]:
        click.echo(f"note: {res['note']}")
    if res["out"]:
        click.echo(f"wrote {res['out']} ({res['results'][0]['method']})")


def _echo_frame_errors(errors, truth_file) -> None:
    click.echo("")
    click.echo(f"errors against {truth_file}:")
    click.echo(f"  {'method':<15} {'rotation deg':>12} {'volume mm':>10} {'P_e mm':>9} {'t_sb mm':>9}")
    for k, e in errors.items():
        click.echo(f"  {k:<15} {e['rotation_deg']:>12.5f} {e['at_point_mm']:>10.4f} {e['P_e_mm']:>9.4f} "
                   f"{e['translation_mm']:>9.4f}")
    click.echo("  (volume: the frame's position error at the centre of the measured sphere positions; t_sb: "
               "translation of T_sensor_base, the base origin, far from the data)")


# ---------------------------------------------------------------------------------------------- screen
def _wrapped(prefix, text, width=110):
    """Echo ``prefix + text``, wrapping ``text`` at spaces, continuation lines indented under it."""
    line = prefix
    for word in text.split(" "):
        if len(line) + len(word) > width and line.strip() and len(line) > len(prefix):
            click.echo(line.rstrip())
            line = " " * len(prefix)
        line += word + " "
    click.echo(line.rstrip())


@thermal.command("screen", cls=OptionalRobotCommand, short_help="Screen the parameters to re-identify online (thesis 3.2, table 5-1).")
@click.argument("robot", **OPTIONAL_ROBOT)
@click.argument("run_dir", type=click.Path(path_type=str))
@click.option("--keep", "n_keep", default=8, show_default=True, help="Parameters to keep.")
@click.option("--threshold", "threshold_mm", default=0.1, show_default=True, metavar="MM",
              help="lambda: share of monitored directions with residual below this [mm].")
@click.option("--statistic", type=click.Choice(["rms", "max", "mean_abs"]), default="rms", show_default=True,
              help="How a direction's residual over the cycles is summarised.")
@click.option("--online-poses", "n_online", default=6, show_default=True,
              help="Sphere poses used online; lambda of the traditional and screened sets uses the best such subset.")
@click.option("--params", "params", multiple=True, metavar="NAMES",
              help="Do not screen: evaluate this parameter set on the run (e.g. the set screened on another run).")
@click.option("--sensor", "sensor_file", type=FILE, default=None,
              help="Sensor calibration JSON (calibrate-sensor --out); default: calibrated here from sphere_cold.csv.")
@click.option("--setup", "setup_file", type=FILE, default=None, help="Set-up JSON (default RUN_DIR/setup.json).")
@click.option("--json", "as_json", is_flag=True, help="Print JSON.")
def screen_cmd(run_dir, n_keep, threshold_mm, statistic, n_online, params, sensor_file, setup_file, robot, as_json):
    """Parameter screening (thesis 3.2, fig. 3-5, table 5-1) on a heating run.

    ROBOT: robot name or file (default: the robot the files name). RUN_DIR: a run directory as
    written by 'robocal thermal simulate' (sphere_cold.csv, sphere.csv,
    monitor_cold.csv, monitor.csv, cycles.csv, setup.json). Prints the elimination table (step,
    removed parameter, lambda, remaining set), the selected set, the best online sphere poses, and
    lambda before / traditional / screened on this run. With --params the given set is evaluated
    instead (table 5-2 on an evaluation run).
    """
    from ..workflows.thermal.commands import screen_run

    res = _call(screen_run, run_dir, n_keep=n_keep, threshold_mm=threshold_mm, statistic=statistic, n_online=n_online,
                params=_names(params), sensor_file=sensor_file, setup_file=setup_file, robot=robot,
                progress=_progress)
    if as_json:
        _echo_json(res)
        return
    _echo_screening(res)
    _echo_online(res, n_online)
    click.echo(f"use: robocal thermal compensate ... --params {','.join(res['selected'])}")


def _echo_screening(res) -> None:
    """The elimination table (or the given set) of ``screen``."""
    chosen = res["selected"]
    click.echo(f"sensor: {res['sensor']}")
    if res["mode"] == "screen":
        click.echo(f"parameter screening (table 5-1): {res['cycles']} cycles x {res['sphere_poses']} sphere poses, "
                   f"{res['monitored_directions']} monitored directions, lambda = share with {res['statistic']} "
                   f"residual < {res['threshold_mm']:g} mm")
        click.echo(f"{'step':>4} {'n':>3}  {'removed':<8} {'lambda %':>8}  remaining")
        for st in res["steps"]:
            _wrapped(f"{st['step']:>4} {st['n_params']:>3}  {st['removed']:<8} {st['lambda']:>8.2f}  ",
                     ", ".join(st["remaining"]))
        click.echo(f"selected ({len(chosen)}): {', '.join(chosen)}")
    else:
        click.echo(f"given set ({len(chosen)}): {', '.join(chosen)} on {res['cycles']} cycles x "
                   f"{res['sphere_poses']} sphere poses")


def _echo_online(res, n_online) -> None:
    """The online sphere poses and the lambda table of ``screen``."""
    label = "screened" if res["mode"] == "screen" else "given"
    lam, n_poses, statistic, threshold_mm = (res["lambda_percent"], res["sphere_poses"], res["statistic"],
                                             res["threshold_mm"])
    click.echo("")
    rows = [(f"{label} set", res["online_poses"]["screened"]), ("traditional set", res["online_poses"]["traditional"])]
    for name, p in rows:
        click.echo(f"online sphere poses ({n_online} of {n_poses}), {name + ':':<16} {', '.join(p)}")
    click.echo("")
    click.echo(f"lambda on this run [%] ({statistic} residual < {threshold_mm:g} mm, "
               f"{res['monitored_directions']} directions):")
    table = [("before compensation", lam["before"], ""),
             (f"traditional ({', '.join(res['traditional'])})", lam["traditional"], f"{n_online} online poses"),
             (f"{label} ({len(res['selected'])})", lam["screened"], f"{n_online} online poses"),
             (f"{label}, all {n_poses} poses", lam["screened_all_poses"], "")]
    w = max(len(t[0]) for t in table)
    for text, v, note in table:
        click.echo(f"  {text:<{w}}  {v:7.2f}" + (f"   ({note})" if note else ""))


# ---------------------------------------------------------------------------------------------- compensate
@thermal.command("compensate", short_help="Identify the drift from sphere poses and correct a taught program.")
@click.argument("robot")
@click.option("--sensor", "sensor_file", required=True, type=FILE,
              help="Sensor calibration JSON (calibrate-sensor --out): T_sensor_base, P_e_mm.")
@click.option("--sphere", "sphere_file", required=True, type=FILE,
              help="Measurement file of the current sphere centres (sensor frame), ~6 poses.")
@click.option("--poses", "poses", multiple=True, metavar="IDS",
              help="Use only these pose ids of --sphere (comma separated, shell patterns such as 'c020-*').")
@click.option("--cold", "cold_file", type=FILE, default=None,
              help="Cold reference: sphere measured when cold at the same joints (matched by joints). "
                   "Default: predicted by the robot model and the sensor calibration.")
@click.option("--params", "params", required=True, multiple=True, metavar="NAMES",
              help="Parameter deltas to identify, comma separated (e.g. the screened set: a1,a2,beta2,...).")
@click.option("--program", "program_file", required=True, type=FILE,
              help="Taught program (robocal-program/1): joints per point.")
@click.option("--out", "out_file", required=True, type=FILE, help="Corrected program file (robocal-program/1).")
@click.option("--overwrite", is_flag=True, help="Replace an existing --out file.")
@click.option("--position-only", is_flag=True, help="Correct the flange position only (default: full pose).")
@click.option("--noise", "sigma_mm", type=float, default=None, metavar="MM",
              help="Sensor noise per coordinate [mm] for the standard deviations (default: from the residuals).")
@click.option("--db", "history", is_flag=False, flag_value="", default=None, metavar="URL_OR_FILE",
              help="Record a thermal_compensation cycle in the history database (a path or URL; without a value: "
                   "$ROBOCAL_HISTORY_DB or robocal-history.sqlite).")
@click.option("--robot-id", "robot_id", default=None, help="Robot id in the history (default: the robot's name).")
@click.option("--json", "as_json", is_flag=True, help="Print JSON.")
@click.option("--force", is_flag=True,
              help="Write the corrected program even when the identification fails the sanity gates (exit code 3).")
def compensate_cmd(robot, sensor_file, sphere_file, poses, cold_file, params, program_file, out_file, overwrite,
                   position_only, sigma_mm, history, robot_id, as_json, force):
    """Online compensation: identify the given parameter deltas from the current sphere
    measurements (thesis (3-8)-(3-10)) and correct the joints of a taught program so the warm
    robot reaches the taught poses (iterative IK, <= 3 iterations).

    ROBOT: robot name or robot file (the cold model the program was taught on).
    """
    from ..calib.sanity import Verdict
    from ..workflows.thermal.commands import compensate_program_files
    from .tcp import _exit_if_failed

    res = _call(compensate_program_files, robot, sensor_file=sensor_file, sphere_file=sphere_file, poses=poses,
                cold_file=cold_file, params=_names(params), program_file=program_file, out_file=out_file,
                overwrite=overwrite, position_only=position_only, sigma_mm=sigma_mm, history=history,
                robot_id=robot_id, note=lambda text: click.echo(text, err=True), force=force)
    if as_json:
        _echo_json(res)
    else:
        _echo_drift(res)
        if res["out"] is not None:
            _echo_corrected(res)
    _exit_if_failed(Verdict(tuple(res["reasons"])))
    missed = [p["point"] for p in res["points"] if not p["converged"]]
    if res["out"] is not None and missed:  # as `robocal correct`: exit 5 when a corrected point is not reached
        from ._common import EXIT_TARGETS_NOT_REACHED

        click.echo(f"not reached: {', '.join(missed[:10])}" + (f" and {len(missed) - 10} more" if len(missed) > 10
                                                              else "") + " (the corrected joints did not converge within tolerance; see the table)",
                   err=True)
        raise SystemExit(EXIT_TARGETS_NOT_REACHED)


def _echo_drift(res) -> None:
    """The identified deltas of ``compensate`` (angles in deg)."""
    from ..workflows.thermal.commands import format_delta

    params = res["parameters"]
    click.echo(f"drift identification: {len(params)} parameter(s) from {res['n_poses']} sphere poses "
               f"({res['equations']} equations), rank {res['rank']}, condition {res['condition_number']:.3g}"
               + ("" if res["cold"] else " (cold reference predicted)"))
    click.echo(f"  sphere residual RMS {res['residual_rms_before_mm']:.4f} mm before -> "
               f"{res['residual_rms_after_mm']:.4f} mm after")
    click.echo(f"  {'parameter':<10} {'delta':>16} {'std':>14}")
    for p in params:
        n, u, s = p["name"], p["unit"], p["std"]
        sd = "-" if s is None else (f"{math.degrees(s):.6f} deg" if u == "rad" else f"{s:.5f} {u}")
        click.echo(f"  {n:<10} {format_delta(u, p['delta']):>16} {sd:>14}")


def _echo_corrected(res) -> None:
    """The corrected program of ``compensate``: one row per point, the summary, the files."""
    click.echo(f"program {res['program']}: {len(res['points'])} points "
               f"({'position only' if res['position_only'] else 'position and orientation'})")
    click.echo(f"  {'point':<10} {'drift mm':>9} {'after mm':>9} {'max dq deg':>11} {'iter':>4}")
    for p in res["points"]:
        flag = "" if p["converged"] else "  not converged"
        flag += "" if p["within_limits"] else "  outside joint limits"
        click.echo(f"  {p['point']:<10} {p['drift_before_mm']:>9.4f} {p['residual_mm']:>9.1e} "
                   f"{p['max_joint_correction_deg']:>11.5f} {p['iterations']:>4}{flag}")
    click.echo("  (drift: predicted by the identified deltas at the taught joints; after: left on the warm model)")
    click.echo(res["_summary"])
    h = res["history"]
    click.echo(f"wrote {res['out']}" + ("" if h is None else f"; history cycle {h['cycle_id']} in {h['db']}"))


from .thermal_experiment import experiment_cmd  # noqa: E402  (registers 'robocal thermal experiment')

thermal.add_command(experiment_cmd)
