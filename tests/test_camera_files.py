"""io.camera_files: ROS YAML, OpenCV YAML and JSON camera files load and round-trip exactly."""

import numpy as np
import pytest

from robocal.camera import Camera
from robocal.io.camera_files import read_camera, write_camera_json, write_camera_ros_yaml
from robocal.io.header import FileFormatError

cv2 = pytest.importorskip("cv2")
CAM = Camera(1402.5, 1398.25, 640.125, 511.75, (-0.12, 0.081, 0.0008, -0.0005, -0.021), image_size=(1280, 1024))


def test_json_and_ros_yaml_round_trip(tmp_path):
    write_camera_json(tmp_path / "c.json", CAM)
    write_camera_ros_yaml(tmp_path / "c.yaml", CAM)
    assert read_camera(tmp_path / "c.json") == CAM
    assert read_camera(tmp_path / "c.yaml") == CAM
    div = Camera(1000.0, 1000.0, 600.0, 500.0, (-0.2,), model="division")
    write_camera_json(tmp_path / "d.json", div)
    assert read_camera(tmp_path / "d.json") == div


def test_opencv_file_storage_yaml_loads_unchanged(tmp_path):
    fs = cv2.FileStorage(str(tmp_path / "cv.yaml"), cv2.FILE_STORAGE_WRITE)
    fs.write("image_width", 1280)
    fs.write("image_height", 1024)
    fs.write("camera_matrix", CAM.matrix)
    fs.write("distortion_coefficients", np.array(CAM.distortion)[None])
    fs.release()
    assert read_camera(tmp_path / "cv.yaml") == CAM


def test_a_broken_file_names_the_problem(tmp_path):
    (tmp_path / "bad.yaml").write_text("camera_matrix: {rows: 3}\n")
    with pytest.raises(FileFormatError, match="camera_matrix.data"):
        read_camera(tmp_path / "bad.yaml")
