"""robocal.handeye: the linear AX=XB and AX=ZB solvers recover the truth on noise-free data and
agree with OpenCV's calibrateHandEye / calibrateRobotWorldHandEye; degenerate pose sets raise."""

import numpy as np
import pytest

from robocal.handeye import HandEyeError, solve_hand_eye, solve_robot_world_hand_eye
from robocal.transforms import invert_transforms, so3_exp, so3_log

cv2 = pytest.importorskip("cv2")

CV_METHODS = {"tsai": cv2.CALIB_HAND_EYE_TSAI, "park": cv2.CALIB_HAND_EYE_PARK,
              "daniilidis": cv2.CALIB_HAND_EYE_DANIILIDIS}


def _frame(rng, rot_sigma, t_sigma, t_mean=(0.0, 0.0, 0.0)):
    T = np.eye(4)
    T[:3, :3] = so3_exp(rng.normal(0, rot_sigma, 3))
    T[:3, 3] = np.asarray(t_mean) + rng.normal(0, t_sigma, 3)
    return T


def _data(seed, setup, n=10):
    """(T_base_flange, T_camera_target, X, Z), noise-free. X: T_flange_camera or T_base_camera;
    Z: T_base_target or T_flange_target."""
    rng = np.random.default_rng(seed)
    F = np.stack([_frame(rng, 0.5, 200, (800, 0, 600)) for _ in range(n)])
    if setup == "eye_in_hand":
        X, Z = _frame(rng, 1.0, 80), _frame(rng, 0.3, 100, (900, 0, 0))
        C = invert_transforms(F @ X) @ Z  # T_camera_target = (F X)^-1 T_base_target
    else:
        X, Z = _frame(rng, 1.0, 300, (500, 1200, 1500)), _frame(rng, 0.5, 60)
        C = invert_transforms(X) @ F @ Z  # T_camera_target = T_base_camera^-1 F T_flange_target
    return F, C, X, Z


def _err(T, T_ref):
    """(rotation error [rad], translation error [mm])."""
    rot = np.linalg.norm(so3_log((T[:3, :3] @ T_ref[:3, :3].T)[None])[0])  # not arccos: exact near 0
    return rot, np.linalg.norm(T[:3, 3] - T_ref[:3, 3])


def _cv_hand_eye(F, C, method):
    X = np.eye(4)
    X[:3, :3], t = cv2.calibrateHandEye(list(F[:, :3, :3]), list(F[:, :3, 3]), list(C[:, :3, :3]),
                                        list(C[:, :3, 3]), method=CV_METHODS[method])
    X[:3, 3] = t.ravel()
    return X


@pytest.mark.parametrize("method", sorted(CV_METHODS))
@pytest.mark.parametrize("setup", ["eye_in_hand", "eye_to_hand"])
def test_ax_xb_recovers_the_truth_and_agrees_with_opencv(method, setup):
    F, C, X, _ = _data(1, setup)
    ours = solve_hand_eye(F, C, setup=setup, method=method)
    rot, tr = _err(ours, X)
    assert rot < 1e-12 and tr < 1e-9  # rad, mm; measured <= 4e-14 rad, 1.4e-11 mm
    # OpenCV wants the flange poses inverted for a static camera (issue 14's known trap)
    F_cv = F if setup == "eye_in_hand" else invert_transforms(F)
    rot_cv, tr_cv = _err(ours, _cv_hand_eye(F_cv, C, method))
    assert rot_cv < 1e-12 and tr_cv < 1e-9  # measured <= 2e-14 rad, 1.5e-11 mm


@pytest.mark.parametrize("setup", ["eye_in_hand", "eye_to_hand"])
def test_ax_zb_recovers_both_transforms_and_agrees_with_opencv(setup):
    F, C, X, Z = _data(2, setup)
    hand_eye, world = solve_robot_world_hand_eye(F, C, setup=setup)
    for T, ref in ((hand_eye, X), (world, Z)):
        rot, tr = _err(T, ref)
        assert rot < 1e-12 and tr < 1e-9  # measured <= 4e-15 rad, 4e-12 mm
    if setup == "eye_in_hand":  # OpenCV: world = target, gripper = flange
        R_bw, t_bw, R_gc, t_gc = cv2.calibrateRobotWorldHandEye(
            list(C[:, :3, :3]), list(C[:, :3, 3]), list(invert_transforms(F)[:, :3, :3]),
            list(invert_transforms(F)[:, :3, 3]), method=cv2.CALIB_ROBOT_WORLD_HAND_EYE_SHAH)
        T_world_base, T_cam_gripper = np.eye(4), np.eye(4)
        T_world_base[:3, :3], T_world_base[:3, 3] = R_bw, t_bw.ravel()
        T_cam_gripper[:3, :3], T_cam_gripper[:3, 3] = R_gc, t_gc.ravel()
        for T, ref in ((hand_eye, np.linalg.inv(T_cam_gripper)), (world, np.linalg.inv(T_world_base))):
            rot, tr = _err(T, ref)
            assert rot < 1e-8 and tr < 1e-6


def test_degenerate_pose_sets_raise_naming_the_problem():
    F, C, _, _ = _data(3, "eye_in_hand")
    with pytest.raises(HandEyeError, match="at least 3 poses"):
        solve_hand_eye(F[:2], C[:2])
    with pytest.raises(HandEyeError, match="pair one to one"):
        solve_hand_eye(F, C[:-1])
    rng = np.random.default_rng(4)
    axis = np.array([0.3, -0.2, 0.9]) / np.linalg.norm([0.3, -0.2, 0.9])
    F1 = np.tile(F[0], (6, 1, 1))  # the flange turned about one fixed flange-frame axis, and moved
    F1[:, :3, :3] = F[0, :3, :3] @ so3_exp(axis * rng.uniform(-1, 1, (6, 1)))
    F1[:, :3, 3] += rng.normal(0, 100, (6, 3))
    X, Z = np.eye(4), np.eye(4)
    X[:3, 3], Z[:3, 3] = [10, 20, 30], [900, 0, 0]
    C1 = invert_transforms(F1 @ X) @ Z
    for call in (lambda: solve_hand_eye(F1, C1, method="park"), lambda: solve_robot_world_hand_eye(F1, C1)):
        with pytest.raises(HandEyeError, match="one axis"):
            call()
    F2 = np.tile(F[0], (5, 1, 1))
    F2[:, :3, 3] += rng.normal(0, 100, (5, 3))
    with pytest.raises(HandEyeError, match="only translates"):
        solve_hand_eye(F2, invert_transforms(F2 @ X) @ Z)
