"""``robocal simulate camera``: rendered images of a board with flange poses and the hidden truth
(issue 14; docs/handeye.md, "Simulated cells").

Writes into one folder, all or nothing (:func:`.outputs.staged_outputs`):

* ``images/img_00.png`` ... : 8-bit grey renders (lens distortion, blur, lighting, noise);
* ``flange_poses.csv``: the controller's flange poses (with the robot's pose noise) in a named
  orientation convention and units, one row per image, ``pose`` = the image's name;
* ``joints.csv`` (with a robot): the controller's joints of every image (``robocal-program/1``,
  point names = image names) for a robot whose true joint zero offsets differ from its robot file
  by ``joint_offset_sigma_deg`` (the truth has them);
* ``camera.json``: the true camera (robocal-camera/1), standing in for a prior intrinsic calibration;
* ``truth.json``: the hidden truth: set-up, camera pose, target pose, true flange poses, noise levels, board.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np

from ...camera import Camera
from ...io.boards import board_image, parse_board
from ...io.camera_files import write_camera_json
from ...io.images import write_png
from ...io.tcp_files import write_flange_poses_csv
from ...handeye.refine import joint_offset_names
from ...io.programs.joint_table import JointProgram, write_joint_program
from ...robots import load_robot
from ...sim import VirtualRobot
from ...sim.cameras.camera_cell import SETUPS, default_camera, reachable, robot_joints, simulate_hand_eye_poses
from ...sim.cameras.camera_render import BoardRenderer, RenderSettings
from ...transforms import rotvec_from_matrix
from ..outputs import check_output_folder, staged_outputs

__all__ = ["simulate_camera", "DEFAULT_BOARD", "OUTPUT_NAMES"]

DEFAULT_BOARD = "charuco:9x7:30mm:22mm:DICT_5X5_100"
OUTPUT_NAMES = ["images", "flange_poses.csv", "joints.csv", "camera.json", "truth.json"]


def _texel_mm(board) -> float:
    """A texel size that divides the pitch (and ChArUco's marker offset) and resolves the print finely."""
    pitch = board.pitch_mm
    n = max(int(np.ceil(pitch / 0.25)), 1)
    if board.kind == "charuco":
        n = 2 * int(np.ceil(n / 2))  # the marker sits centred: keep its edges on texel boundaries when possible
    return pitch / n


def _pose_dict(T: np.ndarray, frame: str) -> dict:
    return {"frame": frame, "position_mm": [float(v) for v in T[:3, 3]],
            "rotation_vector_deg": [float(v) for v in np.degrees(rotvec_from_matrix(T[:3, :3]))],
            "matrix": [[float(v) for v in row] for row in T]}


def _robot_joints(nominal, T_true: np.ndarray, offset_sigma_deg: float, seed: int) -> dict:
    """The controller joints of a robot whose true joint zero offsets are Gaussian draws
    (``offset_sigma_deg``) around its robot file's: {model, q (N, n) [rad], offsets_deg {name: value}}."""
    true = VirtualRobot.perturbed(nominal, np.random.default_rng(np.random.SeedSequence([int(seed), 2])),
                                  length_sigma_mm=0.0, angle_sigma_deg=0.0, offset_sigma_deg=offset_sigma_deg,
                                  joint_noise_deg=0.0, joint_noise_mm=0.0).true_model
    q = robot_joints(true, T_true)
    names = joint_offset_names(nominal)
    index = {n: i for i, n in enumerate(nominal.params.names)}
    delta = {n: float(np.degrees(true.params.values[index[n]] - nominal.params.values[index[n]])) for n in names}
    return {"model": nominal, "q": q, "offsets_deg": delta}


def simulate_camera(out_dir, *, board: str = DEFAULT_BOARD, setup: str = "eye_in_hand", n_images: int = 15,
                    camera: Camera | None = None, pose_noise_mm: float = 0.05, pose_noise_deg: float = 0.01,
                    settings: RenderSettings | None = None, convention: str = "kuka_abc", length_unit: str = "mm",
                    angle_unit: str = "deg", robot=None, joint_offset_sigma_deg: float = 0.05, seed: int = 0,
                    overwrite: bool = False, progress=None) -> dict:
    """Render a simulated hand-eye cell into ``out_dir`` (module docstring).

    board: a board spec (:func:`robocal.io.boards.parse_board`); setup: ``"eye_in_hand"`` |
    ``"eye_to_hand"``; camera: the true camera (default 1280x1024, :func:`default_camera`);
    pose_noise_mm / pose_noise_deg: robot pose noise per axis; convention, length_unit, angle_unit:
    of the flange-pose file; robot: a shipped robot name or robot file: also write its joints;
    progress(i, n, text) after each image. Returns a summary dict with the truth.
    """
    if setup not in SETUPS:
        raise ValueError(f"setup must be one of {', '.join(SETUPS)}, got {setup!r}")
    if n_images < 1:
        raise ValueError(f"n_images must be at least 1, got {n_images}")
    b = parse_board(board)
    cam = camera or default_camera()
    nominal = load_robot(robot) if robot else None
    truth = simulate_hand_eye_poses(b.object_points(), setup=setup, n_images=n_images, camera=cam,
                                    front_z=b.front_z, pose_noise_mm=pose_noise_mm, pose_noise_deg=pose_noise_deg,
                                    seed=seed, accept=None if nominal is None else lambda T: reachable(nominal, T))
    joints = _robot_joints(nominal, truth.T_base_flange_true, joint_offset_sigma_deg, seed) if robot else None
    texture, affine = board_image(b, _texel_mm(b))
    renderer = BoardRenderer(cam, texture, affine, settings)
    rng = np.random.default_rng(np.random.SeedSequence([int(seed), 1]))
    labels = [f"img_{i:02d}" for i in range(n_images)]
    camera_frame, target_frame = ("flange", "base") if setup == "eye_in_hand" else ("base", "flange")
    doc = {
        "format": "robocal-handeye-truth/1", "setup": setup, "board": b.spec, "seed": int(seed),
        "camera_pose": _pose_dict(truth.camera_pose, camera_frame),
        "target_pose": _pose_dict(truth.target_pose, target_frame),
        "camera": {"fx": cam.fx, "fy": cam.fy, "cx": cam.cx, "cy": cam.cy, "distortion": list(cam.distortion),
                   "model": cam.model, "image_size": list(cam.image_size)},
        "pose_noise_mm": pose_noise_mm, "pose_noise_deg": pose_noise_deg,
        "labels": labels,
        "T_base_flange_true": truth.T_base_flange_true.tolist(),
        "T_camera_target": truth.T_camera_target.tolist(),
        "units": "mm; rotation vectors in degrees; matrices are 4x4 homogeneous",
    }
    if joints is not None:
        doc["robot"] = {"name": joints["model"].name, "joint_offsets_deg": joints["offsets_deg"],
                        "joints_file": "joints.csv: the joints the controller reports; the robot file's flange "
                                       "pose at them differs from T_base_flange_true by the true joint offsets"}
    out = Path(out_dir)
    check_output_folder(out, OUTPUT_NAMES, {"ROBOT": robot} if isinstance(robot, (str, Path)) else {}, overwrite)
    with staged_outputs(out, OUTPUT_NAMES, overwrite=overwrite) as stage:
        (stage / "images").mkdir()
        for i, (label, T) in enumerate(zip(labels, truth.T_camera_target), 1):
            write_png(stage / "images" / f"{label}.png", renderer.render(T, rng))
            if progress is not None:
                progress(i, n_images, f"rendered {label}.png")
        write_flange_poses_csv(stage / "flange_poses.csv", labels, truth.T_base_flange, convention=convention,
                               length_unit=length_unit, angle_unit=angle_unit,
                               notes=[f"simulated {setup} cell, board {b.spec}, seed {seed}",
                                      f"robot pose noise {pose_noise_mm} mm / {pose_noise_deg} deg per axis"])
        if joints is not None:
            write_joint_program(stage / "joints.csv", JointProgram(joints["q"], tuple(labels),
                                                                   tuple(joints["model"].controller_joints),
                                                                   {"angle_unit": "deg"}), joints["model"],
                                metadata={"note": f"simulated {setup} cell, seed {seed}"})
        write_camera_json(stage / "camera.json", cam)
        (stage / "truth.json").write_text(json.dumps(doc, indent=1) + "\n")
        old_images = out / "images"
        if overwrite and old_images.is_dir():
            os.replace(old_images, stage / ".replaced-images")  # removed with the staging folder
    return {"out_dir": out, "images": out / "images", "poses": out / "flange_poses.csv",
            "joints": None if joints is None else out / "joints.csv", "camera": out / "camera.json",
            "truth": out / "truth.json", "n_images": n_images, "board": b.spec, "setup": setup, "truth_data": truth}
