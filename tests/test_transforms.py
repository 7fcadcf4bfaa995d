"""Tests of robocal.transforms: SE(3)/SO(3) primitives and orientation conventions."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from robocal.transforms import (
    EULER_CONVENTIONS,
    POSE_CONVENTIONS,
    compose,
    euler_from_matrix,
    invert_transforms,
    matrix_from_euler,
    matrix_from_quaternion,
    matrix_from_rotvec,
    pose_from_transform,
    quaternion_from_matrix,
    rot_x,
    rot_y,
    rot_z,
    rotvec_from_matrix,
    so3_exp,
    so3_log,
    transform_from_pose,
    transform_points,
    transforms_from,
)

DEG = np.pi / 180.0
CONVENTIONS = sorted(EULER_CONVENTIONS)
SETTINGS = settings(derandomize=True, max_examples=60, deadline=None, database=None)


def _is_proper(name: str) -> bool:
    """First axis repeated (middle angle in [0, pi])."""
    seq = name.split("_")[0]
    return name == "kawasaki_oat" or (len(seq) == 3 and seq[0] == seq[2])


def _last_is_right(name: str) -> bool:
    """True if the last triple entry is the angle of the rightmost matrix factor."""
    return not (name.endswith("_extrinsic") or name in ("fanuc_wpr", "rpy"))


finite = dict(allow_nan=False, allow_infinity=False)
rotvecs = st.tuples(*[st.floats(-1.0, 1.0, **finite)] * 3, st.floats(0.0, np.pi, **finite)).map(
    lambda t: np.array(t[:3]) / (np.linalg.norm(t[:3]) or 1.0) * (t[3] if np.linalg.norm(t[:3]) else 0.0)
)
angle = st.floats(-np.pi + 1e-6, np.pi - 1e-6, **finite)
points = st.tuples(*[st.floats(-2000.0, 2000.0, **finite)] * 3).map(np.array)


def _transform(rv, p):
    return transforms_from(so3_exp(rv), p)


# --- hand-derived reference values -------------------------------------------------------------


def test_elementary_rotations_hand_values():
    assert np.allclose(rot_z(90 * DEG), [[0, -1, 0], [1, 0, 0], [0, 0, 1]], atol=1e-15)
    assert np.allclose(rot_y(90 * DEG), [[0, 0, 1], [0, 1, 0], [-1, 0, 0]], atol=1e-15)
    assert np.allclose(rot_x(90 * DEG), [[1, 0, 0], [0, 0, -1], [0, 1, 0]], atol=1e-15)


def test_kuka_abc_hand_values():
    # A = 90 deg: rotation about base Z only.
    assert np.allclose(matrix_from_euler([90 * DEG, 0, 0], "kuka_abc"), [[0, -1, 0], [1, 0, 0], [0, 0, 1]], atol=1e-15)
    # B = 90 deg: about Y.
    assert np.allclose(matrix_from_euler([0, 90 * DEG, 0], "kuka_abc"), [[0, 0, 1], [0, 1, 0], [-1, 0, 0]], atol=1e-15)
    # C = 180 deg: the common "tool pointing down" orientation, diag(1, -1, -1).
    assert np.allclose(matrix_from_euler([0, 0, np.pi], "kuka_abc"), np.diag([1.0, -1.0, -1.0]), atol=1e-15)
    # A = 90, C = 90 (intrinsic Z then X'): Rz(90) @ Rx(90); tool x = base y, tool z = base x.
    R = matrix_from_euler([90 * DEG, 0, 90 * DEG], "kuka_abc")
    assert np.allclose(R, [[0, 0, 1], [1, 0, 0], [0, 1, 0]], atol=1e-15)


def test_fanuc_wpr_hand_values():
    # W = 90 deg is a rotation about X.
    assert np.allclose(matrix_from_euler([90 * DEG, 0, 0], "fanuc_wpr"), [[1, 0, 0], [0, 0, -1], [0, 1, 0]], atol=1e-15)
    # R = 90 deg is about Z.
    assert np.allclose(matrix_from_euler([0, 0, 90 * DEG], "fanuc_wpr"), rot_z(np.pi / 2), atol=1e-15)
    # W = 90 then R = 90 about the fixed axes: X first, then Z: Rz(90) @ Rx(90).
    R = matrix_from_euler([90 * DEG, 0, 90 * DEG], "fanuc_wpr")
    assert np.allclose(R, [[0, 0, 1], [1, 0, 0], [0, 1, 0]], atol=1e-15)


def test_zxz_thesis_hand_values():
    # Thesis (4-10): R = Rz(psi) Rx(theta) Rz(-psi); its z column is the tool axis
    # (sin psi sin theta, -cos psi sin theta, cos theta).
    psi, th = 30 * DEG, 20 * DEG
    R = matrix_from_euler([psi, th, -psi], "zxz")
    assert np.allclose(R[:, 2], [np.sin(psi) * np.sin(th), -np.cos(psi) * np.sin(th), np.cos(th)], atol=1e-15)
    assert np.allclose(R, rot_z(psi) @ rot_x(th) @ rot_z(-psi), atol=1e-15)


def test_every_convention_matches_its_documented_formula():
    a, b, c = 0.3, -0.7, 1.1
    Rx, Ry, Rz = rot_x, rot_y, rot_z
    expected = {
        "kuka_abc": Rz(a) @ Ry(b) @ Rx(c),
        "fanuc_wpr": Rz(c) @ Ry(b) @ Rx(a),
        "rpy": Rz(c) @ Ry(b) @ Rx(a),
        "kawasaki_oat": Rz(a) @ Ry(b) @ Rz(c),
        "zxz": Rz(a) @ Rx(b) @ Rz(c),
        "zyz": Rz(a) @ Ry(b) @ Rz(c),
    }
    elem = {"x": Rx, "y": Ry, "z": Rz}
    for name in CONVENTIONS:
        seq, _, kind = name.partition("_")
        if kind == "intrinsic":
            expected[name] = elem[seq[0]](a) @ elem[seq[1]](b) @ elem[seq[2]](c)
        elif kind == "extrinsic":
            expected[name] = elem[seq[2]](c) @ elem[seq[1]](b) @ elem[seq[0]](a)
    assert set(expected) == set(CONVENTIONS)
    for name, R in expected.items():
        assert np.allclose(matrix_from_euler([a, b, c], name), R, atol=1e-14), name


def test_kuka_abc_equals_fanuc_wpr_reversed():
    # KUKA (A, B, C) and FANUC (W, P, R) are the same matrix when (A, B, C) = (R, P, W):
    # intrinsic Z-Y'-X'' equals extrinsic X-Y-Z with the angle order reversed.
    rng = np.random.default_rng(1)
    abc = rng.uniform(-np.pi, np.pi, size=(50, 3))
    R_kuka = matrix_from_euler(abc, "kuka_abc")
    for name in ("fanuc_wpr", "rpy", "xyz_extrinsic"):
        assert np.allclose(matrix_from_euler(abc[:, ::-1], name), R_kuka, atol=1e-14)
    assert np.allclose(matrix_from_euler(abc, "zyx_intrinsic"), R_kuka, atol=1e-14)
    # and the extracted triples agree
    assert np.allclose(euler_from_matrix(R_kuka, "fanuc_wpr"), euler_from_matrix(R_kuka, "kuka_abc")[:, ::-1])


def test_quaternion_published_values():
    # 90 deg about x: (cos 45, sin 45, 0, 0) in (w, x, y, z).
    q = quaternion_from_matrix(rot_x(np.pi / 2))
    assert np.allclose(q, [np.cos(np.pi / 4), np.sin(np.pi / 4), 0, 0], atol=1e-15)
    # ABB "tool down" [0, 0, 1, 0] is 180 deg about y: diag(-1, 1, -1).
    assert np.allclose(matrix_from_quaternion([0, 0, 1, 0]), np.diag([-1.0, 1.0, -1.0]), atol=1e-15)
    # 120 deg about (1, 1, 1)/sqrt(3) cycles the axes x -> y -> z: q = (1/2, 1/2, 1/2, 1/2).
    R = np.array([[0.0, 0, 1], [1, 0, 0], [0, 1, 0]])
    assert np.allclose(quaternion_from_matrix(R), [0.5, 0.5, 0.5, 0.5], atol=1e-15)
    assert np.allclose(matrix_from_quaternion([0.5, 0.5, 0.5, 0.5]), R, atol=1e-15)


def test_kawasaki_oat_against_published_quaternion_formula():
    # Roboception rc_visard docs, "Kawasaki XYZ-OAT format": O about z, A about the new y, T about
    # the new z, R = rz(O) ry(A) rz(T); their quaternion in half angles (here reordered to w, x, y, z).
    rng = np.random.default_rng(2)
    for O, A, T in rng.uniform(-np.pi, np.pi, size=(20, 3)):
        cO, sO, cA, sA, cT, sT = (f(v / 2) for v in (O, A, T) for f in (np.cos, np.sin))
        q_ref = np.array(
            [
                cO * cA * cT - sO * cA * sT,
                cO * sA * sT - sO * sA * cT,
                cO * sA * cT + sO * sA * sT,
                sO * cA * cT + cO * cA * sT,
            ]
        )
        q = quaternion_from_matrix(matrix_from_euler([O, A, T], "kawasaki_oat"))
        assert np.allclose(q, q_ref * np.sign(q_ref[0]), atol=1e-12)


def test_rotvec_hand_values():
    assert np.allclose(matrix_from_rotvec([np.pi, 0, 0]), np.diag([1.0, -1.0, -1.0]), atol=1e-15)
    assert np.allclose(matrix_from_rotvec([0, 0, np.pi / 2]), rot_z(np.pi / 2), atol=1e-15)
    assert np.allclose(rotvec_from_matrix(rot_y(0.5)), [0, 0.5, 0], atol=1e-15)


def test_ur_and_abb_poses_at_the_boundary():
    # Universal Robots: metres and a rotation vector in radians; internal mm.
    T = transform_from_pose([0.1, -0.2, 0.3, 0.0, 0.0, np.pi / 2], "rotvec", length_unit="m", angle_unit="rad")
    assert np.allclose(T[:3, 3], [100.0, -200.0, 300.0])
    assert np.allclose(T[:3, :3], rot_z(np.pi / 2), atol=1e-15)
    assert np.allclose(pose_from_transform(T, "rotvec", "m", "rad"), [0.1, -0.2, 0.3, 0, 0, np.pi / 2])
    # ABB: mm and quaternion (w, x, y, z).
    T = transform_from_pose([500.0, 0.0, 800.0, 0.0, 0.0, 1.0, 0.0], "quaternion")
    assert np.allclose(T[:3, :3], np.diag([-1.0, 1.0, -1.0]), atol=1e-15)
    assert pose_from_transform(T, "quaternion").shape == (7,)
    # KUKA: mm/deg.
    T = transform_from_pose([1, 2, 3, 90, 0, 0], "kuka_abc")
    assert np.allclose(T[:3, :3], rot_z(np.pi / 2), atol=1e-15)
    assert np.allclose(pose_from_transform(T, "kuka_abc"), [1, 2, 3, 90, 0, 0])


# --- Euler round trips -------------------------------------------------------------------------


@SETTINGS
@given(rv=rotvecs)
def test_matrix_euler_matrix_round_trip_all_conventions(rv):
    R = so3_exp(rv)
    for name in CONVENTIONS:
        e = euler_from_matrix(R, name)
        assert np.allclose(matrix_from_euler(e, name), R, atol=1e-12), name
        mid_lo, mid_hi = (0.0, np.pi) if _is_proper(name) else (-np.pi / 2, np.pi / 2)
        assert mid_lo - 1e-12 <= e[1] <= mid_hi + 1e-12, name
        assert np.all(np.abs(e[[0, 2]]) <= np.pi + 1e-12), name


@SETTINGS
@given(a=angle, b=st.floats(0.0, 1.0, **finite), c=angle)
def test_euler_matrix_euler_round_trip_away_from_singularity(a, b, c):
    for name in CONVENTIONS:
        if _is_proper(name):
            mid = 0.01 + b * (np.pi - 0.02)
        else:
            mid = -np.pi / 2 + 0.01 + b * (np.pi - 0.02)
        e = np.array([a, mid, c])
        back = euler_from_matrix(matrix_from_euler(e, name), name)
        assert np.allclose(back, e, atol=1e-9), (name, e, back)


@pytest.mark.parametrize("name", CONVENTIONS)
@pytest.mark.parametrize("offset", [0.0, 1e-12, 1e-9, 1e-7, 1e-4])
def test_gimbal_lock_round_trip(name, offset):
    rng = np.random.default_rng(3)
    outer = rng.uniform(-np.pi, np.pi, size=(40, 2))
    if _is_proper(name):
        mids = [0.0 + offset, np.pi - offset]
    else:
        mids = [np.pi / 2 - offset, -np.pi / 2 + offset]
    for mid in mids:
        e = np.stack([outer[:, 0], np.full(len(outer), mid), outer[:, 1]], axis=-1)
        R = matrix_from_euler(e, name)
        back = euler_from_matrix(R, name)
        assert np.all(np.isfinite(back))
        assert np.allclose(matrix_from_euler(back, name), R, atol=1e-12), name
        if offset == 0.0:
            # exactly at the lock, the rightmost factor's angle is set to 0
            idx = 2 if _last_is_right(name) else 0
            assert np.allclose(back[:, idx], 0.0, atol=1e-9), name


# --- quaternions ---------------------------------------------------------------------------------


@SETTINGS
@given(rv=rotvecs)
def test_quaternion_round_trip_and_sign(rv):
    R = so3_exp(rv)
    q = quaternion_from_matrix(R)
    assert q[0] >= 0.0
    assert np.isclose(np.linalg.norm(q), 1.0)
    assert np.allclose(matrix_from_quaternion(q), R, atol=1e-12)
    assert np.allclose(matrix_from_quaternion(-q), R, atol=1e-12)
    # the quaternion of a rotation by theta about n is (cos theta/2, sin theta/2 n)
    th = np.linalg.norm(rv)
    if 1e-6 < th < np.pi - 1e-6:
        assert np.allclose(q, np.r_[np.cos(th / 2), np.sin(th / 2) * rv / th], atol=1e-9)


def test_quaternion_near_180_degrees_is_accurate():
    rng = np.random.default_rng(4)
    axes = rng.normal(size=(200, 3))
    axes /= np.linalg.norm(axes, axis=-1, keepdims=True)
    for th in (np.pi, np.pi - 1e-9, np.pi - 1e-5):
        R = so3_exp(axes * th)
        q = quaternion_from_matrix(R)
        assert np.all(q[:, 0] >= 0.0)
        assert np.allclose(matrix_from_quaternion(q), R, atol=1e-12)


def test_matrix_from_quaternion_normalizes_and_validates():
    q = np.array([1.0, 0.0, 0.0, 1.0]) / np.sqrt(2) * (1 + 5e-4)
    assert np.allclose(matrix_from_quaternion(q), rot_z(np.pi / 2), atol=1e-12)
    with pytest.raises(ValueError, match=r"q: .*zero norm"):
        matrix_from_quaternion([0.0, 0.0, 0.0, 0.0])
    with pytest.raises(ValueError, match=r"q: .*norm deviates from 1"):
        matrix_from_quaternion([1.0, 0.0, 0.0, 1.0])
    assert np.allclose(matrix_from_quaternion([2.0, 0.0, 0.0, 0.0], tol=None), np.eye(3))
    with pytest.raises(ValueError, match=r"q: expected shape \(\.\.\., 4\), got \(3,\)"):
        matrix_from_quaternion([1.0, 0.0, 0.0])
    with pytest.raises(ValueError, match=r"quaternion"):
        transform_from_pose([0, 0, 0, 1, 1, 0, 0], "quaternion")


# --- rotation vectors and so3 log/exp -----------------------------------------------------------


@SETTINGS
@given(rv=rotvecs)
def test_rotvec_round_trip(rv):
    R = matrix_from_rotvec(rv)
    back = rotvec_from_matrix(R)
    assert np.allclose(matrix_from_rotvec(back), R, atol=1e-12)
    if np.linalg.norm(rv) < np.pi - 1e-6:
        assert np.allclose(back, rv, atol=1e-9)


@pytest.mark.parametrize("eps", [0.0, 1e-12, 1e-8, 1e-5, 1e-3, 2e-3])
def test_rotvec_near_pi(eps):
    rng = np.random.default_rng(5)
    axes = rng.normal(size=(100, 3))
    axes /= np.linalg.norm(axes, axis=-1, keepdims=True)
    rv = axes * (np.pi - eps)
    R = matrix_from_rotvec(rv)
    back = rotvec_from_matrix(R)
    assert np.allclose(np.linalg.norm(back, axis=-1), np.pi - eps, atol=1e-9)
    assert np.allclose(matrix_from_rotvec(back), R, atol=1e-12)
    if eps > 1e-8:
        # the axis sign is determined away from exactly pi
        assert np.allclose(back, rv, atol=1e-6)
    else:
        assert np.allclose(np.abs(np.einsum("ij,ij->i", back, axes)), np.pi - eps, atol=1e-6)


@SETTINGS
@given(rv=rotvecs)
def test_so3_exp_log(rv):
    R = so3_exp(rv)
    assert np.allclose(R.T @ R, np.eye(3), atol=1e-14)
    assert np.isclose(np.linalg.det(R), 1.0)
    assert np.allclose(so3_exp(so3_log(R)), R, atol=1e-12)
    # R leaves its axis fixed
    assert np.allclose(R @ rv, rv, atol=1e-12)


def test_so3_small_angles():
    for th in (0.0, 1e-12, 1e-8, 1e-6, 1e-4):
        rv = np.array([0.3, -0.4, 0.5]) / np.linalg.norm([0.3, -0.4, 0.5]) * th
        assert np.allclose(so3_log(so3_exp(rv)), rv, atol=1e-15)
        assert np.allclose(so3_exp(rv), rot_axis_ref(rv), atol=1e-15)


def test_so3_log_near_pi_precision():
    # An angle taken from arccos(trace) would lose about half the digits near pi (~1e-8 rad);
    # so3_log goes through the quaternion and is accurate to rounding there.
    rng = np.random.default_rng(7)
    axes = rng.normal(size=(100, 3))
    axes /= np.linalg.norm(axes, axis=-1, keepdims=True)
    for eps in (0.0, 1e-10, 1e-6, 1e-3):
        R = so3_exp(axes * (np.pi - eps))
        assert np.allclose(so3_exp(so3_log(R)), R, atol=1e-13)
        assert np.allclose(so3_exp(rotvec_from_matrix(R)), R, atol=1e-13)


def rot_axis_ref(rv):
    """Rodrigues with cos/sin directly (reference)."""
    th = np.linalg.norm(rv)
    if th == 0:
        return np.eye(3)
    n = rv / th
    K = np.array([[0, -n[2], n[1]], [n[2], 0, -n[0]], [-n[1], n[0], 0]])
    return np.eye(3) + np.sin(th) * K + (1 - np.cos(th)) * K @ K


# --- transforms: naming, compose, invert --------------------------------------------------------


def test_naming_rule_p_a_equals_T_a_b_p_b():
    # Frame b sits at (100, 0, 0) in frame a, turned 90 deg about z: b's x axis is a's y axis.
    T_a_b = transforms_from(rot_z(np.pi / 2), [100.0, 0.0, 0.0])
    assert np.allclose(transform_points(T_a_b, [0.0, 0.0, 0.0]), [100.0, 0.0, 0.0])
    assert np.allclose(transform_points(T_a_b, [1.0, 0.0, 0.0]), [100.0, 1.0, 0.0])
    # Composition: T_a_c = T_a_b @ T_b_c; c sits at (0, 10, 0) in b -> at (90, 0, 0) in a.
    T_b_c = transforms_from(None, [0.0, 10.0, 0.0])
    assert np.allclose(compose(T_a_b, T_b_c)[:3, 3], [90.0, 0.0, 0.0])


@SETTINGS
@given(rv1=rotvecs, p1=points, rv2=rotvecs, p2=points, x=points)
def test_compose_invert_identities(rv1, p1, rv2, p2, x):
    A, B = _transform(rv1, p1), _transform(rv2, p2)
    assert np.allclose(compose(A, invert_transforms(A)), np.eye(4), atol=1e-9)
    assert np.allclose(compose(invert_transforms(A), A), np.eye(4), atol=1e-9)
    assert np.allclose(invert_transforms(compose(A, B)), compose(invert_transforms(B), invert_transforms(A)), atol=1e-9)
    assert np.allclose(invert_transforms(A), np.linalg.inv(A), atol=1e-9)
    assert np.allclose(transform_points(compose(A, B), x), transform_points(A, transform_points(B, x)), atol=1e-8)


@SETTINGS
@given(rv=rotvecs, p=points)
def test_pose_round_trip_all_conventions_and_units(rv, p):
    T = _transform(rv, p)
    for name in POSE_CONVENTIONS:
        for lu in ("mm", "m"):
            for au in ("deg", "rad"):
                v = pose_from_transform(T, name, length_unit=lu, angle_unit=au)
                assert v.shape == ((7,) if name == "quaternion" else (6,))
                assert np.allclose(v[:3], p / (1000.0 if lu == "m" else 1.0))
                assert np.allclose(transform_from_pose(v, name, lu, au), T, atol=1e-9), (name, lu, au)


# --- batching equals a loop ---------------------------------------------------------------------


def test_batched_equals_loop():
    rng = np.random.default_rng(6)
    rv = rng.normal(size=(2, 3, 3)) * 1.5
    R = so3_exp(rv)
    T = transforms_from(R, rng.normal(size=(2, 3, 3)) * 100)
    # include a gimbal-locked item and a 180 deg item in the batch
    R[0, 0] = matrix_from_euler([0.4, np.pi / 2, 0.7], "kuka_abc")
    R[1, 2] = so3_exp([0.0, np.pi, 0.0])
    T[..., :3, :3] = R
    for name in CONVENTIONS:
        e = euler_from_matrix(R, name)
        assert e.shape == (2, 3, 3)
        loop = np.array([[euler_from_matrix(R[i, j], name) for j in range(3)] for i in range(2)])
        assert np.allclose(e, loop, atol=1e-15)
        assert np.allclose(
            matrix_from_euler(e, name),
            np.array([[matrix_from_euler(e[i, j], name) for j in range(3)] for i in range(2)]),
        )
    cases = [
        (quaternion_from_matrix, R),
        (matrix_from_quaternion, quaternion_from_matrix(R)),
        (rotvec_from_matrix, R),
        (matrix_from_rotvec, rv),
        (invert_transforms, T),
        (lambda t: pose_from_transform(t, "quaternion"), T),
        (lambda t: pose_from_transform(t, "fanuc_wpr", "m", "deg"), T),
        (lambda v: transform_from_pose(v, "rotvec", "m", "rad"), pose_from_transform(T, "rotvec", "m", "rad")),
    ]
    for f, x in cases:
        batched = f(x)
        loop = np.array([[f(x[i, j]) for j in range(3)] for i in range(2)])
        assert batched.shape == loop.shape
        assert np.allclose(batched, loop, atol=1e-15)


# --- error messages ------------------------------------------------------------------------------


def test_unknown_convention_lists_valid_names():
    with pytest.raises(ValueError, match=r"unknown Euler convention 'kuka'.*kuka_abc.*zyz"):
        matrix_from_euler([0, 0, 0], "kuka")
    with pytest.raises(ValueError, match=r"unknown Euler convention 'quaternion'"):
        euler_from_matrix(np.eye(3), "quaternion")
    with pytest.raises(ValueError, match=r"unknown pose convention 'abb'.*quaternion.*rotvec"):
        pose_from_transform(np.eye(4), "abb")
    with pytest.raises(ValueError, match=r"unknown length_unit 'cm'; valid: mm, m"):
        transform_from_pose(np.zeros(6), "kuka_abc", length_unit="cm")
    with pytest.raises(ValueError, match=r"unknown angle_unit 'grad'"):
        pose_from_transform(np.eye(4), "kuka_abc", angle_unit="grad")


def test_shape_errors_say_what_arrived():
    with pytest.raises(ValueError, match=r"angles: expected shape \(\.\.\., 3\), got \(4,\)"):
        matrix_from_euler([0, 0, 0, 0], "zxz")
    with pytest.raises(ValueError, match=r"R: expected shape \(\.\.\., 3, 3\), got \(4, 4\)"):
        euler_from_matrix(np.eye(4), "zxz")
    with pytest.raises(ValueError, match=r"expects shape \(\.\.\., 7\).*got \(6,\)"):
        transform_from_pose(np.zeros(6), "quaternion")
    with pytest.raises(ValueError, match=r"expects shape \(\.\.\., 6\).*got \(7,\)"):
        transform_from_pose(np.zeros(7), "kuka_abc")
    with pytest.raises(ValueError, match=r"T: expected shape \(\.\.\., 4, 4\), got \(3, 3\)"):
        pose_from_transform(np.eye(3), "kuka_abc")
    with pytest.raises(ValueError, match=r"rotvec: expected shape"):
        matrix_from_rotvec([1.0, 2.0])


def test_registry_descriptions_name_formula():
    assert "Rz(A) @ Ry(B) @ Rx(C)" in EULER_CONVENTIONS["kuka_abc"]
    assert "Rz(R) @ Ry(P) @ Rx(W)" in EULER_CONVENTIONS["fanuc_wpr"]
    assert "Rz(a) @ Rx(b) @ Rz(c)" in EULER_CONVENTIONS["zxz"]
    for required in ("kuka_abc", "fanuc_wpr", "zxz", "xyz_extrinsic", "rpy", "zyx_intrinsic", "zyz"):
        assert required in EULER_CONVENTIONS
    assert "quaternion" in POSE_CONVENTIONS and "rotvec" in POSE_CONVENTIONS
