"""Real data: the ROS-Industrial 2-axis positioner (../shared/datasets/ros_industrial_handeye/raw/
kinematic_calibration, Apache-2.0; 205 target poses measured by a fixed camera). The reader, and
the positioner's axes calibrated on the core with hold-out figures (seeded 150 / 55 split)."""

from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("yaml")

from robocal.io.datasets import DatasetError, read_ros_industrial_positioner  # noqa: E402
from robocal.workflows.datasets.positioner_reference import reference_axes  # noqa: E402
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



# The independent reference fit (a screw-axis model written from scratch, numpy / scipy only):
# robocal.workflows.datasets.positioner_reference.reference_axes.


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
    a1 = run["result"].parameter_table()[2]
    assert a1["name"] == "a1" and a1["std"] < 0.05  # mm: the common normal is determined to 0.04 mm
    # what the camera cannot tell apart from the camera mount (theta1, d1) or the target mount (link 2)
    assert {n for n, _ in axes["dropped"]} == {"theta1", "d1", "theta2", "d2", "a2", "alpha2"}


@needs_data
def test_positioner_axes_agree_with_an_independent_screw_axis_fit():
    """The axes robocal measures (angle, common normal) against :func:`reference_axes`, a fit written
    from scratch (numpy / scipy only) on the same records and started from the data alone:

    * the same three target points (the same least-squares problem in another parameterisation): the
      angle and common normal must agree to 1 % of the reference's standard deviation (solver
      stopping only), and robocal's reported sigma of alpha1 and a1 must equal the reference's
      propagated sigma within 1 % (the uncertainty checked, not only the value);
    * the target origin alone (another estimator, the orientation left out): within 2 of its own
      sigma;
    * the departure from the source's nominal (90 deg, intersecting axes) is more than 3 reference
      sigma in both: the data show it.

    A screw-axis check from grouped relative motions (docs/testing.md) is biased by the joint
    differences within each group (89.984 deg on noise-free data whose truth is 89.976 deg); the fit
    here uses every record at its own joints and has no such bias. Measured (seed 0, 150 records):
    robocal 89.97619 deg / 0.6041 mm; reference, three points 89.97619 deg (sigma 0.0031) / 0.6041 mm
    (sigma 0.036), differences under 1e-9 deg / 1e-7 mm, robocal's sigmas equal within 1e-6; origin alone
    89.9767 deg (sigma 0.0055) / 0.597 mm (sigma 0.061). The sigmas are the formal ones of an
    unweighted point fit, in both codes: over the seeded splits 0-4 (which share most records)
    robocal gives 89.9762-89.9825 deg and 0.54-0.64 mm, so they are optimistic by about 2-3x
    (docs/datasets.md); the claims here compare estimates on the same records."""
    from robocal.workflows.datasets.ros_industrial_positioner import axes_on_training_records

    rec = axes_on_training_records(seed=0, n_train=150, root=DATASETS)
    T, q, got, robocal_sigma = rec["T_camera_target"], rec["joints"], rec["axes"], rec["sigma"]
    ref, sigma, rms = reference_axes(T, q)
    assert rms < 1.0, rms  # mm: the fit found the data's minimum (robocal's training residual is ~0.2 mm)
    assert np.all(np.abs(got - ref) < 0.01 * sigma), (got, ref, sigma)
    assert np.all(np.abs(robocal_sigma / sigma - 1.0) < 0.01), (robocal_sigma, sigma)
    ref1, sigma1, _ = reference_axes(T, q, n_points=1)
    assert np.all(np.abs(got - ref1) < 2.0 * sigma1), (got, ref1, sigma1)
    assert 90.0 - ref[0] > 3 * sigma[0] and ref[1] > 3 * sigma[1], (ref, sigma)
