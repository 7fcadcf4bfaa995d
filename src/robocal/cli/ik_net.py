"""``robocal ik-train``: train a GA-RBF IK seed network for a robot (docs/kinematics.md)."""

from __future__ import annotations

from pathlib import Path

import click

from ._common import _robot


@click.command("ik-train")
@click.argument("robot")
@click.option("--samples", default=20000, show_default=True, help="FK samples on the branch (80% train, 20% validation).")
@click.option("--seed", default=0, show_default=True, help="Seed of the sampling, the centres and the genetic algorithm.")
@click.option("--out", "out", default=None, type=click.Path(dir_okay=False),
              help="Network file (.npz). Default: next to a robot file (<robot>.iknet.npz), or "
                   "<name>.iknet.npz in the current folder for a shipped robot.")
@click.option("--generations", default=5, show_default=True, help="GA generations (0: only the initial population).")
@click.option("--population", default=10, show_default=True, help="GA population size.")
@click.option("--no-tune", is_flag=True, help="Skip the genetic algorithm; fixed structure (500 centres).")
@click.option("--overwrite", is_flag=True, help="Replace an existing network file.")
def ik_train(robot, samples, seed, out, generations, population, no_tune, overwrite):
    """Train a learned IK seed (GA-RBF network) for ROBOT on one configuration branch and save it."""
    from ..io.ik_network import default_network_path, save_ik_network
    from ..kinematics.ik_analytic import NotAnalyticError
    from ..kinematics.ik_net import train_ik_network
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
        out = default_network_path(rp) if Path(robot).suffix == ".toml" or Path(robot).exists() \
            else Path(f"{model.name}.iknet.npz")
    out = Path(out)
    if out.exists() and not overwrite:
        raise click.ClickException(f"{out}: file exists; pass --overwrite to replace it")

    def progress(stage, text):
        click.echo(f"[{stage}] {text}", err=True)

    try:
        net = train_ik_network(model, samples, seed, tune=not no_tune, population=population,
                               generations=generations, progress=progress)
    except NotAnalyticError as exc:
        raise click.ClickException(str(exc)) from None
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
