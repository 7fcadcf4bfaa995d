"""``robocal simulate ...``: simulated measurement campaigns in the real file formats."""

from __future__ import annotations

import click

from ._common import _item_progress, _user_error
from ._json import json_option, set_json_result


@click.group()
def simulate():
    """Simulated measurement campaigns (files in the real formats, with the hidden truth)."""


@simulate.command("tracker")
@json_option
@click.argument("robot")
@click.option("--poses", "n_poses", default=100, show_default=True, type=click.IntRange(1, 1_000_000),
              help="Number of random poses (at most 1,000,000).")
@click.option("--noise", "noise_mm", default=0.02, show_default=True, metavar="MM", help="Tracker noise per coordinate [mm].")
@click.option("--reflectors", type=click.Choice(["1", "3"]), default="1", show_default=True,
              help="Reflectors on the flange (3: the file also holds the flange orientation).")
@click.option("--joint-noise", "joint_noise_deg", default=0.0, show_default=True, metavar="DEG", help="Encoder noise [deg].")
@click.option("--seed", default=0, show_default=True, help="Seed of the true parameters, tracker placement and poses.")
@click.option("--out", "out_file", required=True, type=click.Path(dir_okay=False),
              help="Measurement CSV file; the truth goes to <name>.truth.json next to it.")
@click.option("--overwrite", is_flag=True, help="Replace existing files.")
@click.option("--cell", "cell_file", default=None, type=click.Path(dir_okay=False, exists=True),
              help="Cell file (robocal-cell/1, docs/cells.md; lengths in its length_unit); default: the robot on "
                   "the floor, the floor an obstacle, the tracker as instrument.")
@click.option("--effects", type=click.Choice(["ideal", "realistic"]), default="ideal", show_default=True,
              help="Effects the geometric model lacks. ideal: the true robot is a geometric model (figures "
                   "documented so far). realistic: reducer transmission error 0.005/0.003 deg once/twice per "
                   "revolution, arm growth 20 ppm over the campaign, tracker scale error 5 ppm (docs/testing.md); "
                   "recorded in the truth file and applied by `robocal simulate execute`.")
def simulate_tracker_cmd(robot, n_poses, noise_mm, reflectors, joint_noise_deg, seed, out_file, overwrite, cell_file,
                         effects):
    """Simulate a laser-tracker campaign of ROBOT with hidden true parameters."""
    from ..workflows.calibration.simulate import simulate_tracker

    if n_poses < 1:
        raise click.ClickException(f"--poses must be at least 1, got {n_poses}")
    try:
        r = simulate_tracker(robot, out_file, n_poses=n_poses, noise_mm=noise_mm, reflectors=int(reflectors),
                             joint_noise_deg=joint_noise_deg, seed=seed, overwrite=overwrite, cell=cell_file,
                             effects=effects)
    except (ValueError, KeyError, OSError) as exc:
        raise _user_error(exc) from None
    click.echo(f"simulated {r['n_poses']} poses of {r['robot']} (seed {seed}, tracker noise {noise_mm} mm, "
               f"effects {effects})")
    click.echo(f"wrote {r['measurements']} and {r['truth']}")
    set_json_result(r)



@simulate.command("camera")
@json_option
@click.option("--out", "out_dir", required=True, type=click.Path(file_okay=False),
              help="Folder for images/, flange_poses.csv, camera.json and truth.json.")
@click.option("--board", default="charuco:9x7:30mm:22mm:DICT_5X5_100", show_default=True,
              help="Board spec (docs/handeye.md): checkerboard:9x6:25mm, charuco:5x7:36.195mm:18.256mm:DICT_6X6_250, "
                   "circles:10x10:25.4mm:modified.")
@click.option("--eye-in-hand/--eye-to-hand", "eye_in_hand", default=True, show_default=True,
              help="Camera on the flange (board fixed) or fixed in the cell (board on the flange).")
@click.option("--images", "n_images", default=15, show_default=True, type=click.IntRange(1, 1000),
              help="Number of images (robot poses; at most 1000).")
@click.option("--pose-noise", "pose_noise_mm", default=0.05, show_default=True, metavar="MM",
              help="Robot pose noise per axis, positions [mm].")
@click.option("--pose-angle-noise", "pose_noise_deg", default=0.01, show_default=True, metavar="DEG",
              help="Robot pose noise per axis, rotations [deg].")
@click.option("--orientation", "convention", default="kuka_abc", show_default=True,
              help="Orientation convention of flange_poses.csv (a robocal.transforms.POSE_CONVENTIONS name).")
@click.option("--length-unit", type=click.Choice(["mm", "m"]), default="mm", show_default=True,
              help="Unit of the positions written to flange_poses.csv [mm or m].")
@click.option("--angle-unit", type=click.Choice(["deg", "rad"]), default="deg", show_default=True,
              help="Unit of the angles written to flange_poses.csv [deg or rad].")
@click.argument("robot", default=None, required=False)
@click.option("--joint-offset-sigma", "joint_offset_sigma_deg", default=0.05, show_default=True, metavar="DEG",
              help="With ROBOT: spread of the robot's true joint zero offsets around its robot file [deg].")
@click.option("--seed", default=0, show_default=True, help="Seed of the truth, the poses and the image noise.")
@click.option("--overwrite", is_flag=True, help="Replace the files of an earlier run in the folder.")
def simulate_camera_cmd(out_dir, board, eye_in_hand, n_images, pose_noise_mm, pose_noise_deg, convention,
                        length_unit, angle_unit, robot, joint_offset_sigma_deg, seed, overwrite):
    """Render a hand-eye cell: PNG images of a board (1280x1024, lens distortion, blur, lighting,
    noise), the flange poses as a CSV in a named convention, the camera and the hidden truth. With
    ROBOT (shipped name or robot file) also joints.csv: that robot's joints at every image."""
    from ..workflows.cameras.camera_simulate import simulate_camera

    if n_images < 1:
        raise click.ClickException(f"--images must be at least 1, got {n_images}")
    try:
        r = simulate_camera(out_dir, board=board, setup="eye_in_hand" if eye_in_hand else "eye_to_hand",
                            n_images=n_images, pose_noise_mm=pose_noise_mm, pose_noise_deg=pose_noise_deg,
                            convention=convention, length_unit=length_unit, angle_unit=angle_unit, robot=robot,
                            joint_offset_sigma_deg=joint_offset_sigma_deg, seed=seed,
                            overwrite=overwrite, progress=_item_progress)
    except (ValueError, KeyError, OSError, RuntimeError) as exc:
        raise _user_error(exc) from None
    click.echo(f"rendered {r['n_images']} images of {r['board']} ({r['setup']}, seed {seed})")
    joints = "" if r["joints"] is None else f"{r['joints']}, "
    click.echo(f"wrote {r['images']}/, {r['poses']}, {joints}{r['camera']} and {r['truth']}")
    set_json_result(r)


@simulate.command("self-calibration")
@json_option
@click.argument("robot")
@click.option("--out", "out_dir", required=True, type=click.Path(file_okay=False),
              help="Folder for images/, joint_log.csv, frames.csv, camera.json and truth.json.")
@click.option("--images-per-chain", "n_images", default=40, show_default=True, type=click.IntRange(1, 1000),
              help="Images with the full board per chain (board-holding hand, or the fixed board).")
@click.option("--chains", default=None,
              help="Comma-separated end effectors holding a board, or 'world' (board fixed, camera on the "
                   "flange). Default: left_hand,right_hand for a robot with camera_top (nao_h25), else world.")
@click.option("--board", default=None,
              help="Board spec (docs/handeye.md). Default checkerboard:7x4:12mm in a hand, checkerboard:9x6:25mm "
                   "fixed in the world.")
@click.option("--joint-offsets", "joint_offsets_deg", default=3.0, show_default=True, metavar="DEG",
              help="True joint zero offsets: uniform within +- this [deg], on every joint moving the camera or a board.")
@click.option("--length-sigma", "length_sigma_mm", default=0.0, show_default=True, metavar="MM",
              help="Spread of true link lengths [mm].")
@click.option("--joint-noise", "joint_noise_deg", default=0.05, show_default=True, metavar="DEG", help="Joint reading noise per log row [deg].")
@click.option("--partial-fraction", default=0.1, show_default=True,
              help="Extra images per chain showing the board only partly, as a fraction of --images-per-chain.")
@click.option("--board-bow", "board_bow_mm", default=0.0, show_default=True, metavar="MM",
              help="Bend the board: its middle this far out of the plane of its ends [mm] (a flat-board model "
                   "does not contain it; 0.4 mm moves NAO corners by ~2 px).")
@click.option("--clock-offset", "clock_offset_s", default=0.035, show_default=True, metavar="S",
              help="Camera clock minus robot clock [s] (frames.csv vs joint_log.csv).")
@click.option("--jitter", "jitter_s", default=0.004, show_default=True, metavar="S", help="Capture time jitter [s].")
@click.option("--log-rate", "log_rate_hz", default=20.0, show_default=True, metavar="HZ",
              help="Joint log sampling rate [Hz].")
@click.option("--seed", default=0, show_default=True, help="Seed of the truth, the poses, the noise and the images.")
@click.option("--overwrite", is_flag=True, help="Replace the files of an earlier run in the folder.")
def simulate_self_calibration_cmd(robot, out_dir, n_images, chains, board, joint_offsets_deg, length_sigma_mm,
                                  joint_noise_deg, partial_fraction, board_bow_mm, clock_offset_s, jitter_s,
                                  log_rate_hz, seed, overwrite):
    """Simulate a camera self-calibration run of ROBOT: its own camera photographs a board held in a
    hand (nao_h25) or fixed in the world (a 6R arm, camera on the flange); rendered PNG images, a
    time-stamped joint log, the frames' capture times, the camera and the hidden truth."""
    from ..workflows.cameras.self_calibration_simulate import simulate_self_calibration_files

    if n_images < 1:
        raise click.ClickException(f"--images-per-chain must be at least 1, got {n_images}")
    if log_rate_hz <= 0:
        raise click.ClickException(f"--log-rate must be positive [Hz], got {log_rate_hz}")
    chain_list = None if chains is None else tuple(c.strip() for c in chains.split(",") if c.strip())
    try:
        r = simulate_self_calibration_files(
            robot, out_dir, chains=chain_list, board=board, n_images_per_chain=n_images,
            joint_offsets_deg=joint_offsets_deg, length_sigma_mm=length_sigma_mm, joint_noise_deg=joint_noise_deg,
            partial_fraction=partial_fraction, board_bow_mm=board_bow_mm, clock_offset_s=clock_offset_s,
            jitter_s=jitter_s,
            log_rate_hz=log_rate_hz, seed=seed, overwrite=overwrite,
            progress=_item_progress)
    except (ValueError, KeyError, OSError, RuntimeError) as exc:
        raise _user_error(exc) from None
    where = "fixed in the world" if r["chains"] == ("world",) else "held by " + ", ".join(r["chains"])
    click.echo(f"rendered {r['n_images']} images ({r['n_full']} with the full board) of {r['board']} {where} "
               f"({r['robot']}, seed {seed})")
    click.echo(f"wrote {out_dir}/images/, joint_log.csv, frames.csv, camera.json and truth.json")
    set_json_result(r)


from .simulate_execute import execute_cmd  # noqa: E402

simulate.add_command(execute_cmd)
