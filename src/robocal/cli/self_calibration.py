"""``robocal self-calibrate``: joint offsets from the robot's own camera images (issue 15)."""

from __future__ import annotations

import json

import click

from ._common import EXIT_FAILED_RESULT, _item_progress, _user_error, allow_unconverged_option, finish_convergence
from .camera import BOARD_HELP


@click.command("self-calibrate")
@click.argument("robot")
@click.option("--images", required=True, type=click.Path(path_type=str), help="Folder of the images.")
@click.option("--joints", "joints_file", required=True, type=click.Path(path_type=str),
              help="Joint log (robocal-joint-log/1, docs/joint-log-files.md).")
@click.option("--frames", "frames_file", required=True, type=click.Path(path_type=str),
              help="Capture times of the images (robocal-frames/1: image,time_s).")
@click.option("--board", required=True, help=BOARD_HELP)
@click.option("--camera-on", "camera_ee", required=True, help="The end effector that carries the camera.")
@click.option("--board-on", required=True,
              help="The end effector holding the board, 'world' for a fixed board, or several separated by commas "
                   "(e.g. left_hand,right_hand: each image goes to the nearest).")
@click.option("--camera", "camera_file", default=None, type=click.Path(path_type=str),
              help="Camera intrinsics file (default: calibrated on the same images).")
@click.option("--time-tolerance", "tolerance", type=float, default=0.05, show_default=True, metavar="S",
              help="Largest time difference [s] between an image and its joint reading.")
@click.option("--match", type=click.Choice(["nearest", "interpolate"]), default="nearest", show_default=True,
              help="Take the nearest joint reading or interpolate between the two around the capture time.")
@click.option("--link-parameter", "link_parameters", multiple=True,
              help="A further robot parameter to estimate (repeatable, e.g. a2).")
@click.option("--refine-intrinsics", is_flag=True, help="Refine the intrinsics too.")
@click.option("--joint-noise", "joint_noise_deg", type=float, default=None, metavar="DEG",
              help="1-sigma of a joint reading [deg]: per-image joint corrections (errors in variables). Default: "
                   "exact readings when the residuals fit the corner noise, else estimated (reported in the JSON).")
@click.option("--out", "out_dir", required=True, type=click.Path(file_okay=False),
              help="Folder for robot.toml, self_calibration.json, report.html (created if needed).")
@click.option("--overwrite", is_flag=True, help="Replace earlier results in the folder.")
@click.option("--force", is_flag=True,
              help="Write robot.toml even when the result FAILS the sanity gates or did not converge (same exit code).")
@click.option("--json", "as_json", is_flag=True, help="Print the result as JSON on stdout (the files are written too).")
@allow_unconverged_option
def self_calibrate(robot, images, joints_file, frames_file, board, camera_ee, board_on, camera_file, tolerance, match,
                   link_parameters, refine_intrinsics, joint_noise_deg, out_dir, overwrite, force, as_json,
                   allow_unconverged):
    """Calibrate ROBOT's joint offsets from images of a board taken by its own camera.

    Sanity gates (docs/reliability.md): residuals against what the corner noise and
    --joint-noise explain, joint offsets a mastering error can have; a failure names a camera
    clock offset or permuted frame times when the motions show one. A failed result exits 3, a
    solve that did not converge exits 4 (no robot.toml unless --allow-unconverged); a failed result
    writes no robot.toml unless --force."""

    from ..handeye import HandEyeError
    from ..workflows.cameras.self_calibration import self_calibrate as run

    try:
        s = run(robot, images=images, joints=joints_file, frames=frames_file, board=board, camera_end_effector=camera_ee,
                camera_file=camera_file, board_on=[c.strip() for c in board_on.split(",") if c.strip()],
                tolerance=tolerance, match=match,
                link_parameters=link_parameters, refine_intrinsics=refine_intrinsics,
                joint_noise_deg=joint_noise_deg, out_dir=out_dir,
                overwrite=overwrite, progress=_item_progress, force=force, allow_unconverged=allow_unconverged)
    except (ValueError, HandEyeError, OSError) as exc:
        raise _user_error(exc) from None
    if as_json:
        click.echo(json.dumps(s, indent=2))
        _finish(s, allow_unconverged)
        return
    click.echo(f"self-calibration of {s['robot']}: {s['n_images_used']} of {s['n_images']} images, reprojection RMS "
               f"{s['reprojection_rms_px']:.3f} px ({'converged' if s['converged'] else 'NOT converged'})")
    held = {r["name"]: r for r in s["joint_report"] if not r["identifiable"]}
    for j in s["joint_offsets"]:
        if j["name"] in held:
            click.echo(f"  {j['name']:>8s}: not identifiable ({held[j['name']]['why']})")
        else:
            click.echo(f"  {j['name']:>8s}: {j['value']:+.6f} {j['unit']}  (1-sigma {j['sigma']:.6f})")
    for r in s["images"]:
        if not r["used"]:
            click.echo(f"  skipped {r['name']}: {r['skip_reason']}")
    for note in s.get("notes", []):
        click.echo(f"note: {note}")
    if s.get("outputs"):
        click.echo("wrote " + ", ".join(s["outputs"].values()))
    _finish(s, allow_unconverged)


def _finish(s: dict, allow_unconverged: bool) -> None:
    """The one exit-code table: a non-converged fit is named (one ``Warning:`` line) even when the
    gates fail too; failed gates exit 3, non-convergence alone exits 4."""
    from ..workflows.convergence import Convergence

    conv = Convergence.from_dict(s["convergence"])
    if s.get("status", "ok") != "ok" and not conv.converged:
        click.echo(f"Warning: {conv.warning()}", err=True)
    _exit_status(s)
    finish_convergence(conv, allow_unconverged)


def _exit_status(s: dict) -> None:
    """Exit 3 (failed gates, reasons on stderr); non-convergence is :func:`finish_convergence`'s."""
    if s.get("status", "ok") != "ok":
        click.echo("FAILED: the self-calibration did not pass the sanity gates (exit code 3"
                   + ("" if "robot.toml" in (s.get("outputs") or {}) else ", no robot.toml written") + "):", err=True)
        for reason in s.get("reasons", []):
            click.echo(f"  - {reason}", err=True)
        raise SystemExit(EXIT_FAILED_RESULT)
