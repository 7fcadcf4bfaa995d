"""Real data: the ROS-Industrial 2-axis positioner (../shared/datasets/ros_industrial_handeye/raw/
kinematic_calibration, Apache-2.0; 205 target poses measured by a fixed camera). The reader, and
the positioner's axes calibrated on the core with hold-out figures (seeded 150 / 55 split)."""

from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("yaml")

from robocal.io.datasets import DatasetError, read_ros_industrial_positioner  # noqa: E402
from robocal.workflows.datasets.ros_industrial_positioner import calibrate_positioner  # noqa: E402

DATASETS = Path(__file__).resolve().parents[2] / "shared" / "datasets"
FOLDER = DATASETS / "ros_industrial_handeye" / "raw" / "kinematic_calibration"
needs_data = pytest.mark.skipif(not FOLDER.is_dir(), reason=f"real data folder {FOLDER} absent (tests read "
                                "../shared/datasets in place)")


@needs_data
def test_reader_returns_mm_and_rad():
    ds = read_ros_industrial_positioner(DATASETS)
    assert ds.n_poses == 205 and ds.joints.shape == (205, 2)
    T = ds.per_pose["T_camera_target"]
    # first record, 1593701755: x = -0.5325496958762886 m; target_joints[1] = 0.0002200359886046499 rad
    assert T[0, 0, 3] == pytest.approx(-532.5496958762886) and ds.joints[0, 1] == pytest.approx(2.200359886046499e-4)
    assert np.allclose(T[:, :3, :3] @ np.swapaxes(T[:, :3, :3], 1, 2), np.eye(3), atol=1e-12)
    assert ds.metadata["T_world_camera_guess"][:3, 3] == pytest.approx([2200.0, 700.0, 1075.0])


def test_reader_names_the_bad_entry(tmp_path):
    folder = tmp_path.joinpath("ros_industrial_handeye", "raw", "kinematic_calibration")
    folder.mkdir(parents=True)
    folder.joinpath("measurements.yaml").write_text(
        "'17':\n  camera_joints: []\n  pose: {qw: 1.0, qx: 0.0, qy: 0.0, qz: 0.0, x: 0.1, y: abc, z: 1.0}\n"
        "  target_joints: [0.0, 0.1]\n")
    folder.joinpath("pose_initial_guesses.yaml").write_text("{}\n")
    with pytest.raises(DatasetError, match=r"measurements.yaml: 17/pose/y: 'abc' is not a number"):
        read_ros_industrial_positioner(tmp_path)
    folder.joinpath("measurements.yaml").write_text(
        "'17':\n  camera_joints: []\n  pose: {qw: 1.0, qx: 0.0, qy: 0.0, qz: 0.0, x: 100.0, y: 700.0, z: 1000.0}\n"
        "  target_joints: [0.0, 0.1]\n")
    with pytest.raises(DatasetError, match="not plausible in metres"):
        read_ros_industrial_positioner(tmp_path)


@needs_data
def test_positioner_axes_calibrate_with_holdout_figures():
    run = calibrate_positioner(seed=0, n_train=150, root=DATASETS)
    cal, nom = run["calibrated"], run["nominal"]
    assert run["result"].converged
    # hold-out (55 records): measured 0.386 mm / 0.0509 deg calibrated, 0.420 mm / 0.0513 deg nominal DH
    assert cal["test"]["pos_mean"] < 0.40 and cal["test"]["pos_mean"] < 0.95 * nom["test"]["pos_mean"]
    assert cal["test"]["rot_mean"] < 0.06 and cal["test"]["pos_max"] < nom["test"]["pos_max"]
    # the source's own acceptance on its fit: position mean < 2 mm, orientation mean < 0.2 deg
    assert cal["train"]["pos_mean"] < 2.0 and cal["train"]["rot_mean"] < 0.2
    axes = run["axes"]
    # the axes: perpendicular to 0.024 deg, 0.60 mm apart (nominal: 90 deg, intersecting)
    assert abs(axes["angle_deg"] - 89.976) < 0.01 and abs(axes["common_normal_mm"] - 0.60) < 0.1
    a1 = run["result"].parameter_table()[2]
    assert a1["name"] == "a1" and a1["std"] < 0.05  # mm: the common normal is determined to 0.04 mm
    # what the camera cannot tell apart from the camera mount (theta1, d1) or the target mount (link 2)
    assert {n for n, _ in axes["dropped"]} == {"theta1", "d1", "theta2", "d2", "a2", "alpha2"}
