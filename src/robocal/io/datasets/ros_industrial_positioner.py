"""Reader of ``ros_industrial_handeye/raw/kinematic_calibration``: a 2-axis part positioner carrying a
target, seen by a fixed camera (ROS-Industrial's industrial_calibration example data, Apache-2.0;
needs PyYAML).

``measurements.yaml``: one record per time stamp, ``target_joints`` (2 positioner joints [rad]),
``camera_joints`` (empty: the camera is fixed) and ``pose`` (``x, y, z`` [m], ``qx, qy, qz, qw``
Hamilton, scalar last): the target's pose in the camera frame, as the camera measured it.
``pose_initial_guesses.yaml``: ``camera_mount_to_camera_guess`` (the camera in the world/mount
frame) and ``target_mount_to_target_guess`` (the target on the positioner's last link), metres.

Returned as a :class:`RealDataset` in mm / rad: ``joints`` (N, 2); ``points`` (N, 1, 3) the target
origin in the camera frame [mm] (target ``"target"``); ``per_pose["T_camera_target"]`` (N, 4, 4)
[mm] the full measured poses; ``per_pose["stamp"]`` (N,) the record keys; ``metadata`` with
``T_world_camera_guess`` and ``T_mount_target_guess`` (4, 4) [mm].
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ...transforms import matrix_from_quaternion
from ._common import DatasetError, RealDataset, dataset_file, number

__all__ = ["POSITIONER_FOLDER", "read_ros_industrial_positioner"]

#: the data folder inside the data-sets root
POSITIONER_FOLDER = ("ros_industrial_handeye", "raw", "kinematic_calibration")
_MAX_RANGE_M = 20.0  # a camera-to-target distance beyond this is not in metres


def _yaml_load(p: Path):
    try:
        import yaml
    except ImportError:
        raise DatasetError(f"{p}: reading the positioner data needs PyYAML (pip install 'robocal[yaml]')") from None
    try:
        with open(p, encoding="utf-8") as fh:
            return yaml.load(fh, Loader=getattr(yaml, "CSafeLoader", yaml.SafeLoader))
    except yaml.YAMLError as exc:
        raise DatasetError(f"{p}: not valid YAML: {exc}") from None


def _pose_mm(d, where: str) -> np.ndarray:
    """(4, 4) [mm] from a ``{x, y, z, qw, qx, qy, qz}`` mapping in metres."""
    if not isinstance(d, dict):
        raise DatasetError(f"{where}: expected a mapping with x, y, z, qx, qy, qz, qw, got {d!r}")
    v = {}
    for k in ("x", "y", "z", "qw", "qx", "qy", "qz"):
        if k not in d:
            raise DatasetError(f"{where}: missing key {k!r}")
        if isinstance(d[k], bool):
            raise DatasetError(f"{where}/{k}: {d[k]!r} is not a number")
        v[k] = number(d[k], f"{where}/{k}")
    t = np.array([v["x"], v["y"], v["z"]])
    if np.linalg.norm(t) > _MAX_RANGE_M:
        raise DatasetError(f"{where}: position {t.tolist()} is not plausible in metres")
    q = np.array([v["qw"], v["qx"], v["qy"], v["qz"]])
    try:
        R = matrix_from_quaternion(q)
    except ValueError as exc:
        raise DatasetError(f"{where}: {exc}") from None
    T = np.eye(4)
    T[:3, :3], T[:3, 3] = R, t * 1000.0
    return T


def read_ros_industrial_positioner(root=None) -> RealDataset:
    """The 2-axis positioner records (see the module docstring), in file order."""
    p = dataset_file(root, *POSITIONER_FOLDER, "measurements.yaml")
    data = _yaml_load(p)
    if not isinstance(data, dict) or not data:
        raise DatasetError(f"{p}: expected a mapping of time stamps to records")
    joints, poses, stamps = [], [], []
    for key, rec in data.items():
        where = f"{p.name}: {key}"
        if not isinstance(rec, dict):
            raise DatasetError(f"{where}: expected a record with target_joints and pose")
        tj = rec.get("target_joints")
        if not isinstance(tj, list) or len(tj) != 2:
            raise DatasetError(f"{where}/target_joints: expected 2 joint values [rad], got {tj!r}")
        q = [number(x, f"{where}/target_joints[{i}]") for i, x in enumerate(tj)]
        if max(abs(x) for x in q) > 4 * np.pi:
            raise DatasetError(f"{where}/target_joints: {q} is not plausible in radians")
        if rec.get("camera_joints") not in ([], None):
            raise DatasetError(f"{where}/camera_joints: expected an empty list (a fixed camera), got "
                               f"{rec.get('camera_joints')!r}")
        joints.append(q)
        poses.append(_pose_mm(rec.get("pose"), f"{where}/pose"))
        stamps.append(str(key))
    g = dataset_file(root, *POSITIONER_FOLDER, "pose_initial_guesses.yaml")
    guesses = _yaml_load(g)
    if not isinstance(guesses, dict):
        raise DatasetError(f"{g}: expected a mapping")
    T_wc = _pose_mm(guesses.get("camera_mount_to_camera_guess"), f"{g.name}: camera_mount_to_camera_guess")
    T_mt = _pose_mm(guesses.get("target_mount_to_target_guess"), f"{g.name}: target_mount_to_target_guess")
    T = np.stack(poses)
    return RealDataset("ros_industrial_positioner", np.array(joints), T[:, None, :3, 3].copy(), ("target",),
                       ("j1", "j2"), np.zeros(len(T), dtype=int), [],
                       {"T_camera_target": T, "stamp": np.array(stamps)},
                       {"source": str(p), "instrument": "camera (pose of the target by PnP)",
                        "units_in_file": "m, rad, quaternion (x, y, z, w)", "T_world_camera_guess": T_wc,
                        "T_mount_target_guess": T_mt})
