"""``robocal verify``: is the robot still what its calibration promised? ok / recalibrate / fault."""

from __future__ import annotations

import json
import sys

import click

from ._common import EXIT_FAILED_RESULT, EXIT_MECHANICAL_FAULT, _user_error
from .iso9283 import check_history_options, history_options

__all__ = ["verify"]


@click.command("verify")
@click.argument("model", type=click.Path(exists=True))
@click.argument("measurements", type=click.Path(exists=True, dir_okay=False))
@click.option("--noise", "noise_mm", metavar="MM", default=0.02, show_default=True,
              help="Instrument noise per coordinate [mm] (standard deviation).")
@click.option("--false-alarm", "false_alarm_rate", default=0.01, show_default=True,
              help="Probability that a healthy robot is flagged (the test's alpha).")
@click.option("--register", "register_frame", is_flag=True,
              help="The instrument was moved: re-fit its frame on the same poses (a J1 offset is then not checked).")
@click.option("--tool", "tool", default=None, metavar="X,Y,Z",
              help="The measured point on the flange, X,Y,Z [mm] (default: the calibration's identified target).")
@click.option("--json", "as_json", is_flag=True, help="Print the result as JSON.")
@history_options
def verify(model, measurements, noise_mm, false_alarm_rate, register_frame, tool, as_json, db, robot_id, when,
           temperature_c, instrument):
    """Check a calibrated robot (MODEL: the calibration folder or its robot file) against a few
    measured poses (MEASUREMENTS, a robocal measurement file in the calibration's instrument frame;
    optional columns approach_J1 ... hold each joint's approach direction, +1 or -1, for the
    backlash diagnosis).

    Exit 0: ok; 3: recalibrate; 6: mechanical fault suspected (a joint named)."""
    from ..errors import RobocalError
    from ..workflows.performance.verify import run_verify
    from .iso9283 import _xyz

    check_history_options(db, robot_id, when)
    point = _xyz(tool, "--tool") if tool else None
    try:
        r = run_verify(model, measurements, noise_mm=noise_mm, false_alarm_rate=false_alarm_rate,
                       register_frame=register_frame, tool_point_mm=point, temperature_c=temperature_c,
                       instrument=instrument)
        if when is not None:
            r["time"] = when
        if db is not None:
            from ..workflows.performance.iso9283_history import record_verification

            r["history"] = {"database": db, "robot_id": robot_id,
                            "cycle_id": record_verification(db, robot_id, r)}
    except (ValueError, OSError, RobocalError) as exc:
        raise _user_error(exc) from None
    if as_json:
        click.echo(json.dumps(r, indent=1))
    else:
        click.echo(f"{r['robot']}: {r['n_poses']} poses, residual RMS {r['rms_mm']:.4f} mm, max {r['max_mm']:.4f} mm")
        click.echo(f"chi2 test: T = {r['statistic']:.1f}, threshold {r['threshold']:.1f} ({r['dof']} dof, "
                   f"false-alarm rate {r['false_alarm_rate']:g}), p = {r['p_value']:.3g}")
        for reason in r["reasons"][1:]:
            click.echo(f"  {reason}")
        if "suspect_offset" in r:
            s = r["suspect_offset"]
            what = "offset jump" if r["suspect_cause"] == "offset" else "backlash"
            click.echo(f"  {r['suspect_joint']} {what} {s['value']:+.4f} ± {s['std']:.4f} {s['unit']}")
        click.echo(f"decision: {r['decision'].upper()}")
        if db is not None:
            click.echo(f"recorded in the history of {robot_id!r} (cycle {r['history']['cycle_id']})")
    if r["decision"] == "recalibrate":
        sys.exit(EXIT_FAILED_RESULT)
    if r["decision"] == "mechanical fault suspected":
        sys.exit(EXIT_MECHANICAL_FAULT)
