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
@click.option("--distortion", "n_distortion",
              type=click.Choice(["auto", "4", "5", "8", "k1-k2", "k1-k3", "k1-k2-p1-p2", "k1-k3-p1-p2", "rational"]),
              default="auto", show_default=True,
              help="Brown-Conrady terms (OpenCV order k1, k2, p1, p2[, k3[, k4, k5, k6]], unitless): 'auto' picks "
                   "k1-k2, k1-k2-p1-p2, k1-k3, k1-k3-p1-p2 or rational (k1-k6, p1, p2) by held-out reprojection "
                   "(5-fold over the images); 4, 5, 8 = that many coefficients.")
@click.option("--board-shape", is_flag=True,
              help="Also estimate the board's sag along its x and y axes [mm] (a board that is not flat biases "
                   "the focal length: 1 mm moved fx by ~27 px in a rendered test).")
@click.option("--fix", multiple=True, help="Parameter held at its start value (repeatable): fx, cx, k3, ...")
@click.option("--out", "out_dir", required=True, type=click.Path(file_okay=False),
              help="Folder for camera.json, camera.yaml (ROS), camera_calibration.json and report.html (created if "
                   "needed; not the images' folder).")
@click.option("--overwrite", is_flag=True, help="Replace earlier results in the folder.")
@click.option("--force", is_flag=True,
              help="Write camera.json/camera.yaml even when the result FAILS the sanity gate (exit code 3 all the same).")
@click.option("--json", "as_json", is_flag=True, help="Print the summary as JSON on stdout (the files are written too).")
@allow_unconverged_option
def calibrate_cmd(images_dir, board, model, n_distortion, board_shape, fix, out_dir, overwrite, force, as_json,
                  allow_unconverged):
    """Calibrate a camera from the images in IMAGES_DIR (intrinsics, distortion, 1-sigma).

    Exit code 3 (no camera.json) when the sanity gate fails, unless --force; exit code 4 (and no
    camera.json/.yaml) when the fit did not converge, unless --allow-unconverged."""
    from ..workflows.convergence import Convergence

    from ..handeye import HandEyeError
    from ..workflows.cameras.camera_calibrate import calibrate_camera_images

    try:
        s = calibrate_camera_images(images_dir, board, out_dir=out_dir, model=model, n_distortion=n_distortion,
                                    fix=fix, overwrite=overwrite, allow_unconverged=allow_unconverged,
                                    progress=_item_progress, force=force, board_shape=board_shape)
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
    sel = s.get("distortion_selection")
    if sel:
        scores = ", ".join(f"{k} {v:.4f}" for k, v in sel["held_out_rms_px"].items())
        click.echo(f"distortion model {s['distortion_model']} (held-out RMS over {sel['folds']} folds [px]: {scores})")
    elif s.get("distortion_model"):
        click.echo(f"distortion model {s['distortion_model']}")
    if s.get("corner_set_rms_px"):
        click.echo(f"corners: {s['corners']} (RMS [px] " + ", ".join(
            f"{k} {v:.4f}" for k, v in s["corner_set_rms_px"].items()) + ")")
    units = cam.get("parameter_units", {})
    for name, value in cam["parameters"].items():
        sigma = cam["sigma"].get(name)
        unit = units.get(name, "")
        unit = f" {unit}" if unit == "px" else " (unitless)"
        flag = "  NOT DETERMINED (1-sigma > |value|)" if name in s.get("not_determined", {}) else ""
        held = sigma is None or sigma != sigma
        click.echo(f"  {name:>5s} {value:14.6f}" + ("" if held else f"  +- {sigma:.6f}") + unit
                   + ("  held" if held else "") + flag)
    sag = s.get("board_sag_mm")
    if sag:
        click.echo(f"  board sag {sag['x']:+.4f} mm along x (+- {sag['sigma_x']:.4f} mm), {sag['y']:+.4f} mm along y "
                   f"(+- {sag['sigma_y']:.4f} mm), middle against the outermost points")
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
