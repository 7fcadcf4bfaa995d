"""``robocal handeye solve``: the camera's pose on the flange or in the cell (issue 14)."""

from __future__ import annotations

import json

import click

from ._common import EXIT_FAILED_RESULT, _item_progress, _user_error, allow_unconverged_option, finish_convergence
from ._grammar import OPTIONAL_ROBOT, OptionalRobotCommand
from .camera import BOARD_HELP, echo_findings


@click.group()
def handeye():
    """Hand-eye calibration: camera on the flange (eye-in-hand) or fixed in the cell (eye-to-hand)."""


@handeye.command("solve", cls=OptionalRobotCommand)
@click.argument("robot", **OPTIONAL_ROBOT)
@click.argument("data", type=click.Path(path_type=str))
@click.option("--poses", default=None, type=click.Path(path_type=str),
              help="Flange-pose CSV (docs/tcp.md: '# orientation:', units), one row per image named like the image; "
                   "or 4x4 matrices (16 numbers per line row-major, as RobotPosesVec.txt, or 4 lines per pose) "
                   "paired with the images by order (natural sort), with --length-unit.")
@click.option("--length-unit", type=click.Choice(["m", "mm"]), default=None,
              help="Unit of the translations in a 4x4 matrix pose file [m or mm] (unless it has '# length_unit:').")
@click.option("--joints", "joints_file", default=None, type=click.Path(path_type=str),
              help="Instead of --poses: a robocal-program/1 joint table (point names = image names); the flange "
                   "poses are ROBOT's forward kinematics (ROBOT is then required).")
@click.option("--joint-offsets", is_flag=True, help="With --joints: also estimate the robot's joint zero offsets.")
@click.option("--board", default=None, help=BOARD_HELP + " With cal_data.yaml: taken from its target_finder.")
@click.option("--eye-in-hand", "setup", flag_value="eye_in_hand", default=None,
              help="Camera on the flange, board fixed (the default for --poses/--joints).")
@click.option("--eye-to-hand", "setup", flag_value="eye_to_hand", help="Camera fixed in the cell, board on the flange.")
@click.option("--method", type=click.Choice(["shah", "tsai", "park", "daniilidis"]), default="shah", show_default=True,
              help="Linear solution the refinement starts from (all are reported side by side).")
@click.option("--camera", "camera_file", default=None, type=click.Path(path_type=str),
              help="Camera file (robocal JSON, ROS or OpenCV YAML); default: cal_data's intrinsics or a calibration "
                   "on the same images.")
@click.option("--loss", type=click.Choice(["linear", "huber", "cauchy"]), default="linear", show_default=True,
              help="Robust loss per image: images that do not fit (a swapped pose) are rejected and named.")
@click.option("--refine-intrinsics", is_flag=True, help="Refine the intrinsics together with the hand-eye transform.")
@click.option("--robot-pose-sigma", default="auto", show_default=True, metavar="auto|estimate|MM,DEG",
              help="The robot's pose error per axis [mm, deg] (errors in variables): 'auto' fits the flange poses "
                   "as exact and with their noise estimated from the data and keeps the one that predicts "
                   "held-out images better (a Warning: when the two disagree beyond their sigma); 'estimate' "
                   "the estimated noise (variance components); 'MM,DEG' a fixed prior, e.g. 0.05,0.01.")
@click.option("--exact-poses", is_flag=True, help="Take the flange poses as exact (as ROS-Industrial's calibration).")
@click.option("--homography-threshold", type=float, default=None,
              help="Skip images whose detections one homography misses by more than this mean [px] "
                   "(default: cal_data.yaml's homography_threshold, else no check).")
@click.option("--out", "out_dir", required=True, type=click.Path(file_okay=False),
              help="Folder for handeye.json, handeye.yaml (ROS transform) and report.html (created if needed).")
@click.option("--overwrite", is_flag=True, help="Replace earlier results in the folder.")
@click.option("--force", is_flag=True,
              help="Write handeye.yaml even when the result FAILS the sanity gates (exit code 3 all the same).")
@click.option("--json", "as_json", is_flag=True, help="Print the result as JSON on stdout (the files are written too).")
@allow_unconverged_option
def solve_cmd(robot, data, poses, length_unit, joints_file, joint_offsets, board, setup, method, camera_file, loss,
              refine_intrinsics, robot_pose_sigma, exact_poses, homography_threshold, out_dir, overwrite, force,
              as_json, allow_unconverged):
    """Solve the hand-eye transform from images and flange poses. DATA is

    \b
    * a ROS-Industrial cal_data.yaml (or its folder): images, flange poses, board, intrinsics;
    * with --poses POSES.csv --board SPEC: the folder of the images;
    * with ROBOT and --joints JOINTS.csv --board SPEC: the folder of the images, the flange poses
      computed from the joints.

    ROBOT (a shipped name or a robot file) is given only with --joints.

    Sanity gates (docs/reliability.md): back-projection RMS against the corner noise, the screw
    invariants of every image pair (images paired with the wrong pose are named), agreement with the
    linear start. A failed result prints the reasons and likely causes, exits with code 3 and writes
    no handeye.yaml unless --force. Exit code 4 (and no handeye.yaml) when a fit did not converge,
    unless --allow-unconverged."""
    from ..workflows.convergence import Convergence

    from ..handeye import HandEyeError
    from ..workflows.cameras.handeye_solve import solve_handeye

    if poses is not None and joints_file is not None:
        raise click.UsageError("give either --poses or --joints, not both")
    if joints_file is not None and robot is None:
        raise click.UsageError("--joints needs ROBOT before DATA: robocal handeye solve ROBOT IMAGES_DIR --joints "
                               "JOINTS.csv --board SPEC --out DIR")
    if robot is not None and joints_file is None:
        raise click.UsageError(f"ROBOT {robot!r} is used only with --joints (the flange poses computed from the "
                               "joints); give DATA alone with a cal_data.yaml or --poses")
    image_form = poses is not None or joints_file is not None
    if image_form and board is None:
        raise click.UsageError("--board SPEC is needed with --poses or --joints (DATA is then the folder of the images)")
    cal_data, images = (None, data) if image_form else (data, None)
    sigma = _pose_sigma(robot_pose_sigma)
    if exact_poses:
        if robot_pose_sigma != "auto":
            raise click.UsageError("--exact-poses and --robot-pose-sigma exclude each other")
        sigma = None
    try:
        s = solve_handeye(cal_data=cal_data, poses=poses, images=images, board=board, setup=setup, method=method,
                          camera_file=camera_file, refine_intrinsics=refine_intrinsics, robot_pose_sigma=sigma,
                          homography_threshold=homography_threshold, joints=joints_file, robot=robot,
                          joint_offsets=joint_offsets, loss=loss, out_dir=out_dir,
                          overwrite=overwrite, progress=_item_progress, force=force,
                          allow_unconverged=allow_unconverged, length_unit=length_unit)
    except (ValueError, HandEyeError, OSError) as exc:
        raise _user_error(exc) from None
    for w in s.get("warnings", []):
        click.echo(f"Warning: {w}", err=True)
    if as_json:
        click.echo(json.dumps(s, indent=2))
        _exit_on_failed_gate(s)
        finish_convergence(Convergence.from_dict(s["convergence"]), allow_unconverged)
        return
    cp = s["camera_pose"]
    sig_p, sig_r = cp.get("sigma_position_mm") or [float("nan")] * 3, cp.get("sigma_rotation_deg") or [float("nan")] * 3
    click.echo(f"hand-eye ({s['setup']}): {s['n_images_used']} of {s['n_images']} images, {s['n_corners']} corners, "
               f"reprojection RMS {s['reprojection_rms_px']:.3f} px ({'converged' if s['converged'] else 'NOT converged'})")
    click.echo(f"camera in {cp['frame']}: position {_v(cp['position_mm'])} mm  (1-sigma {_v(sig_p, 3)})")
    click.echo(f"  rotation vector {_v(cp['rotation_vector_deg'], 4)} deg  (1-sigma {_v(sig_r, 4)})")
    click.echo(f"flange poses: {s['robot_pose_sigma_text']}")
    click.echo("linear solutions (start of the refinement):")
    for m, d in s["linear"].items():
        click.echo(f"  {m:>10s}  {_v(d['position_mm'])} mm, {_n(d['difference_position_mm'])} mm / "
                   f"{_n(d['difference_rotation_deg'], 3)} deg from the refined, RMS {_n(d['reprojection_rms_px'])} px")
    for r in s["images"]:
        if r.get("outlier"):
            click.echo(f"  outlier {r['name']}: {r['outlier']}")
    for name, value in (s.get("joint_offsets_deg") or {}).items():
        click.echo(f"  joint offset {name}: {value:+.4f} deg")
    echo_findings(s, out_dir)
    _exit_on_failed_gate(s)
    finish_convergence(Convergence.from_dict(s["convergence"]), allow_unconverged)


def _exit_on_failed_gate(s: dict) -> None:
    """``FAILED:`` with the reasons on stderr and exit code 3 when the sanity gates failed."""
    if s.get("status", "ok") == "ok":
        return
    click.echo("FAILED: the hand-eye result did not pass the sanity gates (exit code 3"
               + (", no handeye.yaml written" if not (s.get("outputs") or {}).get("handeye.yaml") else "") + "):",
               err=True)
    for reason in s.get("reasons", []):
        click.echo(f"  - {reason}", err=True)
    raise SystemExit(EXIT_FAILED_RESULT)


def _n(value, digits=2) -> str:
    return "nan" if value is None else f"{value:.{digits}f}"


def _pose_sigma(text: str):
    """``--robot-pose-sigma``: "auto" | "estimate" | (mm, deg) from "MM,DEG" (or "MM DEG")."""
    t = text.strip().lower()
    if t in ("auto", "estimate"):
        return t
    parts = t.replace(",", " ").split()
    try:
        values = tuple(float(v) for v in parts)
    except ValueError:
        values = ()
    if len(values) != 2 or not all(v > 0 for v in values):
        raise click.BadParameter(f"expected auto, estimate or MM,DEG (two positive numbers, e.g. 0.05,0.01), "
                                 f"got {text!r}", param_hint="--robot-pose-sigma")
    return values


def _v(values, digits=2) -> str:
    return "(" + ", ".join("nan" if v is None else f"{v:.{digits}f}" for v in values) + ")"
