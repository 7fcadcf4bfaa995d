"""``robocal iso9283 plan|evaluate``: the ISO 9283 performance test; ``robocal simulate iso9283``
lives in this module too (attached to ``robocal simulate``)."""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path

import click

from ..errors import RobocalError
from ._common import EXIT_FAILED_RESULT, _robot, _user_error
from ._json import json_option, set_json_result

__all__ = ["iso9283", "simulate_iso9283_cmd", "xyz_option", "history_options", "check_history_options"]


def history_options(f):
    """``--db``, ``--robot-id``, ``--time``, ``--temperature``, ``--instrument``: record the result
    in the history database."""
    f = click.option("--instrument", default=None, help="Instrument name/serial, recorded.")(f)
    f = click.option("--temperature", "temperature_c", type=float, default=None,
                     help="Robot temperature during the measurement [degC], recorded.")(f)
    f = click.option("--time", "when", default=None, metavar="ISO_TIME",
                     help="When it was measured (ISO 8601 with a zone, e.g. 2026-05-01T06:00Z; default now), recorded.")(f)
    f = click.option("--robot-id", default=None, help="The robot's id in the history database (with --db).")(f)
    f = click.option("--db", default=None, metavar="URL_OR_FILE",
                     help="Record the result in this history database (an SQLite file or a URL; created if absent).")(f)
    return f


def check_history_options(db, robot_id, when=None) -> None:
    """``--db`` and ``--robot-id`` together, a valid robot id and ``--time``, before any work."""
    from ..store import HistoryInputError
    from ..store._validate import check_robot_id, parse_time

    if (db is None) != (robot_id is None):
        raise click.ClickException("--db and --robot-id go together (which database, which robot)")
    try:
        if robot_id is not None:
            check_robot_id(robot_id)
        if when is not None:
            parse_time(when, "--time")
    except HistoryInputError as exc:
        raise click.ClickException(str(exc)) from None


def _xyz(text, option):
    parts = str(text).replace(";", ",").split(",")
    try:
        v = [float(p) for p in parts]
    except ValueError:
        v = []
    if len(v) != 3 or not all(math.isfinite(x) for x in v):
        raise click.ClickException(f"{option}: expected X,Y,Z in mm (three numbers separated by commas), got {text!r}")
    return v


def _frame6(text, option):
    """X,Y,Z[,A,B,C] [mm, deg, KUKA ABC] -> (4, 4)."""
    import numpy as np

    from ..transforms import transform_from_pose

    parts = str(text).split(",")
    try:
        v = [float(p) for p in parts]
    except ValueError:
        v = []
    if len(v) not in (3, 6) or not all(math.isfinite(x) for x in v):
        raise click.ClickException(f"{option}: expected X,Y,Z[,A,B,C] (mm, deg, KUKA A,B,C), got {text!r}")
    if len(v) == 3:
        T = np.eye(4)
        T[:3, 3] = v
        return T
    return transform_from_pose(np.array(v), "kuka_abc", "mm", "deg")


def xyz_option(name, help_text):
    return click.option(name, default=None, metavar="X,Y,Z", help=help_text)


@click.group("iso9283")
def iso9283():
    """The ISO 9283 performance test: plan it, evaluate the measurements."""


@iso9283.command("plan")
@click.argument("robot")
@click.option("--out", "out_dir", required=True, type=click.Path(file_okay=False),
              help="Folder for protocol.json and program.csv.")
@click.option("--tool", default=None, metavar="X,Y,Z[,A,B,C]",
              help="The measured tool point (reflector) on the flange, X,Y,Z [mm] and A,B,C [deg, KUKA A,B,C].")
@click.option("--cycles", default=30, show_default=True, help="Cycles of the pose and distance tests (ISO: 30).")
@click.option("--path-cycles", default=10, show_default=True, help="Cycles of the path tests (ISO: 10).")
@click.option("--drift-hours", default=0.0, show_default=True, help="Length of the drift run [h] (ISO: 8; 0: none).")
@click.option("--load", default=None, help="The load the test runs with (text recorded in the protocol; "
              "default: 100 % of the rated load at its rated offset, as ISO 9283 asks).")
@click.option("--speed", "speed_percent", default=100.0, show_default=True,
              help="Speed of the test [% of the rated speed] (ISO: 100, 50 and 10).")
@click.option("--min-height", "min_height_mm", default=100.0, show_default=True,
              help="The cube's lowest face above the mounting plane [mm].")
@click.option("--language", type=click.Choice(["krl", "rapid", "tp", "urscript"]), default=None,
              help="Also write the test as a robot program: KUKA KRL (.dat + .src), ABB RAPID (.mod), FANUC TP "
                   "(.ls), UR script (.script); joint targets in driving order, a wait at each point.")
@click.option("--cell", "cell_file", default=None, type=click.Path(dir_okay=False, exists=True),
              help="Cell file (robocal-cell/1, docs/cells.md): mounting, obstacles, joint ranges the test must "
                   "respect; default: the robot on the floor, the floor an obstacle.")
@click.option("--json", "as_json", is_flag=True, help="Print the plan's summary as JSON.")
@click.option("--overwrite", is_flag=True, help="Replace an earlier plan in the folder.")
def plan_cmd(robot, out_dir, tool, cycles, path_cycles, drift_hours, load, speed_percent, min_height_mm, language,
             cell_file, as_json, overwrite):
    """The ISO 9283 test of ROBOT: the largest cube in its working range, P1-P5, the sequences."""
    from ..workflows.performance.iso9283_plan import build_iso_plan, write_iso_plan

    model = _robot(robot)
    T_tool = _frame6(tool, "--tool") if tool else None
    try:
        cell = None
        if cell_file:
            from ..io.cell_file import read_cell

            cell = read_cell(cell_file, model)
        plan = build_iso_plan(model, T_flange_tool=T_tool, cycles=cycles, path_cycles=path_cycles,
                              drift_hours=drift_hours, load=load, speed_percent=speed_percent,
                              min_height_mm=min_height_mm, cell=cell)
        files = write_iso_plan(out_dir, plan, model, overwrite=overwrite, language=language,
                               inputs={"ROBOT": robot, "--cell": cell_file})
    except (ValueError, OSError) as exc:
        raise _user_error(exc) from None
    cube = plan["cube"]
    summary = {"robot": model.name, "cube": cube, "poses_mm": {k: v["position_mm"] for k, v in plan["poses"].items()},
               "n_measurements": len(plan["measurements"]), "conditions": plan["conditions"], "files": files}
    if as_json:
        click.echo(json.dumps(summary, indent=1))
        return
    c = cube["centre_mm"]
    click.echo(f"ISO 9283 test of {model.name}: cube {cube['edge_mm']:.0f} mm, centre ({c[0]:.1f}, {c[1]:.1f}, "
               f"{c[2]:.1f}) mm in the base frame")
    for k, v in plan["poses"].items():
        p = v["position_mm"]
        click.echo(f"  {k}: ({p[0]:9.2f}, {p[1]:9.2f}, {p[2]:9.2f}) mm")
    click.echo(f"load: {plan['conditions']['load']}; speed {speed_percent:g} % of rated")
    extra = "".join(f", {f}" for f in files.get("robot_program", []))
    click.echo(f"{len(plan['measurements'])} measurements; wrote {files['protocol']}, {files['program']}{extra}")


def _mpe(text):
    from ..performance.adequacy import parse_mpe

    try:
        return parse_mpe(text)
    except ValueError as exc:
        raise click.ClickException(f"--mpe: {exc}") from None


@iso9283.command("evaluate")
@click.argument("plan", type=click.Path(exists=True))
@click.argument("measurements", type=click.Path(exists=True, dir_okay=False))
@click.argument("after", required=False, type=click.Path(exists=True, dir_okay=False))
@click.option("--out", "out_dir", required=True, type=click.Path(file_okay=False),
              help="Folder for iso9283.json, iso9283.txt and report.html.")
@click.option("--mpe", default=None, metavar="A+B/m",
              help="The instrument's maximum permissible error, ISO 10360-10 form, e.g. 15um+6um/m.")
@xyz_option("--instrument-at", "Instrument position in the robot's base frame [mm] (for --mpe).")
@click.option("--json", "as_json", is_flag=True, help="Print the result as JSON.")
@click.option("--overwrite", is_flag=True, help="Replace an earlier evaluation in the folder.")
@history_options
def evaluate_cmd(plan, measurements, after, out_dir, mpe, instrument_at, as_json, overwrite, db, robot_id,
                 when, temperature_c, instrument):
    """Every ISO 9283 characteristic MEASUREMENTS support (a second file AFTER: before/after).

    With --db and --robot-id the figures are recorded in the history database (the AFTER run's
    when two are given: the robot as it will work, with the corrected program)."""
    from ..io.iso9283_files import read_iso_measurements
    from ..workflows.performance.iso9283_evaluate import compare_runs, evaluate_iso_run, iso_table_lines
    from ..workflows.performance.iso9283_report import write_iso_outputs
    from ..workflows.performance.iso9283_plan import read_iso_plan

    if (mpe is None) != (instrument_at is None):
        raise click.ClickException("--mpe and --instrument-at go together (the MPE depends on the distance)")
    check_history_options(db, robot_id, when)
    m = _mpe(mpe) if mpe else None
    st = _xyz(instrument_at, "--instrument-at") if instrument_at else None
    try:
        protocol = read_iso_plan(plan)
        runs = [evaluate_iso_run(protocol, read_iso_measurements(measurements), mpe=m, instrument_at_mm=st)]
        if after:
            runs.append(evaluate_iso_run(protocol, read_iso_measurements(after), mpe=m, instrument_at_mm=st))
        result = {"format": "robocal-iso9283-result/1", "robot": protocol.get("robot"), "runs": runs,
                  "instrument": {"mpe": mpe, "instrument_at_mm": st},
                  "conditions": protocol.get("conditions")}
        if after:
            result["comparison"] = compare_runs(runs[0], runs[1])
        plan_file = Path(plan) / "protocol.json" if Path(plan).is_dir() else Path(plan)
        files = write_iso_outputs(out_dir, result, overwrite=overwrite,
                                  inputs={"PLAN": plan_file, "MEASUREMENTS": measurements, "AFTER": after})
        if db is not None:
            from ..workflows.performance.iso9283_history import record_iso_run

            result["history"] = {"database": db, "robot_id": robot_id, "cycle_id": record_iso_run(
                db, robot_id, runs[-1], time=when, temperature_c=temperature_c,
                instrument=instrument or (f"MPE {mpe}" if mpe else None),
                meta={"plan": str(plan), "measurements": str(after or measurements),
                      "corrected_program": bool(after)})}
    except (ValueError, OSError, RobocalError) as exc:
        raise _user_error(exc) from None
    failed = [r for r in runs if r["status"] != "ok"]
    if as_json:
        click.echo(json.dumps(result, indent=1, default=float))
        if failed:
            sys.exit(EXIT_FAILED_RESULT)
        return
    click.echo("\n".join(iso_table_lines(runs[0])))
    if after:
        click.echo("")
        click.echo(f"{'characteristic':<16}{'before':>10}{'after':>10}{'gain':>10}")
        for row in result["comparison"]:
            click.echo(f"{row['characteristic']:<16}{row['before']:>10.4f}{row['after']:>10.4f}{row['gain']:>+10.4f}")
    click.echo(f"wrote {', '.join(files.values())}")
    if db is not None:
        click.echo(f"recorded in the history of {robot_id!r} (cycle {result['history']['cycle_id']})")
    if failed:
        click.echo("FAILED: the evaluation did not pass its sanity gate (exit code 3):", err=True)
        for r in failed:
            for reason in r["reasons"]:
                click.echo(f"  - {reason}", err=True)
        sys.exit(EXIT_FAILED_RESULT)


@click.command("iso9283")
@click.argument("robot")
@click.argument("plan", type=click.Path(exists=True))
@click.option("--out", "out_file", required=True, type=click.Path(dir_okay=False),
              help="Measurement file to write (and <name>.truth.csv beside it: the instrument-free truth).")
@click.option("--seed", default=0, show_default=True,
              help="Seed of the true robot (the same as `robocal simulate tracker --seed`) and of the noise.")
@click.option("--truth", "truth_file", default=None, type=click.Path(exists=True, dir_okay=False),
              help="Take the true robot from this .truth.json of `robocal simulate tracker` instead.")
@click.option("--calibrated", default=None, type=click.Path(exists=True, dir_okay=False),
              help="Drive the plan corrected by this calibrated robot file (the 'after' run).")
@click.option("--mpe", default="15um+6um/m", show_default=True, metavar="A+B/m",
              help="The simulated tracker's MPE (its random error per coordinate is MPE/4).")
@xyz_option("--instrument-at", "Tracker position in the base frame [mm] (default: 3000 mm in front of the cube).")
@click.option("--joint-noise", "joint_noise_deg", default=0.002, show_default=True, help="Joint noise per arrival [deg].")
@click.option("--backlash", "backlash_deg", default=0.004, show_default=True, help="Backlash per joint [deg].")
@click.option("--drift", "drift_deg", default=0.005, show_default=True,
              help="Thermal drift of the J2/J3 offsets at steady state [deg] (time constant 1 h).")
@click.option("--overwrite", is_flag=True, help="Replace existing files.")
@json_option
def simulate_iso9283_cmd(robot, plan, out_file, seed, truth_file, calibrated, mpe, instrument_at, joint_noise_deg,
                         backlash_deg, drift_deg, overwrite):
    """The simulator's true ROBOT executes an ISO 9283 PLAN; a tracker records it."""
    import numpy as np

    from ..sim.iso9283 import IsoEffects
    from ..workflows.performance.iso9283_plan import read_iso_plan
    from ..workflows.performance.iso9283_simulate import simulate_iso9283

    for name, v in (("--joint-noise", joint_noise_deg), ("--backlash", backlash_deg), ("--drift", drift_deg)):
        if not (v >= 0 and math.isfinite(v)):
            raise click.ClickException(f"{name} must be >= 0 deg, got {v}")
    try:
        protocol = read_iso_plan(plan)
        st = _xyz(instrument_at, "--instrument-at") if instrument_at else \
            (np.asarray(protocol["cube"]["centre_mm"]) + [3000.0, 0.0, 0.0]).tolist()
        r = simulate_iso9283(robot, protocol, out_file, seed=seed, mpe=_mpe(mpe), instrument_at_mm=st,
                             truth_file=truth_file, calibrated=calibrated,
                             effects=IsoEffects(joint_noise_deg, backlash_deg, drift_deg), overwrite=overwrite)
    except (ValueError, OSError, RuntimeError) as exc:
        raise _user_error(exc) from None
    set_json_result(dict(r, instrument_at_mm=st, calibrated=calibrated))
    click.echo(f"simulated the ISO 9283 run ({r['n_points']} points, tracker at "
               f"({st[0]:.0f}, {st[1]:.0f}, {st[2]:.0f}) mm{', corrected program' if calibrated else ''})")
    click.echo(f"wrote {r['measurements']} and {r['truth_measurements']}")
