"""``robocal tcp cross-laser``, ``robocal tcp simulate`` (click commands, registered in the ``tcp``
group by :mod:`robocal.cli.main`) and ``robocal tcp accuracy``."""

from __future__ import annotations

import json
import math
from pathlib import Path

import click
import numpy as np

__all__ = ["cross_laser_cmd", "simulate_cmd", "accuracy_cmd"]

EVENTS_HELP = """Evaluate a recorded cross-laser recalibration (thesis 4.2, steps 1-4).

\b
EVENTS_FILE (format robocal-barrier-events/1, CSV, mm and s, base frame):
  # format: robocal-barrier-events/1
  # motion: {"id": 0, "t_start_s": 0.0, "duration_s": 2.1, "settle_s": 0.1, "kind": "circle",
  #          "step": 1, "role": "circle1", "center_mm": [x,y,z], "radius_mm": 25,
  #          "normal": [..], "ref_dir": [..], "start_angle_deg": 30, "sweep_deg": 570,
  #          "speed_mm_s": 120, "accel_mm_s2": 2000, "R_base_flange": [[..],[..],[..]]}
  # motion: {"id": 1, ..., "kind": "line", "role": "down", "start_mm": [..], "end_mm": [..],
  #          "R_start": [[..]], "R_end": [[..]], "speed_mm_s": 20, "angular_speed_deg_s": 90,
  #          "accel_mm_s2": 2000}
  motion,time_s,barrier,state,x_mm,y_mm,z_mm
  0,0.4310,y,blocked,-841.2,-160.3,395.0
One '# motion:' JSON header per executed motion (the controller program: circle = movec
about "normal" from "start_angle_deg" (0 = "ref_dir") through "sweep_deg", positive =
counter-clockwise about the normal, trapezoidal speed profile; line = movel), then one row per
barrier state change: the motion id, the controller time [s] of the I/O sample that showed it,
the barrier (x|y), the new state (blocked|clear) and the flange position the controller
reported then (mm, base frame; needed for the step-4 moves, may be nan elsewhere).
Required roles: circle1, circle2 (steps 1-2, same orientation, dz apart), circle3 (step 3,
axis re-aligned) and down, up (step 4 vertical moves). `robocal tcp simulate --out DIR`
writes such a file (DIR/events.csv).

SENSOR is the JSON of `robocal tcp calibrate-sensor --json` (keys T_base_sensor, beta_deg,
gap_mm used).
"""


def _load_json(path, what):
    try:
        return json.loads(Path(path).read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise click.ClickException(f"{path}: {what} file not found") from None
    except (OSError, ValueError) as exc:
        raise click.ClickException(f"{path}: cannot read {what} JSON: {exc}") from None


@click.command("cross-laser", help=EVENTS_HELP)
@click.argument("events_file", type=click.Path(dir_okay=False))
@click.option("--sensor", "sensor_file", required=True, type=click.Path(dir_okay=False),
              help="Sensor calibration JSON (output of `robocal tcp calibrate-sensor --json`).")
@click.option("--nominal-tool", "nominal_file", type=click.Path(dir_okay=False), default=None,
              help="JSON with key T_flange_tool (4x4, mm): the tool estimate before the recalibration; "
                   "default: a tool along the flange Z axis. Only its rotation is used (the 5-D update keeps "
                   "its twist about the axis).")
@click.option("--no-beta-correction", is_flag=True, help="Ignore beta (use the centre (d_y, d_x), thesis 4-30 error).")
@click.option("--no-arc-correction", is_flag=True, help="Use (4-9) with R instead of R cos(blocked arc / 2).")
@click.option("--orientation", "convention", default=None, metavar="CONVENTION", help="Also print the tool frame as a pose in this orientation "
                                                  "convention (e.g. kuka_abc, fanuc_wpr, quaternion).")
@click.option("--json", "as_json", is_flag=True, help="Print JSON.")
def cross_laser_cmd(events_file, sensor_file, nominal_file, no_beta_correction, no_arc_correction, convention, as_json):
    from ..io.barrier_events import read_events_csv
    from ..tcp.cross_laser import CrossLaserError, CrossLaserSettings, evaluate_recording

    try:
        records = read_events_csv(events_file)
    except ValueError as exc:
        raise click.ClickException(str(exc)) from None
    sensor = _load_sensor(sensor_file)
    T_nom = _load_nominal_tool(nominal_file)
    settings = CrossLaserSettings(beta_correction=not no_beta_correction, arc_correction=not no_arc_correction)
    try:
        res = evaluate_recording(records, sensor, T_nom, settings)
    except CrossLaserError as exc:
        raise click.ClickException(f"{events_file}: {exc}") from None
    out = _result_dict(res, convention)
    if as_json:
        click.echo(json.dumps(out, indent=2))
        return
    _echo_result(res, out, settings, sensor, convention)


def _load_sensor(sensor_file):
    """The sensor frame from a ``calibrate-sensor --json`` file (click errors name the file)."""
    from ..tcp.cross_laser import sensor_frame

    sd = _load_json(sensor_file, "sensor")
    try:
        return sensor_frame(sd)
    except (KeyError, ValueError, TypeError) as exc:
        raise click.ClickException(f"{sensor_file}: not a sensor calibration ({exc!s}); expected keys "
                                   "T_base_sensor, beta_deg, gap_mm") from None


def _load_nominal_tool(nominal_file) -> np.ndarray:
    """``T_flange_tool`` (4, 4) [mm] from the ``--nominal-tool`` JSON, or the identity."""
    T_nom = np.eye(4)
    if nominal_file:
        nd = _load_json(nominal_file, "nominal tool")
        try:
            T_nom = np.array(nd["T_flange_tool"], dtype=float).reshape(4, 4)
        except (KeyError, ValueError, TypeError) as exc:
            raise click.ClickException(f"{nominal_file}: expected key T_flange_tool with a 4x4 matrix ({exc!s})") from None
    return T_nom


def _result_dict(res, convention) -> dict:
    """The result summary with the per-step evaluations and, with ``convention``, the pose."""
    out = res.summary()
    steps = res.steps
    out["steps"] = {k: {"d_x_mm": steps[k].d_x_mm, "d_y_mm": steps[k].d_y_mm,
                        "center_mm": steps[k].center_mm.tolist(),
                        "angles_deg": np.degrees(steps[k].angles_rad).tolist(),
                        "axis_point_flange_mm": steps[k].axis_point_flange.tolist()}
                    for k in ("circle1", "circle2", "circle3")}
    out["steps"]["vertical"] = {"flange_mean_mm": steps["vertical"].flange_mean_mm.tolist(),
                                "beam_heights_mm": steps["vertical"].beam_heights_mm}
    if convention:
        from ..transforms import pose_from_transform

        try:
            out["pose"] = {"convention": convention,
                           "values": [float(v) for v in pose_from_transform(res.T_flange_tool, convention)]}
        except ValueError as exc:
            raise click.ClickException(str(exc)) from None
    return out


def _echo_result(res, out, settings, sensor, convention) -> None:
    """The result as text: TCP, axis, settings, cycle time, pose, frame, residuals."""
    t, a = res.tcp_flange_mm, res.axis_flange
    click.echo(f"TCP (flange frame)  : {t[0]:.4f} {t[1]:.4f} {t[2]:.4f} mm")
    click.echo(f"tool axis (flange)  : {a[0]:.6f} {a[1]:.6f} {a[2]:.6f}  (psi {math.degrees(res.psi_rad):.4f} deg, "
               f"theta {math.degrees(res.theta_rad):.4f} deg)")
    click.echo(f"beta correction     : {'on' if settings.beta_correction else 'off'} "
               f"(beta = {math.degrees(sensor.beta_rad):.4f} deg)")
    click.echo(f"cycle time          : {res.cycle_time_s:.2f} s")
    if "pose" in out:
        click.echo(f"pose ({convention})  : " + " ".join(f"{v:.4f}" for v in out["pose"]["values"]))
    click.echo("T_flange_tool:")
    for row in res.T_flange_tool:
        click.echo("  " + " ".join(f"{v:12.6f}" for v in row))
    click.echo("residuals:")
    for k, v in res.residuals.items():
        click.echo(f"  {k:<28} {v:.4f}")


@click.command("simulate")
@click.option("--collisions", default=10, show_default=True, type=click.IntRange(1, 1000),
              help="Random collisions, each followed by a recalibration.")
@click.option("--seed", default=0, show_default=True, type=int, help="Seed of every random draw.")
@click.option("--no-beta-correction", is_flag=True,
              help="Only the variants without the beta correction (default: with and without, side by side).")
@click.option("--beta", "beta_deg", default=88.0, show_default=True, type=click.FloatRange(84.0, 96.0),
              help="Angle between the beams [deg]; 84 to 96 (the simulated cell's sensor-calibration moves are "
                   "laid out for nearly crossed beams).")
@click.option("--tilt", "tilt_deg", default=2.0, show_default=True, type=click.FloatRange(-10.0, 10.0),
              help="Sensor tilt vs the base [deg]; -10 to 10 (beyond, the simulated pin misses the beams).")
@click.option("--repeatability", "repeatability_mm", default=0.1, show_default=True, type=float,
              help="Robot repeatability (ISO 9283) [mm].")
@click.option("--io-rate", "io_rate_hz", default=1000.0, show_default=True, type=float, help="Controller I/O rate [Hz].")
@click.option("--tool-radius", "tool_radius_mm", default=3.0, show_default=True, type=float, help="Tool radius [mm].")
@click.argument("robot", default="ur10", required=False)
@click.option("--out", "out_dir", type=click.Path(file_okay=False), default=None,
              help="Folder for events.csv (the first recalibration's barrier events, robocal-barrier-events/1) and "
                   "sensor.json (the simulated sensor calibration, as `robocal tcp calibrate-sensor --json`); "
                   "optional (created if needed).")
@click.option("--events-out", type=click.Path(dir_okay=False), default=None, hidden=True,
              help="Deprecated: write the barrier events to this file; use --out DIR.")
@click.option("--sensor-out", type=click.Path(dir_okay=False), default=None, hidden=True,
              help="Deprecated: write the sensor calibration to this file; use --out DIR.")
@click.option("--overwrite", is_flag=True, help="Replace existing events.csv / sensor.json.")
@click.option("--json", "as_json", is_flag=True, help="Print JSON.")
def simulate_cmd(collisions, seed, no_beta_correction, beta_deg, tilt_deg, repeatability_mm, io_rate_hz, tool_radius_mm,
                 robot, out_dir, events_out, sensor_out, overwrite, as_json):
    """Simulated tool-recalibration study: random collisions, cross-laser recalibration, truth comparison.

    ROBOT (default ur10; 'none' skips it) is checked for reaching the motions.

    A UR10-class cell (by default: repeatability 0.1 mm, I/O 1 kHz, tool radius 3 mm, beta = 88
    deg, sensor tilted 2 deg) as in the thesis's experiment (5.2). Variants: beta_corrected (this
    library's procedure), no_beta_correction, thesis_step3 (step 3 centred as in the thesis) and
    thesis_step3_no_beta.
    """
    from ..tcp.cross_laser import CrossLaserError
    from ..workflows.tool.recalibration import DEFAULT_VARIANTS, format_study_table, tcp_repeatability_study

    from ..io.output_paths import check_outputs
    from ._progress import Progress

    variants = {k: v for k, v in DEFAULT_VARIANTS.items() if not no_beta_correction or v.get("beta_correction") is False}
    if out_dir is not None:
        if events_out or sensor_out:
            raise click.UsageError("give --out DIR (the deprecated --events-out/--sensor-out FILE are its older "
                                   "form), not both")
        events_out, sensor_out = str(Path(out_dir) / "events.csv"), str(Path(out_dir) / "sensor.json")
    if events_out and sensor_out and Path(events_out).resolve() == Path(sensor_out).resolve():
        raise click.ClickException(f"--events-out and --sensor-out are the same file {events_out}")
    try:
        check_outputs([events_out, sensor_out], {"ROBOT": None if robot.lower() == "none" else robot},
                      overwrite=overwrite)
        if out_dir is not None:
            Path(out_dir).mkdir(parents=True, exist_ok=True)
        with Progress("recalibrations", collisions * len(variants)) as bar:
            res = tcp_repeatability_study(collisions=collisions, seed=seed, beta_deg=beta_deg, tilt_deg=tilt_deg,
                                          repeatability_mm=repeatability_mm, io_rate_hz=io_rate_hz,
                                          tool_radius_mm=tool_radius_mm,
                                          robot=None if robot.lower() == "none" else robot, variants=variants,
                                          events_path=events_out, sensor_path=sensor_out,
                                          progress=lambda done, total: bar.update(1))
    except (CrossLaserError, ValueError, OSError) as exc:
        raise click.ClickException(str(exc)) from None
    except RuntimeError as exc:  # the simulated cell cannot carry out a move with these settings
        raise click.ClickException(f"the simulated cell cannot run with --beta {beta_deg:g} --tilt {tilt_deg:g} "
                                   f"--tool-radius {tool_radius_mm:g}: {exc}") from None
    if as_json:
        click.echo(json.dumps(res, indent=2))
    else:
        click.echo(format_study_table(res))
        if events_out:
            click.echo(f"events of the first recalibration written to {events_out}")
        if sensor_out:
            click.echo(f"sensor calibration written to {sensor_out}")


@click.command("accuracy")
@click.option("--preset", type=click.Choice(["ideal", "realistic"]), default="realistic", show_default=True,
              help="Error sources of the cell (docs/tcp.md 'Repeatability and accuracy').")
@click.option("--seeds", "n_seeds", default=20, show_default=True, type=click.IntRange(1, 10000),
              help="Cells (each with its own robot error, dirt, runout, collision).")
@click.option("--seed", "first_seed", default=1, show_default=True, type=int, help="The first seed; the others follow.")
@click.option("--repeats", default=10, show_default=True, type=click.IntRange(2, 1000),
              help="Recalibrations of the same bent tool per cell.")
@click.option("--method", "methods", type=click.Choice(["cross_laser", "parallel_barriers"]), multiple=True,
              help="Method(s) to run (default: both).")
@click.option("--budget", is_flag=True, help="Instead: the error budget (ideal, ideal + each error source, "
                                             "realistic) over the same seeds.")
@click.option("--json", "as_json", is_flag=True, help="Print JSON.")
def accuracy_cmd(preset, n_seeds, first_seed, repeats, methods, budget, as_json):
    """Tool-frame repeatability and accuracy over many simulated cells (issue 11): per cell the
    same bent tool recalibrated REPEATS times by the cross-laser method (thesis 4.2) and by the
    parallel light barriers (4-6, 4-7); repeatability = rms spread of the repeats, accuracy = rms
    distance from the true TCP, arm check = what a measuring arm registered to the robot base
    reads (the thesis's 0.48 mm is of that kind). Median and quartiles over the cells.
    """
    from ..workflows.tool.accuracy import METHODS, format_accuracy_table, tcp_accuracy_study, tcp_error_budget

    from ._common import _step_printer, _user_error

    methods = tuple(methods) or METHODS
    try:
        if budget:
            res = tcp_error_budget(seeds=n_seeds, first_seed=first_seed, repeats=repeats, methods=methods,
                                   progress=_step_printer)
        else:
            res = tcp_accuracy_study(preset=preset, seeds=n_seeds, first_seed=first_seed, repeats=repeats,
                                     methods=methods, progress=_step_printer)
    except (ValueError, RuntimeError) as exc:
        raise _user_error(exc) from None
    if as_json:
        click.echo(json.dumps(res, indent=1, default=float))
    elif budget:
        click.echo(f"error budget over {n_seeds} cells, {repeats} repeats: median repeatability / accuracy / arm "
                   "check [mm], axis accuracy [deg]")
        for name, summ in res.items():
            for m, v in summ.items():
                click.echo(f"  {name:<26} {m:<18} {v['repeatability_mm']['median']:.3f} / "
                           f"{v['accuracy_mm']['median']:.3f} / {v['check_mm']['median']:.3f}   "
                           f"{v['axis_accuracy_deg']['median']:.3f}")
    else:
        click.echo(format_accuracy_table(res))

