"""The ``robocal`` command line: thin over the library (parse, call, print).

Every user error ends in one line ``Error: ...`` and a non-zero exit code.
"""

from __future__ import annotations

import json
import math
import sys

import click
import numpy as np

from .robots import RobotFileError, list_robots, load_robot

JOINTS_ARG = dict(nargs=-1, type=str, required=True)
NUMBERS_CONTEXT = {"ignore_unknown_options": True, "allow_interspersed_args": True}


def _robot(name):
    try:
        return load_robot(name)
    except RobotFileError as exc:
        raise click.ClickException(str(exc)) from None


def _numbers(values, what):
    out = []
    for i, v in enumerate(values, 1):
        try:
            x = float(v)
        except ValueError:
            raise click.ClickException(f"{what} {i}: {v!r} is not a number") from None
        if not math.isfinite(x):
            raise click.ClickException(f"{what} {i}: {v!r} is not a finite number")
        out.append(x)
    return np.array(out)


def _prismatic(model):
    return model.prismatic_joints


def _joints_from_cli(model, values, deg):
    q = _numbers(values, "joint")
    if len(q) != model.n_joints:
        raise click.ClickException(
            f"{model.name} has {model.n_joints} joints ({', '.join(model.controller_joints)}), got {len(q)} values")
    pris = _prismatic(model)
    if deg:
        q = np.where(pris, q, np.radians(q))
    lo, hi = model.limits[:, 0], model.limits[:, 1]
    bad = np.flatnonzero((q < lo - 1e-12) | (q > hi + 1e-12))
    if bad.size:
        j = int(bad[0])
        scale, unit = (1.0, "mm") if pris[j] else ((180 / math.pi, "deg") if deg else (1.0, "rad"))
        raise click.ClickException(
            f"joint {model.controller_joints[j]} = {q[j] * scale:.6g} {unit} is outside its limits "
            f"[{lo[j] * scale:.6g}, {hi[j] * scale:.6g}] {unit}" + ("" if deg else " (pass --deg for degrees)"))
    return q


@click.group(context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(package_name="robocal")
def main():
    """robocal: keep industrial robots accurate (calibration, thermal compensation, tool frames)."""


@main.command()
@click.option("--json", "as_json", is_flag=True, help="Print JSON.")
def robots(as_json):
    """List the robots shipped with robocal."""
    rows = []
    for name in list_robots():
        m = load_robot(name)
        rows.append({"name": name, "model": m.kind, "joints": m.n_joints, "end_effectors": [e.name for e in m.end_effectors],
                     "title": m.title})
    if as_json:
        click.echo(json.dumps(rows, indent=2))
        return
    w = max(len(r["name"]) for r in rows)
    for r in rows:
        click.echo(f"{r['name']:<{w}}  {r['model']:<8} {r['joints']:>2} joints  {r['title']}")


@main.command(context_settings=NUMBERS_CONTEXT)
@click.argument("robot")
@click.argument("joints", **JOINTS_ARG)
@click.option("--deg", is_flag=True, help="Joint angles in degrees (default radians); prismatic joints in mm.")
@click.option("--euler", "convention", default=None,
              help="Also print the orientation in this convention (kuka_abc, fanuc_wpr, zxz, rpy, quaternion, rotvec, ...).")
@click.option("--ee", "end_effector", default=None, help="End effector of a tree robot (default: the first).")
@click.option("--json", "as_json", is_flag=True, help="Print JSON with keys position_mm and rotation.")
def fk(robot, joints, deg, convention, end_effector, as_json):
    """Forward kinematics: flange pose of ROBOT at JOINTS (base frame, mm)."""
    from .transforms import pose_from_transform

    model = _robot(robot)
    q = _joints_from_cli(model, joints, deg)
    try:
        T = model.fk(q, end_effector)
    except (KeyError, IndexError) as exc:
        raise click.ClickException(str(exc).strip('"')) from None
    out = {"robot": model.name, "end_effector": model.end_effectors[model.end_effector_index(end_effector)].name,
           "position_mm": T[:3, 3].tolist(), "rotation": T[:3, :3].tolist()}
    if convention:
        try:
            pose = pose_from_transform(T, convention, length_unit="mm", angle_unit="deg")
        except ValueError as exc:
            raise click.ClickException(str(exc)) from None
        unit = "" if convention == "quaternion" else "deg"
        out["orientation"] = {"convention": convention, "values": pose[3:].tolist(), "unit": unit}
    if as_json:
        click.echo(json.dumps(out, indent=2))
        return
    x, y, z = T[:3, 3]
    click.echo(f"{model.name} {out['end_effector']}: position [mm] x={x:.4f} y={y:.4f} z={z:.4f}")
    for row in T[:3, :3]:
        click.echo("  [" + "  ".join(f"{v:+.6f}" for v in row) + "]")
    if convention:
        vals = "  ".join(f"{v:.6f}" for v in out["orientation"]["values"])
        click.echo(f"orientation {convention} [{out['orientation']['unit'] or '-'}]: {vals}")


@main.command(context_settings=NUMBERS_CONTEXT)
@click.argument("robot")
@click.argument("pose", **JOINTS_ARG)
@click.option("--euler", "convention", default="kuka_abc", show_default=True,
              help="Orientation convention of POSE (angles in degrees; quaternion: w x y z).")
@click.option("--deg", is_flag=True, help="Print joint angles in degrees (default radians).")
@click.option("--start", "start", default=None,
              help="Starting joints for the numerical solver, comma separated (units as --deg).")
@click.option("--all-branches", is_flag=True, help="All closed-form branches (6R spherical-wrist arms).")
@click.option("--ee", "end_effector", default=None, help="End effector of a tree robot (default: the first).")
@click.option("--json", "as_json", is_flag=True, help="Print JSON.")
def ik(robot, pose, convention, deg, start, all_branches, end_effector, as_json):
    """Inverse kinematics: joints that put ROBOT's flange at POSE = X Y Z [mm] and orientation angles."""
    from .kinematics.ik import ik_numeric
    from .transforms import transform_from_pose

    model = _robot(robot)
    values = _numbers(pose, "pose value")
    n_expected = 7 if convention == "quaternion" else 6
    if len(values) != n_expected:
        raise click.ClickException(f"POSE needs {n_expected} values (x y z in mm and the {convention} orientation), "
                                   f"got {len(values)}")
    try:
        T = transform_from_pose(values, convention, length_unit="mm", angle_unit="deg")
    except ValueError as exc:
        raise click.ClickException(str(exc)) from None
    pris = _prismatic(model)
    to_out = (lambda q: np.where(pris, q, np.degrees(q))) if deg else (lambda q: q)
    solutions = []
    if all_branches:
        try:
            from .kinematics.ik_analytic import ik_analytic
            q_all, valid = ik_analytic(model, T)
        except ValueError as exc:
            raise click.ClickException(f"no closed-form solver for {model.name}: {exc}") from None
        for b in range(q_all.shape[0]):
            if valid[b]:
                solutions.append({"branch": b, "joints": to_out(q_all[b]).tolist(),
                                  "within_limits": bool(model.within_limits(q_all[b]))})
        if not solutions:
            raise click.ClickException("pose is not reachable (no valid closed-form branch)")
    else:
        if start is None:
            lo, hi = model.limits[:, 0], model.limits[:, 1]
            q0 = np.where(np.isfinite(lo) & np.isfinite(hi), (lo + hi) / 2, 0.0)
        else:
            q0 = _joints_from_cli(model, start.split(","), deg)
        res = ik_numeric(model, T, q0, end_effector=end_effector)
        if not res.converged:
            raise click.ClickException(
                f"IK did not converge ({res.status}): remaining error {res.position_error_mm:.4g} mm, "
                f"{math.degrees(res.rotation_error_rad):.4g} deg; try --start closer to the solution")
        solutions.append({"joints": to_out(res.q).tolist(), "iterations": int(res.iterations),
                          "position_error_mm": float(res.position_error_mm)})
    unit = "deg" if deg else "rad"
    if as_json:
        click.echo(json.dumps({"robot": model.name, "joint_unit": unit, "joints_names": list(model.controller_joints),
                               "solutions": solutions}, indent=2))
        return
    for s in solutions:
        tag = f"branch {s['branch']}" if "branch" in s else "solution"
        extra = "" if s.get("within_limits", True) else "  (outside joint limits)"
        click.echo(f"{tag} [{unit}]: " + "  ".join(f"{v:.6f}" for v in s["joints"]) + extra)


@main.command()
@click.option("--out", "out_dir", default="robocal-demo", show_default=True, type=click.Path(file_okay=False),
              help="Folder for the results (created if needed; files are replaced atomically).")
@click.option("--seed", default=7, show_default=True, help="Seed of the simulated robot and poses.")
@click.option("--poses", default=500, show_default=True, help="Number of workspace poses for the accuracy maps.")
def demo(out_dir, seed, poses):
    """The accuracy-maintenance cycle on a simulated robot: the problem, geometric calibration,
    a collision and tool recalibration, with a report and a history database."""
    from .workflows.demo import run_demo

    def progress(i, n, text):
        click.echo(f"[{i}/{n}] {text}", err=True)

    if poses < 10:
        raise click.ClickException(f"--poses must be at least 10, got {poses}")
    r = run_demo(out_dir, seed=seed, n_poses=poses, progress=progress)
    acc, rep = r["accuracy_mm"], r["repeatability_mm"]
    g = r["geometric_calibration"]
    t = r["tool_recalibration"]

    def row(label, st):
        return f"{label:<34}{st['rms']:9.3f}{st['mean']:9.3f}{st['p95']:9.3f}{st['max']:9.3f}"

    click.echo("")
    click.echo(f"1. The problem: simulated {r['robot']} (seed {r['seed']}), nominal model vs the real robot")
    click.echo(f"{'':<34}{'RMS':>9}{'mean':>9}{'p95':>9}{'max':>9}   [mm]")
    click.echo(row("accuracy, all poses", acc))
    for b in r["accuracy_by_reach_mm"]:
        click.echo(row(f"  reach {b['reach_mm'][0]:.0f}-{b['reach_mm'][1]:.0f} mm", b))
    click.echo(f"{'repeatability (one pose, 30x)':<34}{rep['rms_deviation']:9.3f}{'':>18}{rep['max_deviation']:9.3f}")
    click.echo("")
    click.echo(f"2. Geometric calibration from {g['poses_measured']} laser-tracker poses "
               f"({g['tracker_noise_mm']} mm noise); {g['identified']} variables identified, "
               f"held: {', '.join(g['not_identifiable'])}")
    ho = g["held_out"]
    if ho.get("before") and ho.get("after"):
        click.echo(row("held-out poses, before", ho["before"]))
        click.echo(row("held-out poses, after", ho["after"]))
    click.echo(row(f"workspace ({r['n_poses']} poses), after", g["workspace_accuracy_mm"]["after"]))
    click.echo("   (held-out errors include tracker noise and encoder noise; the workspace row compares the "
               "calibrated model with the true robot)")
    click.echo("")
    th = r["thermal"]
    click.echo("3. Production with heating (90 cycles of ~3 min per run): share of 34 monitored points' directions "
               "within 0.1 mm (lambda, %)")
    click.echo(f"{'run':>6} {'role':<11}{'TCP drift 3h':>13}{'before':>9}{'traditional':>13}{'screened':>10}")
    for row_ in th["rows"]:
        click.echo(f"{row_['run']:>6} {row_['role']:<11}{row_['tcp_drift_3h_mm']:>10.3f} mm{row_['before']:>9.1f}"
                   f"{row_['traditional']:>13.1f}{row_['screened']:>10.1f}")
    click.echo(f"   screened parameters: {', '.join(th['screened'])}; traditional: {', '.join(th['traditional'])}")
    click.echo("")
    click.echo(f"4. A collision bent the tool by {t['collision']['tilt_deg']:.2f} deg: cross-laser recalibration in "
               f"{t['cycle_time_s']:.1f} s, TCP error {t['tcp_error_mm']:.3f} mm, axis error {t['axis_error_deg']:.3f} deg")
    click.echo("")
    click.echo(f"wrote {r['files']['report']}, {r['files']['result']}" + (f", history {r['history']}" if r.get("history") else ""))


def _user_error(exc) -> click.ClickException:
    """One line ``Error: ...`` from an exception of the library (file, value, name problems)."""
    msg = exc.args[0] if isinstance(exc, KeyError) and exc.args else str(exc)
    return click.ClickException(" ".join(str(msg).split()))


def _names(values):
    """Parameter names from repeated options, each comma or space separated."""
    return [n for v in values for n in v.replace(",", " ").split()]


def _step_printer(i, n, text):
    click.echo(f"[{i}/{n}] {text}", err=True)


@main.command()
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
def calibrate(robot, data, out_dir, free, free_all, fix, holdout, seed, loss, sigma_mm, tool, overwrite):
    """Calibrate ROBOT (name or robot file) from the measurement file DATA."""
    from .workflows.calibrate import run_calibration

    try:
        r = run_calibration(robot, data, out_dir, free=_names(free) or None, free_all=free_all, fix=_names(fix),
                            holdout=holdout, seed=seed, loss=loss, sigma_mm=sigma_mm, tool=tool, overwrite=overwrite,
                            progress=_step_printer)
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


@main.command()
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
    from .workflows.calibrate import run_correct

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


@main.group()
def simulate():
    """Simulated measurement campaigns (files in the real formats, with the hidden truth)."""


@simulate.command("tracker")
@click.argument("robot")
@click.option("--poses", "n_poses", default=100, show_default=True, help="Number of random poses.")
@click.option("--noise", "noise_mm", default=0.02, show_default=True, help="Tracker noise per coordinate [mm].")
@click.option("--reflectors", type=click.Choice(["1", "3"]), default="1", show_default=True,
              help="Reflectors on the flange (3: the file also holds the flange orientation).")
@click.option("--joint-noise", "joint_noise_deg", default=0.0, show_default=True, help="Encoder noise [deg].")
@click.option("--seed", default=0, show_default=True, help="Seed of the true parameters, tracker placement and poses.")
@click.option("--out", "out_file", required=True, type=click.Path(dir_okay=False),
              help="Measurement CSV file; the truth goes to <name>.truth.json next to it.")
@click.option("--overwrite", is_flag=True, help="Replace existing files.")
def simulate_tracker_cmd(robot, n_poses, noise_mm, reflectors, joint_noise_deg, seed, out_file, overwrite):
    """Simulate a laser-tracker campaign of ROBOT with hidden true parameters."""
    from .workflows.simulate import simulate_tracker

    if n_poses < 1:
        raise click.ClickException(f"--poses must be at least 1, got {n_poses}")
    try:
        r = simulate_tracker(robot, out_file, n_poses=n_poses, noise_mm=noise_mm, reflectors=int(reflectors),
                             joint_noise_deg=joint_noise_deg, seed=seed, overwrite=overwrite)
    except (ValueError, KeyError, OSError) as exc:
        raise _user_error(exc) from None
    click.echo(f"simulated {r['n_poses']} poses of {r['robot']} (seed {seed}, tracker noise {noise_mm} mm)")
    click.echo(f"wrote {r['measurements']} and {r['truth']}")


def _register_subcommands():
    """Command groups that live in their own modules (imported here so `robocal --help` lists them)."""
    from .cli_tcp import tcp
    from .cli_tcp_sim import cross_laser_cmd, simulate_cmd

    from .cli_history import history_cmd
    from .cli_thermal import thermal

    tcp.add_command(cross_laser_cmd)
    tcp.add_command(simulate_cmd)
    main.add_command(tcp)
    main.add_command(history_cmd)
    main.add_command(thermal)


_register_subcommands()


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
