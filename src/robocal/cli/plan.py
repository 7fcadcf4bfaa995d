"""``robocal plan-poses``: which poses to measure for a calibration, with the predicted outcome."""

from __future__ import annotations

import math

import click

from ._common import _user_error
from ._grammar import POINT
from ._json import json_option, set_json_result


@click.command("plan-poses")
@json_option
@click.argument("robot")
@click.option("--count", required=True, type=click.IntRange(1, 10_000), help="Number of poses to plan (at most 10,000).")
@click.option("--candidates", default=1000, show_default=True, type=click.IntRange(1, 200_000),
              help="Feasible candidate poses to choose from (random poses within the joint limits are drawn until "
                   "this many are feasible in the cell; at most 200,000).")
@click.option("--workspace", default=None, metavar="BOX",
              help="Flange box in the robot base frame: xmin,xmax,ymin,ymax,zmin,zmax [mm].")
@click.option("--tracker-at", default=None, metavar="X,Y,Z",
              help="Tracker position in the robot base frame [mm]: poses out of range, beyond the reflector's "
                   "acceptance angle or with the beam blocked by the arm are left out.")
@click.option("--tool", type=POINT, default=None, metavar="X,Y,Z",
              help="Reflector in the flange frame [mm]  [default: the cell's, else 0,0,100].")
@click.option("--cell", "cell_file", default=None, type=click.Path(dir_okay=False, exists=True),
              help="Cell file (robocal-cell/1, docs/cells.md; lengths in its length_unit); default: the robot on the "
                   "floor, the floor an obstacle.")
@click.option("--noise", "sigma_mm", metavar="MM", default=0.02, show_default=True, type=click.FloatRange(0.0, min_open=True),
              help="Instrument noise per coordinate [mm], positive.")
@click.option("--seed", default=0, show_default=True, help="Seed of the candidate poses.")
@click.option("--out", "out_file", required=True, type=click.Path(dir_okay=False),
              help="Joint program file to write (robocal-program/1, degrees).")
@click.option("--language", type=click.Choice(["krl", "rapid", "tp", "urscript"]), default=None,
              help="Also write the campaign as a robot program next to --out (joint targets in driving order, a "
                   "wait/trigger comment at each measurement point): KUKA KRL (.dat + .src), ABB RAPID (.mod), "
                   "FANUC TP (.ls), UR script (.script); joint values in the language's unit (deg; UR: rad).")
@click.option("--overwrite", is_flag=True, help="Replace an existing output file.")
def plan_poses_cmd(robot, count, candidates, workspace, tracker_at, tool, cell_file, sigma_mm, seed, out_file,
                   language, overwrite):
    """Plan COUNT measurement poses of ROBOT (D-optimal), print the predicted parameter sigma and
    held-out accuracy, and write the poses as a joint program."""
    from ..workflows.calibration.plan_poses import parse_box, plan_poses

    try:
        box = parse_box(workspace) if workspace else None
        at = None
        if tracker_at:
            try:
                at = [float(v) for v in tracker_at.split(",")]
            except ValueError:
                at = []
            if len(at) != 3 or not all(math.isfinite(v) for v in at):
                raise ValueError(f"--tracker-at: expected three numbers x,y,z [mm] separated by commas, got "
                                 f"{tracker_at!r}")
        p = plan_poses(robot, out_file, count=count, candidates=candidates, workspace=box, tracker_at=at, tool=tool,
                       sigma_mm=sigma_mm, seed=seed, overwrite=overwrite, cell=cell_file,
                       language=language)
    except (ValueError, KeyError, OSError) as exc:
        raise _user_error(exc) from None
    click.echo(f"{count} poses of {p['model'].name} chosen from {p['n_candidates']} feasible candidates "
               f"({p['draws']} random poses drawn; cell: {p['cell'].source}) (D-optimal)")
    click.echo(f"D-efficiency against the plan without the cell: {p['d_efficiency']:.3f} "
               f"({100 * (1 - p['d_efficiency']):.1f} % of D-optimality lost per identifiable direction)")
    click.echo(f"path (largest joint move summed): {math.degrees(p['path_rad']):.0f} deg in driving order, "
               f"{math.degrees(p['path_rad_unordered']):.0f} deg in selection order; every move checked")
    click.echo(f"predicted 1-sigma at {sigma_mm} mm noise ({len(p['names'])} identifiable variables):")
    for name, unit, s in zip(p["names"], p["units"], p["std"]):
        if not (name.startswith("base.") or name.startswith("reflector.")):
            shown, u = (math.degrees(s), "deg") if unit == "rad" else (s, unit)
            click.echo(f"  {name:<12}{shown:>12.5f} {u}")
    if p["dropped"]:
        click.echo("not identifiable with these poses: " + ", ".join(n for n, _ in p["dropped"]))
    click.echo(f"predicted held-out RMS error {p['holdout_rms_mm']:.4f} mm (model {p['holdout_model_std_mm']:.4f} mm "
               f"+ noise) at the other candidates")
    click.echo(f"wrote {p['file']}" + "".join(f" and {f}" for f in p.get("program_files", [])))
    set_json_result(p)
