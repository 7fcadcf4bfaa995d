"""The ROS-Industrial calibration data layout (``industrial_calibration``'s ``cal_data.yaml``;
issue 14, docs/handeye.md "ROS-Industrial cal_data.yaml").

``cal_data.yaml`` lists observations ``data: [{image: images/0.png, pose: poses/0.yaml}, ...]``
(paths relative to the YAML file), the target finder (``target_finder: {type:
CharucoGridTargetFinder | ModifiedCircleGridTargetFinder, ...}``), the camera ``intrinsics: {fx,
fy, cx, cy}`` [px] (no distortion in this layout), the initial guesses
``camera_mount_to_camera_guess`` / ``target_mount_to_target_guess`` and ``static_camera``. Each
pose file holds ``x, y, z`` [m] and ``qx, qy, qz, qw`` (Hamilton, scalar last): the flange
(tool0) in the robot base. Everything is converted here to mm and 4x4 transforms; the numbers are
checked against the units the layout declares (metres) and quaternions must be unit length.

Errors are :class:`CalDataError` naming the file and the YAML key; a missing image or pose file
raises ``FileNotFoundError`` naming the entry of ``data`` that refers to it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..camera import Camera
from ..transforms import transform_from_pose
from .boards import ARUCO_DICTIONARIES, Board, BoardSpecError
from .detection import BlobSettings
from .header import FileFormatError, read_text
from .plausibility import REACH_LARGEST_MM, length_unit_problem

__all__ = ["CalDataError", "RosCalibrationData", "read_cal_data", "read_ros_pose"]


class CalDataError(FileFormatError):
    """A ``cal_data.yaml`` or one of its pose files is malformed (file and key in the message)."""


@dataclass(frozen=True, eq=False)
class RosCalibrationData:
    """A ``cal_data.yaml`` read into robocal's units.

    path: the YAML file; image_paths: N image files; pose_paths: N pose files; labels: N image
    stems; T_base_flange (N, 4, 4) [mm]; board; blob_settings (circle grids) or None; camera:
    from ``intrinsics`` (no distortion) or None; setup: ``"eye_to_hand"`` (``static_camera:
    true``) or ``"eye_in_hand"``; camera_guess, target_guess: (4, 4) [mm] or None, the
    ``camera_mount_to_camera_guess`` / ``target_mount_to_target_guess``; homography_threshold [px]
    or None.
    """

    path: Path
    image_paths: tuple
    pose_paths: tuple
    labels: tuple
    T_base_flange: np.ndarray
    board: Board
    blob_settings: BlobSettings | None
    camera: Camera | None
    setup: str
    camera_guess: np.ndarray | None
    target_guess: np.ndarray | None
    homography_threshold: float | None


def _yaml(path: Path):
    import yaml

    try:
        return yaml.safe_load(read_text(path, CalDataError))
    except yaml.YAMLError as exc:
        raise CalDataError(path, f"not valid YAML: {exc}") from None


def _number(doc: dict, key: str, path, where: str) -> float:
    if not isinstance(doc, dict) or key not in doc:
        raise CalDataError(path, f"missing key '{where}{key}'")
    v = doc[key]
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
        raise CalDataError(path, f"key '{where}{key}': expected a finite number, got {v!r}")
    return float(v)


def _pose(doc: dict, path, where: str = "") -> np.ndarray:
    """(4, 4) [mm] from ``x, y, z`` [m] and ``qx, qy, qz, qw``."""
    vals = [_number(doc, k, path, where) for k in ("x", "y", "z", "qw", "qx", "qy", "qz")]
    q = np.array(vals[3:])
    if abs(np.linalg.norm(q) - 1.0) > 1e-3:
        raise CalDataError(path, f"'{where}qx, qy, qz, qw' is not a unit quaternion (norm {np.linalg.norm(q):.6g})")
    return transform_from_pose(vals, "quaternion", "m")


def read_ros_pose(path) -> np.ndarray:
    """One ROS-Industrial pose file: (4, 4) [mm] (flange in base)."""
    path = Path(path)
    doc = _yaml(path)
    if not isinstance(doc, dict):
        raise CalDataError(path, "expected a mapping with x, y, z [m] and qx, qy, qz, qw")
    return _pose(doc, path)


def _board(tf, path) -> tuple[Board, BlobSettings | None]:
    if not isinstance(tf, dict) or "type" not in tf:
        raise CalDataError(path, "missing 'target_finder' with a 'type'")
    kind = tf["type"]
    try:
        if kind == "CharucoGridTargetFinder":
            rows, cols = int(_number(tf, "rows", path, "target_finder.")), int(_number(tf, "cols", path, "target_finder."))
            square = _number(tf, "chessboard_dim", path, "target_finder.")
            marker = _number(tf, "aruco_marker_dim", path, "target_finder.")
            dictionary = int(_number(tf, "dictionary", path, "target_finder."))
            names = {v: k for k, v in ARUCO_DICTIONARIES.items()}
            if dictionary not in names:
                raise CalDataError(path, f"'target_finder.dictionary': unknown ArUco dictionary id {dictionary}")
            _check_metres(square, "target_finder.chessboard_dim", path)
            return Board("charuco", cols, rows, square * 1000.0, marker * 1000.0, names[dictionary]), None
        if kind == "ModifiedCircleGridTargetFinder":
            rows, cols = int(_number(tf, "rows", path, "target_finder.")), int(_number(tf, "cols", path, "target_finder."))
            spacing = _number(tf, "spacing", path, "target_finder.")
            _check_metres(spacing, "target_finder.spacing", path)
            return Board("circles", cols, rows, spacing * 1000.0, modified=True), _blob_settings(
                tf.get("circle_detector_params") or {})
    except BoardSpecError as exc:
        raise CalDataError(path, f"'target_finder': {exc}") from None
    raise CalDataError(path, f"'target_finder.type' {kind!r} is not supported; robocal reads "
                             "CharucoGridTargetFinder and ModifiedCircleGridTargetFinder")


def _check_metres(value_m: float, key: str, path) -> None:
    if not 1e-4 < value_m < 1.0:
        raise CalDataError(path, f"'{key}' = {value_m:g}: expected metres between 0.0001 and 1 (the layout uses "
                                 "metres; millimetres given?)")


def _blob_settings(p: dict) -> BlobSettings:
    def get(key, default):
        return p.get(key, default)

    return BlobSettings(
        min_threshold=float(get("minThreshold", 20.0)), max_threshold=float(get("maxThreshold", 220.0)),
        n_thresholds=int(get("nThresholds", 20)), min_repeatability=int(get("minRepeatability", 3)),
        min_dist_between_blobs=float(get("circleInclusionRadius", 5.0)),
        min_area=float(get("minArea", 25.0)) if get("filterByArea", True) else 1.0,
        max_area=float(get("maxArea", 5000.0)) if get("filterByArea", True) else 1e9,
        min_convexity=float(get("minConvexity", 0.95)) if get("filterByConvexity", True) else None,
        min_circularity=float(get("minCircularity", 0.8)) if get("filterByCircularity", False) else None,
        min_inertia_ratio=float(get("minInertiaRatio", 0.1)) if get("filterByInertia", False) else None,
        dark_dots=int(get("circleColor", 0)) == 0)


def read_cal_data(path) -> RosCalibrationData:
    """Read ``cal_data.yaml`` and every pose file it lists (module docstring)."""
    path = Path(path)
    if path.is_dir():
        path = path / "cal_data.yaml"
    if not path.is_file():
        raise FileNotFoundError(f"{path}: no such cal_data.yaml")
    doc = _yaml(path)
    if not isinstance(doc, dict):
        raise CalDataError(path, "expected a YAML mapping with 'data', 'target_finder' and 'intrinsics'")
    data = doc.get("data")
    if not isinstance(data, list) or not data:
        raise CalDataError(path, "missing or empty 'data' list of {image, pose} entries")
    root = path.parent
    images, poses, labels, T = [], [], [], []
    for i, entry in enumerate(data):
        if not isinstance(entry, dict) or "image" not in entry or "pose" not in entry:
            raise CalDataError(path, f"'data[{i}]': expected both 'image' and 'pose', got {entry!r}")
        img, pose = root / str(entry["image"]), root / str(entry["pose"])
        if not img.is_file():
            raise FileNotFoundError(f"{path}: 'data[{i}].image' {entry['image']!r}: no such file {img}")
        if not pose.is_file():
            raise FileNotFoundError(f"{path}: 'data[{i}].pose' {entry['pose']!r}: no such file {pose}")
        if img in images:
            raise CalDataError(path, f"'data[{i}].image' {entry['image']!r} is listed twice")
        images.append(img)
        poses.append(pose)
        labels.append(img.stem)
        T.append(read_ros_pose(pose))
    T = np.array(T)
    problem = length_unit_problem(np.linalg.norm(T[:, :3, 3], axis=1), "m", what="flange positions of the pose files",
                                  largest_mm=REACH_LARGEST_MM)
    if problem:
        raise CalDataError(path, problem)
    board, blobs = _board(doc.get("target_finder"), path)
    camera = None
    if "intrinsics" in doc:
        k = doc["intrinsics"]
        fx, fy, cx, cy = (_number(k, n, path, "intrinsics.") for n in ("fx", "fy", "cx", "cy"))
        try:
            camera = Camera(fx, fy, cx, cy, (0.0, 0.0, 0.0, 0.0, 0.0))
        except ValueError as exc:
            raise CalDataError(path, f"'intrinsics': {exc}") from None
    static = doc.get("static_camera", False)
    if not isinstance(static, bool):
        raise CalDataError(path, f"'static_camera': expected true or false, got {static!r}")
    guesses = {}
    for key in ("camera_mount_to_camera_guess", "target_mount_to_target_guess"):
        guesses[key] = _pose(doc[key], path, f"{key}.") if isinstance(doc.get(key), dict) else None
    thr = doc.get("homography_threshold")
    return RosCalibrationData(
        path=path, image_paths=tuple(images), pose_paths=tuple(poses), labels=tuple(labels), T_base_flange=T,
        board=board, blob_settings=blobs, camera=camera, setup="eye_to_hand" if static else "eye_in_hand",
        camera_guess=guesses["camera_mount_to_camera_guess"], target_guess=guesses["target_mount_to_target_guess"],
        homography_threshold=None if thr is None else float(thr))
