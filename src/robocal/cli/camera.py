"""``robocal camera calibrate``: camera intrinsics from images of a board (issue 14)."""

from __future__ import annotations

import json

import click

from ._common import EXIT_FAILED_RESULT, _item_progress, _user_error, allow_unconverged_option, finish_convergence

BOARD_HELP = ("Board spec (docs/handeye.md, 'Boards'): checkerboard:9x6:25mm (inner corners), "
              "charuco:5x7:36.195mm:18.256mm:DICT_6X6_250 (squares), circles:10x10:25.4mm[:modified] (dots).")


@click.group()
def camera():
    """Camera calibration from images of a board."""


@camera.command("calibrate")
@click.argument("images_dir", type=click.Path(path_type=str))  # existence and kind checked by io (one-line errors)
@click.option("--board", required=True, help=BOARD_HELP)
@click.option("--model", type=click.Choice(["brown", "division"]), default="brown", show_default=True,
              help="Distortion model: OpenCV's Brown-Conrady or HALCON's division model.")
@click.option("--distortion", "n_distortion", type=click.Choice(["4", "5", "8"]), default="5", show_default=True,
              help="Number of Brown-Conrady coefficients (OpenCV order k1, k2, p1, p2[, k3[, k4, k5, k6]]).")
@click.option("--fix", multiple=True, help="Parameter held at its start value (repeatable): fx, cx, k3, ...")
@click.option("--out", "out_dir", default=None, type=click.Path(file_okay=False),
              help="Folder for camera.json, camera.yaml (ROS), camera_calibration.json and report.html.")
@click.option("--overwrite", is_flag=True, help="Replace earlier results in the folder.")
@click.option("--force", is_flag=True,
              help="Write camera.json/camera.yaml even when the result FAILS the sanity gate (exit code 3 all the same).")
@click.option("--json", "as_json", is_flag=True, help="Print the summary as JSON.")
@allow_unconverged_option
def calibrate_cmd(images_dir, board, model, n_distortion, fix, out_dir, overwrite, force, as_json, allow_unconverged):
    """Calibrate a camera from the images in IMAGES_DIR (intrinsics, distortion, 1-sigma).

    Exit code 3 (no camera.json) when the sanity gate fails, unless --force; exit code 4 (and no
    camera.json/.yaml) when the fit did not converge, unless --allow-unconverged."""
    from ..workflows.convergence import Convergence

    from ..handeye import HandEyeError
    from ..workflows.camera_calibrate import calibrate_camera_images

    try:
        s = calibrate_camera_images(images_dir, board, out_dir=out_dir, model=model, n_distortion=int(n_distortion),
                                    fix=fix, overwrite=overwrite, allow_unconverged=allow_unconverged,
                                    progress=_item_progress, force=force)
    except (ValueError, HandEyeError, OSError) as exc:
        raise _user_error(exc) from None
    if as_json:
        from ..calib.outputs import json_ready

        click.echo(json.dumps(json_ready(s), indent=2))
        _exit_on_failed_gate(s)
        finish_convergence(Convergence.from_dict(s["convergence"]), allow_unconverged)
        return
    cam = s["camera"]
    click.echo(f"camera calibration: {s['n_images_used']} of {s['n_images']} images, {s['n_corners']} corners, "
               f"RMS {s['reprojection_rms_px']:.3f} px ({'converged' if s['converged'] else 'NOT converged'})")
    for name, value in cam["parameters"].items():
        sigma = cam["sigma"].get(name)
        click.echo(f"  {name:>5s} {value:14.6f}" + ("" if sigma is None else f"  +- {sigma:.6f}"))
    echo_findings(s, out_dir)
    _exit_on_failed_gate(s)
    finish_convergence(Convergence.from_dict(s["convergence"]), allow_unconverged)


def _exit_on_failed_gate(s: dict) -> None:
    """``FAILED:`` with the reasons on stderr and exit code 3 when the sanity gate failed."""
    if s.get("status", "ok") == "ok":
        return
    click.echo("FAILED: the camera calibration did not pass the sanity gate (exit code 3"
               + ("" if "camera.json" in (s.get("outputs") or {}) else ", no camera.json written") + "):", err=True)
    for reason in s.get("reasons", []):
        click.echo(f"  - {reason}", err=True)
    raise SystemExit(EXIT_FAILED_RESULT)


def echo_findings(s: dict, out_dir) -> None:
    """The skipped images, the identifiability findings and the files written."""
    for r in s["images"]:
        if not r["used"]:
            click.echo(f"  skipped {r['name']}: {r['skip_reason']}")
    for line in s["identifiability"]:
        click.echo(f"  identifiability: {line}")
    if out_dir:
        click.echo(f"wrote {', '.join(s.get('outputs', {}).values())}")
