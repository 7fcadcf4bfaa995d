"""``robocal robots``, ``robocal fk``, ``robocal ik``: the robot library and kinematics."""

from __future__ import annotations

import json
import math

import click
import numpy as np

from ..robots import list_robots, load_robot
from ._common import (
    JOINTS_ARG,
    NUMBERS_CONTEXT,
    _joints_from_cli,
    _numbers,
    _prismatic,
    _robot,
)


@click.command()
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


def _with_tool(model, text):
    """``model`` with its single chain's end effector replaced by the ``--tool`` frame."""
    from ..kinematics.model import EndEffector
    from ..transforms import transform_from_pose

    try:
        vals = [float(v) for v in str(text).replace(" ", "").split(",")]
    except ValueError:
        raise click.ClickException(f"--tool: expected X,Y,Z or X,Y,Z,A,B,C numbers, got {text!r}") from None
    if len(vals) not in (3, 6):
        raise click.ClickException(f"--tool: expected 3 or 6 numbers (X,Y,Z[,A,B,C]), got {len(vals)}")
    if len(model.end_effectors) != 1:
        raise click.ClickException("--tool: for single-chain robots (this one has several end effectors; use --ee)")
    T = transform_from_pose(vals + [0.0] * (6 - len(vals)), "kuka_abc", "mm", "deg")
    link = len(model.links) - 1
    return model.replace(end_effectors=[EndEffector("tool", link, T)])


@click.command(context_settings=NUMBERS_CONTEXT)
@click.argument("robot")
@click.argument("joints", **JOINTS_ARG)
@click.option("--deg/--rad", default=False, help="Unit of joint values, in and out: degrees or radians (default); prismatic joints in mm.")
@click.option("--orientation", "convention", default=None, metavar="CONVENTION",
              help="Also print the orientation in this convention (kuka_abc, fanuc_wpr, zxz, rpy, quaternion, rotvec, ...).")
@click.option("--ee", "end_effector", default=None, help="End effector of a tree robot (default: the first).")
@click.option("--frame", type=click.Choice(["base", "world"]), default="base", show_default=True,
              help="Frame of the printed pose: the robot base, or the robot file's world (for a calibrated robot "
                   "file: the measurement instrument's frame, its [base]).")
@click.option("--tool", "tool", default=None, metavar="X,Y,Z[,A,B,C]",
              help="Tool frame on the flange, X,Y,Z [mm] [,A,B,C [deg], KUKA A,B,C], instead of the robot file's "
                   "[tool] (a calibrated robot file carries the identified one); --tool 0,0,0 gives the flange.")
@click.option("--json", "as_json", is_flag=True, help="Print JSON with keys position_mm and rotation.")
def fk(robot, joints, deg, convention, end_effector, frame, tool, as_json):
    """Forward kinematics: pose of ROBOT's tool (the file's [tool], else the flange; or --tool) at
    JOINTS [mm], in the robot base frame (default) or the robot file's world frame (--frame world)."""
    from ..transforms import pose_from_transform

    model = _robot(robot)
    if tool is not None:
        model = _with_tool(model, tool)
    q = _joints_from_cli(model, joints, deg)
    try:
        # one configuration: numpy products, no compiled kernels to load (importing numba alone takes
        # ~0.5 s, ~100x this FK); the kernels agree with it to ~1e-12 mm (tests/test_kinematics*)
        T = model.fk_reference(q, end_effector)
    except (KeyError, IndexError) as exc:
        raise click.ClickException(str(exc).strip('"')) from None
    if frame == "base":
        T = np.linalg.inv(model.T_world_base) @ T
    out = {"robot": model.name, "end_effector": model.end_effectors[model.end_effector_index(end_effector)].name,
           "frame": frame, "tool": tool, "position_mm": T[:3, 3].tolist(), "rotation": T[:3, :3].tolist()}
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
    what = out["end_effector"]
    click.echo(f"{model.name} {what} in the {frame} frame: position [mm] x={x:.4f} y={y:.4f} z={z:.4f}")
    for row in T[:3, :3]:
        click.echo("  [" + "  ".join(f"{v:+.6f}" for v in row) + "]")
    if convention:
        vals = "  ".join(f"{v:.6f}" for v in out["orientation"]["values"])
        click.echo(f"orientation {convention} [{out['orientation']['unit'] or '-'}]: {vals}")


@click.command(context_settings=NUMBERS_CONTEXT)
@click.argument("robot")
@click.argument("pose", **JOINTS_ARG)
@click.option("--orientation", "convention", default="kuka_abc", show_default=True, metavar="CONVENTION",
              help="Orientation convention of POSE (angles in degrees; quaternion: w x y z).")
@click.option("--deg/--rad", default=False, help="Unit of joint values, in and out (--start, the printed joints): degrees or radians (default).")
@click.option("--start", "start", default=None,
              help="Starting joints for the numerical solver, comma separated (units as --deg).")
@click.option("--all-branches", is_flag=True, help="All closed-form branches (6R spherical-wrist arms).")
@click.option("--seed-net", "seed_net", default=None, type=click.Path(dir_okay=False),
              help="Start the numerical solver from a trained IK network (robocal ik-train).")
@click.option("--ee", "end_effector", default=None, help="End effector of a tree robot (default: the first).")
@click.option("--json", "as_json", is_flag=True, help="Print JSON.")
def ik(robot, pose, convention, deg, start, all_branches, seed_net, end_effector, as_json):
    """Inverse kinematics: joints that put ROBOT's flange at POSE = X Y Z [mm] and orientation angles."""
    from ..kinematics.ik import ik_numeric
    from ..transforms import transform_from_pose

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
    if seed_net is not None and (start is not None or all_branches):
        raise click.ClickException("--seed-net cannot be combined with --start or --all-branches")
    if seed_net is not None and end_effector is not None and model.end_effector_index(end_effector) != 0:
        raise click.ClickException("--seed-net: the network is trained for the first end effector; drop --ee")
    seed_info = None
    if all_branches:
        try:
            from ..kinematics.ik_analytic import ik_analytic
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
        if seed_net is not None:
            q0, seed_info, branch = _network_seed(model, T, seed_net, to_out)
        elif start is None:
            lo, hi = model.limits[:, 0], model.limits[:, 1]
            q0 = np.where(np.isfinite(lo) & np.isfinite(hi), (lo + hi) / 2, 0.0)
        else:
            q0 = _joints_from_cli(model, start.split(","), deg)
        res = ik_numeric(model, T, q0, end_effector=end_effector)
        if seed_info is not None:
            seed_info["solution_on_branch"] = bool(res.converged) and _solution_on_branch(model, res.q, branch)
        if not res.converged:
            raise click.ClickException(
                f"IK did not converge ({res.status}): remaining error {res.position_error_mm:.4g} mm, "
                f"{math.degrees(res.rotation_error_rad):.4g} deg; try --start closer to the solution"
                + (f" (network seed: {seed_info['status']})" if seed_info else ""))
        solutions.append({"joints": to_out(res.q).tolist(), "iterations": int(res.iterations),
                          "position_error_mm": float(res.position_error_mm)})
    unit = "deg" if deg else "rad"
    if as_json:
        out = {"robot": model.name, "joint_unit": unit, "joints_names": list(model.controller_joints),
               "solutions": solutions}
        if seed_info is not None:
            out["seed"] = seed_info
        click.echo(json.dumps(out, indent=2))
        return
    if seed_info is not None:
        note = "" if seed_info["in_domain"] else "  -- the pose is outside what the network was trained on; the seed is a guess"
        click.echo(f"seed [{unit}] ({seed_info['status']}, FK of the seed {seed_info['position_error_mm']:.1f} mm "
                   f"from the target): " + "  ".join(f"{v:.6f}" for v in seed_info["joints"]) + note)
        if not seed_info["solution_on_branch"]:
            click.echo(f"note: the solution is not on the network's branch ({seed_info['branch']}): damped least "
                       "squares went to another configuration")
    for s in solutions:
        tag = f"branch {s['branch']}" if "branch" in s else "solution"
        extra = "" if s.get("within_limits", True) else "  (outside joint limits)"
        click.echo(f"{tag} [{unit}]: " + "  ".join(f"{v:.6f}" for v in s["joints"]) + extra)



def _solution_on_branch(model, q, branch) -> bool:
    """Whether joints ``q`` lie on the network's configuration ``branch``."""
    from ..kinematics.ik_analytic import NotAnalyticError
    from ..kinematics.ik_net import on_branch, reference_model

    try:
        ref = None if branch.index < 0 else reference_model(model)
    except NotAnalyticError:
        return False
    return bool(on_branch(ref, q, branch)[0])


def _network_seed(model, T, path, to_out):
    """Seed joints from a network file, and what the domain check said about them."""
    from ..io.ik_network import load_ik_network

    net = load_ik_network(path, model)
    pred = net.seed(model, T)

    info = {"network": str(path), "branch": net.branch.name, "status": str(pred.status[0]),
            "in_domain": bool(pred.in_domain[0]), "joints": to_out(pred.q[0]).tolist(),
            "position_error_mm": float(pred.position_error_mm[0]),
            "rotation_error_deg": float(math.degrees(pred.rotation_error_rad[0])),
            "centre_distance_sigma": float(pred.centre_distance[0])}
    return pred.q[0], info, net.branch
