"""The ``robocal`` command line: thin over the library (parse, call, print).

Every user error ends in one line ``Error: ...`` and a non-zero exit code.
"""

from __future__ import annotations

import sys

import click

from ._errors import GuardedGroup
from ._json import json_option, set_json_result
from ._lazy import LazyGroup


def _attach_cross_laser(tcp):
    """The cross-laser commands live in their own module but belong to ``robocal tcp``."""
    from .tcp_cross_laser import accuracy_cmd, cross_laser_cmd, simulate_cmd

    tcp.add_command(cross_laser_cmd)
    tcp.add_command(simulate_cmd)
    tcp.add_command(accuracy_cmd)


def _attach_simulate_iso(simulate):
    """``robocal simulate iso9283`` lives with the ISO 9283 commands."""
    from .iso9283 import simulate_iso9283_cmd

    simulate.add_command(simulate_iso9283_cmd)


# Every command: (module in robocal.cli, attribute, one line in `robocal --help`, hook after loading).
# The modules are imported only when their command runs (or its help is asked for), so that
# `robocal --help` and `robocal robots` start without numba, scipy or matplotlib. The summaries are
# kept here because click would cut the docstrings' first sentences.
_COMMANDS = {
    "robots": ("kinematics", "robots", "List the robots shipped with robocal.", None),
    "fk": ("kinematics", "fk", "Forward kinematics: flange pose at given joints.", None),
    "ik": ("kinematics", "ik", "Inverse kinematics: joints for a flange pose.", None),
    "ik-train": ("ik_net", "ik_train", "Train a learned IK seed (GA-RBF network) for a robot.", None),
    "calibrate": ("calibrate", "calibrate", "Calibrate a robot's kinematics from a measurement file.", None),
    "correct": ("calibrate", "correct", "Corrected joint targets for a nominal-model controller.", None),
    "simulate": ("simulate", "simulate", "Simulated measurement campaigns with the hidden truth.",
                 _attach_simulate_iso),
    "tcp": ("tcp", "tcp", "Tool frame calibration: touch-up, light barriers, cross-laser.", _attach_cross_laser),
    "thermal": ("thermal", "thermal", "Thermal drift: system calibration, screening, compensation.", None),
    "history": ("history", "history_cmd", "A robot's calibration and maintenance history.", None),
    "import": ("importing", "import_cmd", "A tracker export and a joint log into a measurement file.", None),
    "plan-poses": ("plan", "plan_poses_cmd", "Measurement poses for a calibration, with the predicted sigma.", None),
    "camera": ("camera", "camera", "Camera intrinsics and distortion from images of a board.", None),
    "handeye": ("handeye", "handeye", "Hand-eye calibration of a camera on the flange or in the cell.", None),
    "self-calibrate": ("self_calibration", "self_calibrate", "Joint offsets from the robot's own camera images.",
                       None),
    "closed-chain": ("closed_chain", "closed_chain", "Calibration with a laser spot held on plate targets.", None),
    "fleet": ("fleet", "fleet", "Many robots at once on Dask: calibrate, studies, status.", None),
    "datasets": ("datasets", "datasets", "The real data sets: list them, rerun their protocols.", None),
    "iso9283": ("iso9283", "iso9283", "ISO 9283 performance test: plan, evaluate.", None),
    "verify": ("verify", "verify", "Check a calibrated robot with a few poses.", None),
    "controller": ("controller", "controller", "The controller's own model in and out, probed, compared.", None),
}


class _MainGroup(GuardedGroup, LazyGroup):
    """Commands loaded on first use (:class:`LazyGroup`), and no traceback from any of them
    (:class:`GuardedGroup`)."""


@click.group(cls=_MainGroup, lazy_commands=_COMMANDS, context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(package_name="robocal")
def main():
    """robocal: keep industrial robots accurate (calibration, thermal compensation, tool frames).

    Exit codes of every command (docs/cli.md): 0 success, 1 error (one 'Error:' line), 2 usage
    error, 3 a result that failed the sanity gates (docs/reliability.md), 4 the solver did not
    converge, 5 targets not reached (`correct`, `simulate execute`), 6 `verify`: a mechanical fault suspected. Deprecated option names work with a warning (docs/cli.md)."""


@main.command(short_help="The maintenance cycle on a simulated robot, with a report.")
@json_option
@click.option("--out", "out_dir", default="robocal-demo", show_default=True, type=click.Path(file_okay=False),
              help="Folder for the results (created if needed; existing results need --overwrite).")
@click.option("--seed", default=7, show_default=True, help="Seed of the simulated robot and poses.")
@click.option("--poses", default=500, show_default=True, type=click.IntRange(10, 100_000),
              help="Number of workspace poses for the accuracy maps (10 to 100,000).")
@click.option("--overwrite", is_flag=True, help="Replace the files of an earlier demo in the folder.")
def demo(out_dir, seed, poses, overwrite):
    """The accuracy-maintenance cycle on a simulated robot: the problem, geometric calibration,
    a collision and tool recalibration, with a report and a history database."""
    from ..workflows.demo import run_demo

    def progress(i, n, text):
        click.echo(f"[{i}/{n}] {text}", err=True)

    if poses < 10:
        raise click.ClickException(f"--poses must be at least 10, got {poses}")
    r = run_demo(out_dir, seed=seed, n_poses=poses, progress=progress, overwrite=overwrite)
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
    iso = r.get("iso9283")
    if iso:
        click.echo(f"5. ISO 9283 test (cube {iso['cube_edge_mm']:.0f} mm, {iso['cycles']} pose cycles, "
                   f"{iso['path_cycles']} path cycles) run by the real robot, nominal vs calibrated program:")
        click.echo(f"{'characteristic':<18}{'before':>10}{'after':>10}   [mm | deg]")
        for row in iso["comparison"]:
            if row["characteristic"] in ("AP_mm", "RP_mm", "vAP_mm", "AD_mm", "RD_mm", "AT_mm_line", "RT_mm_line",
                                         "AT_mm_circle", "AP_a_deg", "AP_c_deg"):
                click.echo(f"{row['characteristic']:<18}{row['before']:>10.3f}{row['after']:>10.3f}")
        click.echo("")
    click.echo(f"wrote {r['files']['report']}, {r['files']['result']}" + (f", history {r['history']}" if r.get("history") else ""))
    set_json_result(r)


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
