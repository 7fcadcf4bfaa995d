"""``robocal closed-chain ...``: calibration with a laser pointer held on plate targets (no instrument)."""

from __future__ import annotations

import click

from ._common import _names, _step_printer, _user_error, allow_unconverged_option
from ._json import json_option, set_json_result
from .calibrate_inputs import finish_calibration
from .calibrate_table import parameter_table


@click.group("closed-chain")
def closed_chain():
    """Virtual closed kinematic chain: a laser pointer on the flange held on fixed plate targets
    (METHODS.md section 3, docs/closed-chain.md)."""


@closed_chain.command("simulate")
@json_option
@click.argument("robot")
@click.option("--plates", default=2, show_default=True, help="Plate positions (1-4).")
@click.option("--targets", default=5, show_default=True, type=click.IntRange(1, 1000),
              help="Targets per plate (a row; at most 1000).")
@click.option("--configurations", default=8, show_default=True, type=click.IntRange(1, 1000),
              help="Configurations per target (at most 1000).")
@click.option("--spacing", "spacing_mm", default=50.0, show_default=True, help="Distance between targets [mm].")
@click.option("--distance-tolerance", "tolerance_mm", default=0.1, show_default=True, metavar="MM",
              help="Detection tolerance: the spot lies within this of the mark [mm].")
@click.option("--joint-noise", "resolution_deg", default=0.001, show_default=True, metavar="DEG",
              help="Controller joint resolution and reading noise [deg].")
@click.option("--seed", default=0, show_default=True, help="Seed of the true robot, the laser mount and the holding.")
@click.option("--out", "out_file", required=True, type=click.Path(dir_okay=False),
              help="Held-spot CSV file (robocal-spots/1); the truth goes to <name>.truth.json next to it.")
@click.option("--overwrite", is_flag=True, help="Replace existing files.")
@click.option("--effects", type=click.Choice(["ideal", "realistic"]), default="ideal", show_default=True,
              help="Effects the geometric model lacks. ideal: the cell documented so far (a 0.0005 deg cyclic "
                   "joint error only). realistic: reducer transmission error 0.005/0.003 deg once/twice per "
                   "revolution, gravity sag of J2/J3 (3 mrad/kNm; up to ~0.014 deg), arm growth 20 ppm over the "
                   "session (docs/closed-chain.md); recorded in the truth file.")
def simulate_cmd(robot, plates, targets, configurations, spacing_mm, tolerance_mm, resolution_deg, seed, out_file,
                 overwrite, effects):
    """Simulate holding a laser spot on plate targets with ROBOT (hidden true parameters)."""
    from ..workflows.calibration.closed_chain import simulate_closed_chain

    try:
        r = simulate_closed_chain(robot, out_file, plates=plates, targets=targets, configurations=configurations,
                                  spacing_mm=spacing_mm, tolerance_mm=tolerance_mm,
                                  joint_resolution_deg=resolution_deg, seed=seed, overwrite=overwrite,
                                  effects=effects)
    except (ValueError, KeyError, OSError, RuntimeError) as exc:
        raise _user_error(exc) from None
    click.echo(f"simulated {r['n_rows']} held spots of {r['robot']} ({plates} plate position(s) x {targets} targets "
               f"x {configurations} configurations, tolerance {tolerance_mm} mm, seed {seed}, effects {effects})")
    click.echo(f"wrote {r['spots']} and {r['truth']}")
    set_json_result(r)


@closed_chain.command("calibrate")
@json_option
@click.argument("robot")
@click.argument("spots", type=click.Path(dir_okay=False))
@click.option("--out", "out_dir", required=True, type=click.Path(file_okay=False),
              help="Folder for result.json, calibrated_robot.toml/.urdf and report.html (created if needed).")
@click.option("--target-spacing", "target_spacing_mm", type=float, default=None, metavar="MM",
              help="Known distance between consecutive targets of a plate [mm]: fixes the length scale.")
@click.option("--spacing-sigma", "spacing_sigma_mm", default=0.02, show_default=True,
              help="Uncertainty of --target-spacing [mm].")
@click.option("--noise", "sigma_mm", type=float, default=None, metavar="MM",
              help="Spread of a held spot per in-plate axis [mm] (default: half the file's spot_tolerance_mm).")
@click.option("--free", "free", multiple=True, metavar="NAMES", help="Parameters to identify (comma separated).")
@click.option("--free-all", is_flag=True, help="Identify every kinematic parameter.")
@click.option("--fix", "fix", multiple=True, metavar="NAMES", help="Parameters to hold at nominal.")
@click.option("--holdout", default=0.2, show_default=True,
              help="Share of each spot's configurations held out for validation.")
@click.option("--seed", default=0, show_default=True, help="Seed of the calibration/held-out split.")
@click.option("--max-iterations", default=1000, show_default=True,
              help="Iteration limit of the solver; a fit that stops there did not converge (exit 4).")
@allow_unconverged_option
@click.option("--no-report", is_flag=True, help="Do not write report.html.")
@click.option("--force", is_flag=True, help="Write the calibrated robot files even when the sanity gates fail.")
@click.option("--overwrite", is_flag=True, help="Replace existing output files.")
def calibrate_cmd(robot, spots, out_dir, target_spacing_mm, spacing_sigma_mm, sigma_mm, free, free_all, fix, holdout,
                  seed, max_iterations, allow_unconverged, no_report, force, overwrite):
    """Calibrate ROBOT from SPOTS, a held-spot file (robocal-spots/1). Exit codes as `robocal calibrate`."""
    from ..workflows.calibration.closed_chain import run_closed_chain_calibration

    try:
        r = run_closed_chain_calibration(robot, spots, out_dir, target_spacing_mm=target_spacing_mm,
                                         spacing_sigma_mm=spacing_sigma_mm, sigma_mm=sigma_mm, holdout=holdout,
                                         seed=seed, free=_names(free) or None, free_all=free_all, fix=_names(fix),
                                         overwrite=overwrite, report=not no_report, force=force,
                                         max_iterations=max_iterations, progress=_step_printer,
                                         allow_unconverged=allow_unconverged)
    except (ValueError, KeyError, OSError) as exc:
        raise _user_error(exc) from None
    res = r["result"]
    cc = res["closed_chain"]
    summary = r["calibration_result"].summary().splitlines()
    click.echo(summary[0])
    click.echo(f"E_OP (mean in-plate spot error, eq. 6): {cc['E_OP_before_mm']:.4f} mm before, "
               f"{cc['E_OP_after_mm']:.4f} mm after ({cc['n_spots']} spots)")
    click.echo("")
    for line in parameter_table(res):
        click.echo(line)
    click.echo("")
    click.echo("identifiability:")
    for f in cc["findings"]:
        held = ", ".join(f["parameters_held"]) or "-"
        click.echo(f"  {f['what']:<16}{'identifiable' if f['identifiable'] else 'NOT identifiable':<18}held: {held}")
        if not f["identifiable"]:
            click.echo(f"  {'':<16}to recover: {f['to_recover']}")
    if res.get("validation"):
        v = res["validation"]
        click.echo(f"held-out spots: in-plate error RMS {v['before']['rms']:.4f} mm before, {v['after']['rms']:.4f} mm after")
    set_json_result({**res, "files": r["files"]})
    finish_calibration(r, allow_unconverged)
