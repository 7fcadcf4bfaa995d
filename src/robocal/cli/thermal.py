"""``robocal thermal ...``: thermal drift compensation commands (thesis ch. 3 and 5.1; docs/thermal.md).

Registered in ``robocal.cli`` with ``main.add_command(thermal)``. Thin over the library: parse,
call :mod:`robocal.thermal` / :mod:`robocal.sim.thermal`, print. Files are described in
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

__all__ = ["thermal"]

thermal = click.Group(
    "thermal",
    help="Thermal drift compensation: sensor/sphere system calibration, parameter screening, online "
         "compensation of a taught program, and a simulated thermal cell (see docs/thermal.md).",
    context_settings={"help_option_names": ["-h", "--help"]},
)

FILE = click.Path(path_type=str)   # existence and kind are checked by the readers (one-line errors)
_USER_ERRORS = (ValueError, KeyError, OSError)


def _fail(exc) -> click.ClickException:
    msg = exc.args[0] if isinstance(exc, KeyError) and exc.args else str(exc)
    return click.ClickException(" ".join(str(msg).split()))


def _progress(i, n, text):
    click.echo(f"[{i}/{n}] {text}", err=True)


def _robot(name):
    from ..robots import load_robot

    try:
        return load_robot(name)
    except _USER_ERRORS as exc:
        raise _fail(exc) from None


def _num(x):
    x = float(x)
    return x if math.isfinite(x) else None


def _list(a):
    return [_num(v) for v in np.ravel(a)]


def _clean(obj):
    """JSON-safe: NaN / inf -> null, numpy -> Python."""
    if isinstance(obj, dict):
        return {str(k): _clean(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_clean(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return _clean(obj.tolist())
    if isinstance(obj, (np.bool_, bool)):
        return bool(obj)
    if isinstance(obj, (np.integer, int)):
        return int(obj)
    if isinstance(obj, (np.floating, float)):
        return _num(obj)
    return obj


def _echo_json(obj) -> None:
    click.echo(json.dumps(_clean(obj), indent=2))


def _v(a, fmt="{:.4f}") -> str:
    return "(" + ", ".join("nan" if not np.isfinite(x) else fmt.format(float(x)) for x in np.ravel(a)) + ")"


def _matrix(T, indent="  "):
    for row in np.asarray(T):
        click.echo(indent + " ".join(f"{x:14.6f}" for x in row))


def _names(values):
    return [n for v in values for n in str(v).replace(",", " ").split()]


def _check_new(paths, overwrite):
    if overwrite:
        return
    for p in paths:
        if Path(p).exists():
            raise click.ClickException(f"{p}: file exists; pass --overwrite to replace it")


def _fmt_delta(name, unit, value):
    """A parameter delta for printing: mm as is, rad in deg."""
    if unit == "rad":
        return f"{math.degrees(value):+.6f} deg"
    return f"{value:+.5f} {unit}"


# ---------------------------------------------------------------------------------------------- simulate
@thermal.command("simulate", short_help="Simulate the thermal cell: three heating runs as measurement files.")
@click.option("--seed", default=2024, show_default=True, help="Seed of the cell (true robot, sensors, poses) and runs.")
@click.option("--schedule-seed", default=7, show_default=True, help="Seed of the three production schedules.")
@click.option("--cycles", "n_cycles", default=90, show_default=True, help="Production cycles (~3 min) per run.")
@click.option("--sphere-poses", "n_sphere", default=20, show_default=True,
              help="Sphere poses measured per cycle (the screening set).")
@click.option("--out", "out_dir", required=True, type=click.Path(path_type=str),
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
    from ..io.programs.joint_table import JointProgram, write_joint_program
    from ..io.thermal_files import write_setup_json
    from ..sim.robot import as_rng
    from ..sim.thermal import SPHERE_DIAMETER_MM, ThermalCell, standard_schedules, write_run

    if n_cycles < 2:
        raise click.ClickException(f"--cycles must be at least 2, got {n_cycles}")
    if n_sphere < 6:
        raise click.ClickException(f"--sphere-poses must be at least 6, got {n_sphere}")
    out = Path(out_dir)
    if out.exists() and not out.is_dir():
        raise click.ClickException(f"{out}: not a directory (--out is the folder for run1/, run2/, run3/)")
    run_files = ("sphere_cold.csv", "sphere.csv", "monitor_cold.csv", "monitor.csv", "cycles.csv", "truth.json",
                 "setup.json")
    _check_new([out / f"run{i}" / f for i in (1, 2, 3) for f in run_files] + [out / "program.csv"], overwrite)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise _fail(exc) from None
    _progress(1, 4, f"building the cell (seed {seed}, {n_sphere} sphere poses)")
    cell = ThermalCell.standard(seed, n_sphere_poses=n_sphere, preset=preset)
    run_seeds = as_rng(seed).integers(0, 2**31, 4)                     # as run_thermal_experiment
    schedules = standard_schedules(schedule_seed, n_cycles)
    rows = []
    try:
        for i, sch in enumerate(schedules):
            _progress(2 + i, 4, f"simulating run {i + 1} ({n_cycles} cycles) and writing {out / f'run{i + 1}'}")
            run = cell.simulate(sch, int(run_seeds[1 + i]))
            d = out / f"run{i + 1}"
            write_run(d, cell, run, overwrite=overwrite)
            write_setup_json(d / "setup.json", cell.model.name, cell.T_flange_sensor, SPHERE_DIAMETER_MM,
                             overwrite=overwrite)
            hours = sch.duration_s / 3600.0
            rows.append({"run": i + 1, "role": "screening" if i == 0 else "evaluation", "cycles": run.n_cycles,
                         "hours": hours,
                         "tcp_drift_3h_mm": float(np.interp(3 * 3600.0, run.timeline_s, run.tcp_drift_mm))
                         if hours >= 3.0 else None,
                         "tcp_drift_end_mm": float(run.tcp_drift_mm[-1]),
                         "tcp_drift_max_mm": float(run.tcp_drift_mm.max()), "dir": str(d)})
        prog = JointProgram(cell.q_monitor, tuple(f"P{k + 1:02d}" for k in range(len(cell.q_monitor))),
                       cell.model.controller_joints,
                       {"robot": cell.model.name, "angle_unit": "deg", "program": "car_body",
                        "note": "taught on the cold robot: the 34 monitored car-body poses of the simulated cell"})
        write_joint_program(out / "program.csv", prog, cell.model, overwrite=overwrite)
    except _USER_ERRORS as exc:
        raise _fail(exc) from None
    res = {"seed": seed, "schedule_seed": schedule_seed, "preset": preset, "robot": cell.model.name, "cycles": n_cycles,
           "sphere_poses": n_sphere, "monitored_points": len(cell.q_monitor), "runs": rows,
           "program": str(out / "program.csv")}
    if as_json:
        _echo_json(res)
        return
    click.echo(f"simulated thermal cell ({preset}): {cell.model.name}, seed {seed}, {n_sphere} sphere poses, "
               f"{len(cell.q_monitor)} monitored points, sphere noise {cell.sphere_noise_mm} mm")
    click.echo(f"{'run':>3}  {'role':<10} {'cycles':>6} {'hours':>6} {'TCP 3h mm':>10} {'TCP end mm':>10} "
               f"{'TCP max mm':>10}  folder")
    for r in rows:
        t3 = "-" if r["tcp_drift_3h_mm"] is None else f"{r['tcp_drift_3h_mm']:.3f}"
        click.echo(f"{r['run']:>3}  {r['role']:<10} {r['cycles']:>6} {r['hours']:>6.2f} {t3:>10} "
                   f"{r['tcp_drift_end_mm']:>10.3f} {r['tcp_drift_max_mm']:>10.3f}  {r['dir']}")
    click.echo("(TCP: flange drift at a reference pose; '-': the run is shorter than 3 h)")
    click.echo(f"wrote {out}/run1..run3 and {out / 'program.csv'}")


# ---------------------------------------------------------------------------------------------- calibrate-sensor
def _cal_dict(cal):
    return {"method": cal.method, "n_poses": cal.n_poses, "T_sensor_base": cal.T_sensor_base.tolist(),
            "T_base_sensor": cal.T_base_sensor.tolist(), "P_e_mm": cal.P_e.tolist(),
            "std": {"rotation_deg": _list(np.degrees(cal.std_rotation_rad)),
                    "translation_mm": _list(cal.std_translation_mm), "P_e_mm": _list(cal.std_P_e_mm)},
            "residual_rms_mm": cal.rms_mm,
            "residual_max_mm": float(np.linalg.norm(cal.residuals_mm, axis=1).max()),
            "residuals_mm": cal.residuals_mm.tolist(), "converged": bool(cal.converged),
            "orthonormality_error": float(cal.orthonormality_error)}


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
@click.option("--sigma", "sigma_mm", type=float, default=None,
              help="Sensor noise per coordinate [mm] for the standard deviations (default: from the residuals).")
@click.option("--poses", "poses", multiple=True, metavar="IDS",
              help="Use only these pose ids (comma separated, shell patterns such as 'p0*'; repeatable).")
@click.option("--truth", "truth_file", type=FILE, default=None,
              help="JSON with T_sensor_base and P_e_mm (e.g. a simulated run's truth.json): print the errors.")
@click.option("--out", "out_file", type=FILE, default=None,
              help="Write the calibration as JSON (robocal-thermal-sensor/1) for 'robocal thermal compensate'.")
@click.option("--overwrite", is_flag=True, help="Replace an existing --out file.")
@click.option("--json", "as_json", is_flag=True, help="Print JSON.")
def calibrate_sensor_cmd(robot, sphere_file, method, sigma_mm, poses, truth_file, out_file, overwrite, as_json):
    """System calibration (thesis 3.3): the sensor frame T_sensor_base and the sphere centre P_e on
    the flange from N >= 5 poses.

    ROBOT: robot name or robot file (a calibrated robot makes the result more accurate).
    SPHERE_FILE: measurement file (robocal-measurements/1) of sphere centres in the sensor frame
    (columns pose, <joints>, x, y, z), e.g. a simulated run's sphere_cold.csv.
    """
    from ..thermal import (
        calibrate_system,
        calibrate_system_thesis,
        compare_system_calibrations,
        frame_errors,
    )
    from ..calib.sanity import touchup_verdict
    from ..io.thermal_files import read_sphere_file, read_truth_json, write_sensor_json
    from .tcp import _exit_if_failed
    from ..workflows.thermal_inputs import select_poses

    model = _robot(robot)
    if sigma_mm is not None and not (sigma_mm > 0 and math.isfinite(sigma_mm)):
        raise click.ClickException(f"--sigma must be a positive number of mm, got {sigma_mm}")
    if out_file:
        _check_new([out_file], overwrite)
    try:
        meas = select_poses(read_sphere_file(sphere_file, model), poses, sphere_file)
        q, P = meas.joints, meas.points[:, 0]
        truth = None
        if truth_file:
            t = read_truth_json(truth_file)
            truth = {"T": t["T_sensor_base"], "P_e": t["P_e"]}
        comp = None
        if method == "both":
            comp = compare_system_calibrations(model, q, P, point_sigma_mm=sigma_mm,
                                               T_sensor_base_true=None if truth is None else truth["T"],
                                               P_e_true=None if truth is None else truth["P_e"])
            cals = [comp.least_squares, comp.thesis]
        elif method == "thesis":
            cals = [calibrate_system_thesis(model, q, P)]
        else:
            cals = [calibrate_system(model, q, P, point_sigma_mm=sigma_mm)]
        main_cal = cals[0]
        centre = None
        errors = {}
        if truth is not None:
            from ..thermal.system_calibration import _base_flange

            T = _base_flange(model, q)
            centre = (T[:, :3, :3] @ truth["P_e"] + T[:, :3, 3]).mean(axis=0)
            errors = {c.method: frame_errors(c.T_sensor_base, truth["T"], c.P_e, truth["P_e"], at_base=centre)
                      for c in cals}
        verdict = touchup_verdict(main_cal.rms_mm, main_cal.P_e, sigma_mm, what="system calibration")
        if out_file and verdict.ok:  # a failed calibration writes no sensor file (exit code 3)
            write_sensor_json(out_file, main_cal, model, sphere_file, overwrite=overwrite)
    except _USER_ERRORS as exc:
        raise _fail(exc) from None

    rms_note = None
    if main_cal.rms_mm > 0.1:
        rms_note = (f"residual RMS {main_cal.rms_mm:.3f} mm is well above a sphere sensor's noise (~0.02 mm): "
                    "the robot model's geometry errors are absorbed into T_sensor_base and P_e (harmless for drift "
                    "compensation, which uses differences; use a calibrated robot file for an accurate frame)")
    if as_json:
        d = {"robot": model.name, "file": sphere_file, "pose_ids": list(meas.pose_ids),
             "results": [_cal_dict(c) for c in cals], "errors": errors or None,
             "comparison": None if comp is None else {"difference": comp.difference, "table": comp.table()},
             "out": out_file if verdict.ok else None, "note": rms_note, "status": verdict.status,
             "reasons": list(verdict.reasons)}
        _echo_json(d)
        _exit_if_failed(verdict)
        return
    click.echo(f"system calibration of {model.name} from {sphere_file} ({meas.n_poses} poses)")
    for c in cals:
        click.echo("")
        _print_cal(c, meas.pose_ids)
    if comp is not None:
        click.echo("")
        d = comp.difference
        click.echo(f"thesis vs least squares: rotation {d['rotation_deg']:.5f} deg, T_sensor_base translation "
                   f"{d['translation_mm']:.4f} mm, sensor origin {d['sensor_origin_mm']:.4f} mm, "
                   f"P_e {d['P_e_mm']:.4f} mm")
    if errors:
        click.echo("")
        click.echo(f"errors against {truth_file}:")
        click.echo(f"  {'method':<15} {'rotation deg':>12} {'volume mm':>10} {'P_e mm':>9} {'t_sb mm':>9}")
        for k, e in errors.items():
            click.echo(f"  {k:<15} {e['rotation_deg']:>12.5f} {e['at_point_mm']:>10.4f} {e['P_e_mm']:>9.4f} "
                       f"{e['translation_mm']:>9.4f}")
        click.echo("  (volume: the frame's position error at the centre of the measured sphere positions; t_sb: "
                   "translation of T_sensor_base, the base origin, far from the data)")
    if rms_note:
        click.echo(f"note: {rms_note}")
    if out_file and verdict.ok:
        click.echo(f"wrote {out_file} ({main_cal.method})")
    _exit_if_failed(verdict)


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


@thermal.command("screen", short_help="Screen the parameters to re-identify online (thesis 3.2, table 5-1).")
@click.argument("run_dir", type=click.Path(path_type=str))
@click.option("--keep", "n_keep", default=8, show_default=True, help="Parameters to keep.")
@click.option("--threshold-mm", "threshold_mm", default=0.1, show_default=True,
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
@click.option("--robot", "robot", default=None, help="Robot name or file (default: the robot the files name).")
@click.option("--json", "as_json", is_flag=True, help="Print JSON.")
def screen_cmd(run_dir, n_keep, threshold_mm, statistic, n_online, params, sensor_file, setup_file, robot, as_json):
    """Parameter screening (thesis 3.2, fig. 3-5, table 5-1) on a heating run.

    RUN_DIR: a run directory as written by 'robocal thermal simulate' (sphere_cold.csv, sphere.csv,
    monitor_cold.csv, monitor.csv, cycles.csv, setup.json). Prints the elimination table (step,
    removed parameter, lambda, remaining set), the selected set, the best online sphere poses, and
    lambda before / traditional / screened on this run. With --params the given set is evaluated
    instead (table 5-2 on an evaluation run).
    """
    from ..thermal import calibrate_system
    from ..thermal.screening import (
        ScreeningProblem,
        screen_parameters,
        select_online_poses,
        traditional_parameters,
    )
    from ..io.thermal_files import read_sensor_json
    from ..workflows.thermal_inputs import load_run_dir

    if not (threshold_mm > 0 and math.isfinite(threshold_mm)):
        raise click.ClickException(f"--threshold-mm must be a positive number, got {threshold_mm}")
    given = _names(params)
    try:
        model = None if robot is None else _robot(robot)
        _progress(1, 3, f"reading {run_dir}")
        run = load_run_dir(run_dir, model, setup=setup_file)
        model = run["model"]
        if sensor_file:
            s = read_sensor_json(sensor_file, model)
            T_sb, P_e, sensor_src = s["T_sensor_base"], s["P_e"], sensor_file
        else:
            cal = calibrate_system(model, run["q_sphere"], run["sphere_cold"])
            T_sb, P_e = cal.T_sensor_base, cal.P_e
            sensor_src = f"calibrated from sphere_cold.csv ({cal.n_poses} poses, residual RMS {cal.rms_mm:.3f} mm)"
        prob = ScreeningProblem.from_measurements(model, T_sb, P_e, run["q_sphere"], run["sphere_cold"], run["sphere"],
                                                  run["q_monitor"], run["monitor_cold"], run["monitor"],
                                                  run["T_flange_sensor"], times_s=run["times_s"])
        if not 1 <= n_online <= prob.n_poses:
            raise ValueError(f"--online-poses must be in [1, {prob.n_poses}] (the run's sphere poses), got {n_online}")
        if given:
            for n in given:
                model.params.index(n)                                   # unknown names: suggestions
                if n not in prob.names:
                    raise ValueError(f"parameter {n!r} is fixed in {model.name!r} (not a screening candidate); "
                                     f"candidates: {', '.join(prob.names)}")
            if len(set(given)) != len(given):
                raise ValueError(f"--params names a parameter twice: {', '.join(given)}")
            res = None
            chosen = tuple(given)
            _progress(2, 3, f"evaluating the given set of {len(chosen)} on {prob.n_cycles} cycles")
        else:
            if not 1 <= n_keep <= len(prob.names):
                raise ValueError(f"--keep must be in [1, {len(prob.names)}] (the free parameters), got {n_keep}")
            _progress(2, 3, f"screening {len(prob.names)} -> {n_keep} parameters on {prob.n_cycles} cycles x "
                            f"{prob.n_poses} sphere poses")
            res = screen_parameters(prob, n_keep, threshold_mm=threshold_mm, statistic=statistic)
            chosen = res.selected
        _progress(3, 3, f"choosing {n_online} online sphere poses and evaluating")
        trad = traditional_parameters(model)
        sets = {"traditional": trad, "screened": chosen}
        online = {}
        for k, names in sets.items():
            if 3 * n_online < len(names):
                raise ValueError(f"--online-poses {n_online} gives {3 * n_online} equations, fewer than the "
                                 f"{len(names)} {k} parameters")
            online[k] = select_online_poses(prob, names, n_online)
        lam = {"before": prob.evaluate((), threshold_mm, statistic).lam}
        for k, names in sets.items():
            lam[k] = prob.with_poses(online[k]).evaluate(names, threshold_mm, statistic).lam
        lam["screened_all_poses"] = prob.evaluate(chosen, threshold_mm, statistic).lam
    except _USER_ERRORS as exc:
        raise _fail(exc) from None
    ids = run["sphere_ids"]
    out = {"run_dir": run_dir, "robot": model.name, "mode": "evaluate" if res is None else "screen",
           "cycles": prob.n_cycles, "sphere_poses": prob.n_poses, "monitored_directions": prob.n_directions,
           "threshold_mm": threshold_mm, "statistic": statistic, "sensor": sensor_src,
           "steps": [] if res is None else res.table(), "selected": list(chosen), "traditional": list(trad),
           "online_poses": {k: [ids[i] for i in v] for k, v in online.items()},
           "lambda_percent": lam}
    if as_json:
        _echo_json(out)
        return
    label = "screened" if res is not None else "given"
    click.echo(f"sensor: {sensor_src}")
    if res is not None:
        click.echo(f"parameter screening (table 5-1): {prob.n_cycles} cycles x {prob.n_poses} sphere poses, "
                   f"{prob.n_directions} monitored directions, lambda = share with {statistic} residual "
                   f"< {threshold_mm:g} mm")
        click.echo(f"{'step':>4} {'n':>3}  {'removed':<8} {'lambda %':>8}  remaining")
        for st in res.steps:
            _wrapped(f"{st.step:>4} {st.n_params:>3}  {st.removed or '-':<8} {st.lam:>8.2f}  ",
                     ", ".join(st.remaining))
        click.echo(f"selected ({len(chosen)}): {', '.join(chosen)}")
    else:
        click.echo(f"given set ({len(chosen)}): {', '.join(chosen)} on {prob.n_cycles} cycles x {prob.n_poses} "
                   f"sphere poses")
    click.echo("")
    rows = [(f"{label} set", out["online_poses"]["screened"]), ("traditional set", out["online_poses"]["traditional"])]
    for name, p in rows:
        click.echo(f"online sphere poses ({n_online} of {prob.n_poses}), {name + ':':<16} {', '.join(p)}")
    click.echo("")
    click.echo(f"lambda on this run [%] ({statistic} residual < {threshold_mm:g} mm, {prob.n_directions} directions):")
    table = [("before compensation", lam["before"], ""),
             (f"traditional ({', '.join(trad)})", lam["traditional"], f"{n_online} online poses"),
             (f"{label} ({len(chosen)})", lam["screened"], f"{n_online} online poses"),
             (f"{label}, all {prob.n_poses} poses", lam["screened_all_poses"], "")]
    w = max(len(t[0]) for t in table)
    for text, v, note in table:
        click.echo(f"  {text:<{w}}  {v:7.2f}" + (f"   ({note})" if note else ""))
    click.echo(f"use: robocal thermal compensate ... --params {','.join(chosen)}")


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
@click.option("--out", "out_file", required=True, type=FILE, help="Corrected program (robocal-program/1).")
@click.option("--overwrite", is_flag=True, help="Replace an existing --out file.")
@click.option("--position-only", is_flag=True, help="Correct the flange position only (default: full pose).")
@click.option("--sigma", "sigma_mm", type=float, default=None,
              help="Sensor noise per coordinate [mm] for the standard deviations (default: from the residuals).")
@click.option("--history", "history", is_flag=False, flag_value="", default=None, metavar="DB",
              help="Record a thermal_compensation cycle in the history database (a path or URL; without a value: "
                   "$ROBOCAL_HISTORY_DB or robocal-history.sqlite).")
@click.option("--robot-id", "robot_id", default=None, help="Robot id in the history (default: the robot's name).")
@click.option("--json", "as_json", is_flag=True, help="Print JSON.")
def compensate_cmd(robot, sensor_file, sphere_file, poses, cold_file, params, program_file, out_file, overwrite,
                   position_only, sigma_mm, history, robot_id, as_json):
    """Online compensation: identify the given parameter deltas from the current sphere
    measurements (thesis (3-8)-(3-10)) and correct the joints of a taught program so the warm
    robot reaches the taught poses (iterative IK, <= 3 iterations).

    ROBOT: robot name or robot file (the cold model the program was taught on).
    """
    import time

    from ..thermal import compensate_program, identify_drift
    from ..io.programs.joint_table import JointProgram, read_joint_program, write_joint_program
    from ..io.thermal_files import read_sensor_json, read_sphere_file
    from ..workflows.thermal_inputs import match_cold_reference, select_poses

    t_start = time.perf_counter()
    model = _robot(robot)
    if sigma_mm is not None and not (sigma_mm > 0 and math.isfinite(sigma_mm)):
        raise click.ClickException(f"--sigma must be a positive number of mm, got {sigma_mm}")
    names = _names(params)
    _check_new([out_file], overwrite)
    try:
        sensor = read_sensor_json(sensor_file, model)
        meas = select_poses(read_sphere_file(sphere_file, model), poses, sphere_file)
        q_s, P_w = meas.joints, meas.points[:, 0]
        P_c = None
        if cold_file:
            cold = read_sphere_file(cold_file, model, what="cold sphere")
            P_c = match_cold_reference(q_s, cold, cold_file, meas.pose_ids)
        else:
            click.echo("note: no --cold reference: the cold sphere positions are predicted by the model and the sensor "
                       "calibration (their errors enter the identified deltas)", err=True)
        program = read_joint_program(program_file, model)
        drift = identify_drift(model, sensor["T_sensor_base"], sensor["P_e"], q_s, P_w, P_c, names,
                               point_sigma_mm=sigma_mm)
        comp = compensate_program(model, drift, program.joints, position_only=position_only)
        elapsed = time.perf_counter() - t_start
        md = dict(program.metadata)
        md["note"] = ((md.get("note", "") + "\n") if md.get("note") else "") + (
            f"corrected for thermal drift by robocal thermal compensate from {Path(program_file).name}: "
            f"{', '.join(f'{n} {_fmt_delta(n, u, d)}' for n, u, d in zip(drift.names, drift.units, drift.delta))}")
        write_joint_program(out_file, JointProgram(comp.q, program.names, program.joint_names, md), model,
                            overwrite=overwrite)
    except _USER_ERRORS as exc:
        raise _fail(exc) from None

    corr_deg = np.degrees(np.abs(np.where(model.prismatic_joints, 0.0, comp.correction)).max(axis=1))
    points = [{"point": n, "drift_before_mm": float(b), "residual_mm": float(r), "rotation_residual_rad": float(rr),
               "max_joint_correction_deg": float(c), "correction": comp.correction[i].tolist(),
               "iterations": int(it), "converged": bool(ok), "within_limits": bool(wl)}
              for i, (n, b, r, rr, c, it, ok, wl) in enumerate(zip(
                  program.names, comp.drift_before_mm, comp.position_error_mm, comp.rotation_error_rad, corr_deg,
                  comp.iterations, comp.converged, comp.within_limits))]
    cycle_id = None
    db = None
    if history is not None:
        from ..store import HistoryError, HistoryStore, default_history_target

        db = history or default_history_target()
        rid = robot_id or model.name
        std = [None if not np.isfinite(s) else float(s) for s in drift.std]
        try:
            with HistoryStore.open(db) as store:
                with store.cycle(rid, "thermal_compensation", robot_model=model.name,
                                 notes="robocal thermal compensate",
                                 meta={"sensor": sensor_file, "sphere": sphere_file, "cold": cold_file,
                                       "program": program_file, "out": out_file, "position_only": position_only,
                                       "pose_ids": list(meas.pose_ids)}) as c:
                    c.add_measurements(q_s, P_w, target="sphere", sensor="fixed sensor",
                                       joint_units=["mm" if p else "rad" for p in model.prismatic_joints])
                    c.add_parameters(list(drift.names), drift.delta, units=list(drift.units),
                                     values=(model.params.values[[model.params.index(n) for n in drift.names]]
                                             + drift.delta).tolist(), std=std)
                    c.add_metrics({"residual_rms_before": (drift.rms_before_mm, "mm"),
                                   "residual_rms_after": (drift.rms_after_mm, "mm"),
                                   "condition_number": (float(drift.condition_number), "1"),
                                   "rank": (float(drift.rank), "1"),
                                   "n_poses": (float(drift.n_poses), "1"),
                                   "drift_before_max": (float(comp.drift_before_mm.max()), "mm"),
                                   "compensated_error_max": (float(comp.position_error_mm.max()), "mm"),
                                   "cycle_time": (float(elapsed), "s")})
                    c.add_corrections(comp.q_taught, comp.q, program=Path(program_file).stem,
                                      point_names=list(program.names),
                                      joint_units=["mm" if p else "rad" for p in model.prismatic_joints])
                cycle_id = c.id
        except (HistoryError, ValueError, OSError) as exc:
            raise click.ClickException(" ".join(f"{out_file} was written, but the history was not recorded: "
                                                f"{exc}".split())) from None

    res = {"robot": model.name, "sensor": sensor_file, "sphere": sphere_file, "cold": cold_file,
           "pose_ids": list(meas.pose_ids), "n_poses": drift.n_poses, "equations": 3 * drift.n_poses,
           "parameters": [{**row, "std": _num(row["std"])} for row in drift.table()],
           "rank": drift.rank, "condition_number": float(drift.condition_number),
           "singular_values": drift.singular_values.tolist(),
           "residual_rms_before_mm": drift.rms_before_mm, "residual_rms_after_mm": drift.rms_after_mm,
           "residuals_after_mm": drift.residuals_after_mm.tolist(),
           "program": program_file, "out": out_file, "position_only": position_only,
           "angle_unit_of_corrections": "rad", "points": points,
           "all_converged": comp.all_converged, "all_within_limits": bool(comp.within_limits.all()),
           "elapsed_s": elapsed, "history": None if db is None else {"db": str(db), "cycle_id": cycle_id}}
    if as_json:
        _echo_json(res)
        return
    click.echo(f"drift identification: {len(drift.names)} parameter(s) from {drift.n_poses} sphere poses "
               f"({3 * drift.n_poses} equations), rank {drift.rank}, condition {drift.condition_number:.3g}"
               + ("" if cold_file else " (cold reference predicted)"))
    click.echo(f"  sphere residual RMS {drift.rms_before_mm:.4f} mm before -> {drift.rms_after_mm:.4f} mm after")
    click.echo(f"  {'parameter':<10} {'delta':>16} {'std':>14}")
    for n, u, d, s in zip(drift.names, drift.units, drift.delta, drift.std):
        sd = "-" if not np.isfinite(s) else (f"{math.degrees(s):.6f} deg" if u == "rad" else f"{s:.5f} {u}")
        click.echo(f"  {n:<10} {_fmt_delta(n, u, d):>16} {sd:>14}")
    click.echo(f"program {program_file}: {len(program)} points "
               f"({'position only' if position_only else 'position and orientation'})")
    click.echo(f"  {'point':<10} {'drift mm':>9} {'after mm':>9} {'max dq deg':>11} {'iter':>4}")
    for p in points:
        flag = "" if p["converged"] else "  not converged"
        flag += "" if p["within_limits"] else "  outside joint limits"
        click.echo(f"  {p['point']:<10} {p['drift_before_mm']:>9.4f} {p['residual_mm']:>9.1e} "
                   f"{p['max_joint_correction_deg']:>11.5f} {p['iterations']:>4}{flag}")
    click.echo("  (drift: predicted by the identified deltas at the taught joints; after: left on the warm model)")
    click.echo(comp.summary())
    click.echo(f"wrote {out_file}" + ("" if cycle_id is None else f"; history cycle {cycle_id} in {db}"))


from .thermal_experiment import experiment_cmd  # noqa: E402  (registers 'robocal thermal experiment')

thermal.add_command(experiment_cmd)
