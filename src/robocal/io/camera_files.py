"""Camera files: intrinsics and distortion from OpenCV/ROS YAML and robocal JSON (issue 14).

* ROS ``camera_info`` YAML (``camera_calibration``'s output): ``image_width``, ``image_height``,
  ``camera_matrix: {rows: 3, cols: 3, data: [...]}``, ``distortion_model: plumb_bob |
  rational_polynomial``, ``distortion_coefficients: {rows: 1, cols: K, data: [...]}``;
* OpenCV ``FileStorage`` YAML (``%YAML:1.0``, ``!!opencv-matrix``) with ``camera_matrix`` and
  ``distortion_coefficients`` (read through OpenCV itself);
* JSON ``{"format": "robocal-camera/1", "model": "brown" | "division", "fx", "fy", "cx", "cy",
  "distortion": [...], "image_size": [w, h]}``.

Coefficients keep OpenCV's order, so files load unchanged. Errors are :class:`FileFormatError`.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from ..camera import Camera
from .header import FileFormatError

__all__ = ["read_camera", "write_camera_json", "write_camera_ros_yaml"]


def _camera(path, K, dist, model="brown", size=None) -> Camera:
    try:
        return Camera.from_matrix(np.asarray(K, dtype=float).reshape(3, 3), np.ravel(dist), model,
                                  None if size is None else tuple(int(v) for v in size))
    except (ValueError, TypeError) as exc:
        raise FileFormatError(path, f"not a valid camera: {exc}") from None


def _read_ros(path, text) -> Camera:
    import yaml

    doc = yaml.safe_load(text)
    try:
        K, dist = doc["camera_matrix"]["data"], doc["distortion_coefficients"]["data"]
    except (KeyError, TypeError):
        raise FileFormatError(path, "expected camera_matrix.data and distortion_coefficients.data") from None
    size = (doc["image_width"], doc["image_height"]) if "image_width" in doc else None
    return _camera(path, K, dist, "brown", size)


def _read_opencv(path) -> Camera:
    import cv2

    fs = cv2.FileStorage(str(path), cv2.FILE_STORAGE_READ)
    K, dist = fs.getNode("camera_matrix").mat(), fs.getNode("distortion_coefficients").mat()
    w, h = fs.getNode("image_width").real(), fs.getNode("image_height").real()
    fs.release()
    if K is None or dist is None:
        raise FileFormatError(path, "OpenCV YAML without camera_matrix and distortion_coefficients")
    return _camera(path, K, dist, "brown", (w, h) if w > 0 and h > 0 else None)


def read_camera(path) -> Camera:
    """A :class:`~robocal.camera.Camera` from a ROS or OpenCV YAML file or a robocal JSON file."""
    path = Path(path)
    text = path.read_text()
    if path.suffix.lower() == ".json":
        try:
            doc = json.loads(text)
            K = [[doc["fx"], 0.0, doc["cx"]], [0.0, doc["fy"], doc["cy"]], [0.0, 0.0, 1.0]]
            return _camera(path, K, doc["distortion"], doc.get("model", "brown"), doc.get("image_size"))
        except (json.JSONDecodeError, KeyError) as exc:
            raise FileFormatError(path, f"not a robocal-camera/1 JSON file: {exc}") from None
    if text.lstrip().startswith("%YAML"):
        return _read_opencv(path)
    return _read_ros(path, text)


def write_camera_json(path, camera: Camera) -> None:
    """Write ``camera`` as robocal-camera/1 JSON."""
    doc = {"format": "robocal-camera/1", "model": camera.model, "fx": camera.fx, "fy": camera.fy,
           "cx": camera.cx, "cy": camera.cy, "distortion": list(camera.distortion),
           "image_size": None if camera.image_size is None else list(camera.image_size)}
    Path(path).write_text(json.dumps(doc, indent=2) + "\n")


def write_camera_ros_yaml(path, camera: Camera, name: str = "camera") -> None:
    """Write a Brown–Conrady ``camera`` as a ROS camera_info YAML file."""
    if camera.model != "brown":
        raise ValueError("ROS camera_info files hold Brown-Conrady (plumb_bob) distortion only")
    w, h = camera.image_size or (0, 0)
    d = list(camera.distortion)
    lines = [f"image_width: {int(w)}", f"image_height: {int(h)}", f"camera_name: {name}",
             "camera_matrix:", "  rows: 3", "  cols: 3", f"  data: {[float(v) for v in camera.matrix.ravel()]}",
             f"distortion_model: {'rational_polynomial' if len(d) == 8 else 'plumb_bob'}",
             "distortion_coefficients:", "  rows: 1", f"  cols: {len(d)}", f"  data: {[float(v) for v in d]}"]
    Path(path).write_text("\n".join(lines) + "\n")
