"""``robocal simulate ...``: simulated measurement campaigns in the real file formats."""

from __future__ import annotations

import click

from ._common import _user_error


@click.group()
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
    from ..workflows.simulate import simulate_tracker

    if n_poses < 1:
        raise click.ClickException(f"--poses must be at least 1, got {n_poses}")
    try:
        r = simulate_tracker(robot, out_file, n_poses=n_poses, noise_mm=noise_mm, reflectors=int(reflectors),
                             joint_noise_deg=joint_noise_deg, seed=seed, overwrite=overwrite)
    except (ValueError, KeyError, OSError) as exc:
        raise _user_error(exc) from None
    click.echo(f"simulated {r['n_poses']} poses of {r['robot']} (seed {seed}, tracker noise {noise_mm} mm)")
    click.echo(f"wrote {r['measurements']} and {r['truth']}")

