"""``robocal ik-train``: train a GA-RBF IK seed network for a robot (docs/kinematics.md)."""

from __future__ import annotations

from pathlib import Path

import click

from ._common import _robot
from ._json import json_option, set_json_result


@click.command("ik-train")
@json_option
@click.argument("robot")
@click.option("--samples", default=20000, show_default=True, type=click.IntRange(500, 1_000_000),
              help="FK samples on the branch (80% train, 20% validation; 500 to 1,000,000).")
@click.option("--seed", default=0, show_default=True, help="Seed of the sampling, the centres and the genetic algorithm.")
@click.option("--out", "out", default=None, type=click.Path(dir_okay=False),
              help="Network file (.npz). Default: next to a robot file (<robot>.iknet.npz), or "
                   "<name>.iknet.npz in the current folder for a shipped robot.")
@click.option("--generations", default=5, show_default=True, help="GA generations (0: only the initial population).")
@click.option("--population", default=10, show_default=True, help="GA population size.")
@click.option("--no-tune", is_flag=True, help="Skip the genetic algorithm; fixed structure (500 centres).")
@click.option("--joint-box", "joint_box", default=None,
              help="Branch by joint ranges alone, for robots without a closed form (e.g. UR arms): "
                   "'J3=10:150,J5=10:150' (deg; mm for prismatic joints).")
@click.option("--overwrite", is_flag=True, help="Replace an existing network file.")
def ik_train(robot, samples, seed, out, generations, population, no_tune, joint_box, overwrite):
    """Train a learned IK seed (GA-RBF network) for ROBOT on one configuration branch and save it."""
    from ..io.ik_network import default_network_path, save_ik_network
    from ..kinematics.ik_analytic import NotAnalyticError
    from ..kinematics.ik_net import joint_box_branch, train_ik_network
    from ..robots.loader import robot_path

    model = _robot(robot)
    if model.n_joints != 6:
        raise click.ClickException(f"{model.name}: ik-train supports 6-joint arms, this robot has {model.n_joints}")
    if samples < 500:
        raise click.ClickException(f"--samples must be at least 500, got {samples}")
    if population < 4 or generations < 0:
        raise click.ClickException("--population must be at least 4 and --generations at least 0")
    if out is None:
        rp = Path(str(robot_path(robot)))
        out = default_network_path(rp) if Path(robot).suffix.lower() in (".toml", ".urdf") or Path(robot).exists() \
            else Path(f"{model.name}.iknet.npz")
    out = Path(out)
    from ..io.output_paths import check_outputs

    try:
        check_outputs(out, {"the robot file": robot}, overwrite=overwrite)
    except FileExistsError as exc:
        raise click.ClickException(str(exc)) from None

    def progress(stage, text):
        click.echo(f"[{stage}] {text}", err=True)

    branch = None
    if joint_box is not None:
        try:
            branch = joint_box_branch(model, _parse_box(model, joint_box))
        except ValueError as exc:
            raise click.ClickException(f"--joint-box: {exc}") from None
    try:
        net = train_ik_network(model, samples, seed, tune=not no_tune, population=population,
                               generations=generations, branch=branch, progress=progress)
    except NotAnalyticError as exc:
        raise click.ClickException(f"{exc}; on the command line: --joint-box") from None
    except ImportError as exc:
        raise click.ClickException(f"{exc} (or pass --no-tune)") from None
    save_ik_network(out, net, overwrite=overwrite)
    st = net.stats
    click.echo(f"{model.name}: branch {net.branch.name}, {net.structure.n_centres} centres, "
               f"trained in {st['train_seconds']:.1f} s")
    click.echo(f"validation ({st['n_validation']} poses)   median      p95      max")
    for key, label in (("joint_deg", "joint error [deg]"), ("position_mm", "position error [mm]"),
                       ("rotation_deg", "rotation error [deg]")):
        v = st[key]
        click.echo(f"  {label:<22}{v['median']:9.2f}{v['p95']:9.2f}{v['max']:9.2f}")
    click.echo(f"wrote {out}")
    set_json_result({"robot": model.name, "branch": net.branch.name, "centres": net.structure.n_centres,
                     "file": out, "stats": st})


def _parse_box(model, text):
    """``'J3=10:150,J5=10:150'`` -> {name: (low, high)} in rad (revolute, given in deg) or mm."""
    import math

    ranges = {}
    pris = dict(zip(model.controller_joints, model.prismatic_joints))
    for item in filter(None, (t.strip() for t in text.split(","))):
        name, sep, rng = item.partition("=")
        lo_s, sep2, hi_s = rng.partition(":")
        try:
            lo, hi = float(lo_s), float(hi_s)
        except ValueError:
            lo = hi = math.nan
        if not sep or not sep2 or not (math.isfinite(lo) and math.isfinite(hi)) or hi <= lo:
            raise ValueError(f"{item!r}: expected NAME=LOW:HIGH with LOW < HIGH (deg), e.g. J3=10:150")
        name = name.strip()
        scale = 1.0 if pris.get(name, False) else math.pi / 180.0
        ranges[name] = (lo * scale, hi * scale)
    if not ranges:
        raise ValueError("no joint ranges given")
    return ranges
