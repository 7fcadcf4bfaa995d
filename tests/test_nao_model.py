"""The NAO H25 robot file against Aldebaran's published numbers (docs/robots.md, `nao_h25`)."""

import numpy as np
import pytest

from robocal.robots import load_robot

# "H25 - Links" (mm)
NECK_Z, SHOULDER_Y, SHOULDER_Z = 126.5, 98.0, 100.0
UPPER_ARM, ELBOW_Y, LOWER_ARM, HAND_X, HAND_Z = 105.0, 15.0, 55.95, 57.75, 12.31
# "Video camera", head V4 (V4/V5): CameraTop in the HeadPitch frame, pitched down 1.2 deg
CAMERA_TOP = np.array([58.71, 0.0, 63.64])


@pytest.fixture(scope="module")
def nao():
    return load_robot("nao_h25")


def _ry(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])


def _rz(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])


def _rx(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])


def _hand_by_hand(q_arm, side):
    """The hand position from the documented offsets, composed by hand: shoulder at (0, +-98, 100),
    pitch (y) . roll (z) . (105, +-15, 0) . yaw (x) . roll (z) . (55.95, 0, 0) . yaw (x) . (57.75, 0, -12.31)."""
    sp, sr, ey, er, wy = q_arm
    s = 1.0 if side == "L" else -1.0
    R1 = _ry(sp) @ _rz(sr)
    R2 = R1 @ _rx(ey) @ _rz(er)
    R3 = R2 @ _rx(wy)
    return (np.array([0.0, s * SHOULDER_Y, SHOULDER_Z]) + R1 @ [UPPER_ARM, s * ELBOW_Y, 0.0]
            + R2 @ [LOWER_ARM, 0.0, 0.0] + R3 @ [HAND_X, 0.0, -HAND_Z])


def test_names_and_units(nao):
    assert nao.controller_joints == ("HeadYaw", "HeadPitch", "LShoulderPitch", "LShoulderRoll", "LElbowYaw",
                                     "LElbowRoll", "LWristYaw", "RShoulderPitch", "RShoulderRoll", "RElbowYaw",
                                     "RElbowRoll", "RWristYaw")
    assert [e.name for e in nao.end_effectors] == ["camera_top", "left_hand", "right_hand"]
    lim = np.degrees(nao.limits)
    assert lim[3].tolist() == pytest.approx([-18.0, 76.0]) and lim[8].tolist() == pytest.approx([-76.0, 18.0])
    assert lim[5].tolist() == pytest.approx([-88.5, -2.0]) and lim[10].tolist() == pytest.approx([2.0, 88.5])
    assert lim[1].tolist() == pytest.approx([-38.5, 29.5])


def test_zero_pose_matches_documented_offsets(nao):
    q = np.zeros(12)
    left = nao.fk(q, "left_hand")[:3, 3]
    right = nao.fk(q, "right_hand")[:3, 3]
    # x: UpperArm + LowerArm + HandOffsetX = 218.7; y: ShoulderOffsetY + ElbowOffsetY = 113; z: 100 - 12.31
    np.testing.assert_allclose(left, [218.7, 113.0, 87.69], atol=1e-9)
    np.testing.assert_allclose(right, [218.7, -113.0, 87.69], atol=1e-9)
    cam = nao.fk(q, "camera_top")
    np.testing.assert_allclose(cam[:3, 3], [58.71, 0.0, NECK_Z + 63.64], atol=1e-9)
    # optical axis forward and 1.2 deg down; image x to the robot's right; image y down
    np.testing.assert_allclose(cam[:3, 2], [np.cos(np.radians(1.2)), 0.0, -np.sin(np.radians(1.2))], atol=1e-12)
    np.testing.assert_allclose(cam[:3, 0], [0.0, -1.0, 0.0], atol=1e-12)
    assert cam[2, 1] < -0.99


def test_arm_poses_against_hand_composed_offsets(nao):
    rng = np.random.default_rng(3)
    q = rng.uniform(nao.limits[:, 0], nao.limits[:, 1], size=(20, 12))
    left = nao.fk(q, "left_hand")[:, :3, 3]
    right = nao.fk(q, "right_hand")[:, :3, 3]
    for k in range(len(q)):
        np.testing.assert_allclose(left[k], _hand_by_hand(q[k, 2:7], "L"), atol=1e-9)
        np.testing.assert_allclose(right[k], _hand_by_hand(q[k, 7:12], "R"), atol=1e-9)
    # arm hanging down (ShoulderPitch +90 deg): the hand below the shoulder by the arm's length
    q = np.zeros(12)
    q[2] = np.pi / 2
    np.testing.assert_allclose(nao.fk(q, "left_hand")[:3, 3], [-HAND_Z, 113.0, SHOULDER_Z - 218.7], atol=1e-9)


def test_camera_follows_head_joints(nao):
    q = np.zeros(12)
    q[0], q[1] = np.radians(30.0), np.radians(20.0)
    expected = np.array([0, 0, NECK_Z]) + _rz(q[0]) @ _ry(q[1]) @ CAMERA_TOP
    np.testing.assert_allclose(nao.fk(q, "camera_top")[:3, 3], expected, atol=1e-9)
    # pitched 20 deg (+1.2 deg mount) down, turned 30 deg left
    z = nao.fk(q, "camera_top")[:3, 2]
    assert np.degrees(np.arcsin(-z[2])) == pytest.approx(21.2, abs=1e-9)
    assert np.degrees(np.arctan2(z[1], z[0])) == pytest.approx(30.0, abs=1e-9)


def test_left_and_right_arms_mirror(nao):
    """Right-arm joints = mirror of the left (the pitch joint keeps its sign, roll and
    yaw joints change sign): the right hand is the left hand mirrored in y, orientation included."""
    rng = np.random.default_rng(7)
    qL = rng.uniform(nao.limits[2:7, 0], nao.limits[2:7, 1], size=(30, 5))
    mirror = np.array([1.0, -1.0, -1.0, -1.0, -1.0])  # pitch, roll, yaw, roll, yaw
    q = np.zeros((30, 12))
    q[:, 2:7] = qL
    q[:, 7:12] = qL * mirror
    assert nao.within_limits(q).all()
    TL, TR = nao.fk(q, "left_hand"), nao.fk(q, "right_hand")
    M = np.diag([1.0, -1.0, 1.0])
    np.testing.assert_allclose(TR[:, :3, 3], TL[:, :3, 3] @ M, atol=1e-9)
    np.testing.assert_allclose(TR[:, :3, :3], M @ TL[:, :3, :3] @ M, atol=1e-12)
