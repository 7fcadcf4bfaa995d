"""Tests of robocal.kinematics.ik_analytic: OPW parameter extraction and closed-form IK."""

from __future__ import annotations

import numpy as np
import pytest

from robocal.kinematics.ik_analytic import (
    BRANCHES,
    NotAnalyticError,
    OPWParameters,
    ik_analytic,
    is_analytic,
    opw_fk,
    opw_from_model,
)
from robocal.kinematics.links import Link
from robocal.kinematics.model import EndEffector
from robocal.robots import frame_from_xyz_rpy, load_robot
from robocal.transforms import rot_z

ROBOTS = ["kuka_kr150_r3100", "abb_irb140", "fanuc_r2000ic_165f", "kawasaki_bx200l"]
POS_TOL = 1e-6   # mm
ROT_TOL = 1e-9   # rad


def _rot_err(R1, R2):
    """Rotation angle between rotation stacks, accurate for small angles."""
    D = np.swapaxes(R1, -1, -2) @ R2
    v = np.stack([D[..., 2, 1] - D[..., 1, 2], D[..., 0, 2] - D[..., 2, 0], D[..., 1, 0] - D[..., 0, 1]], -1)
    tr = D[..., 0, 0] + D[..., 1, 1] + D[..., 2, 2]
    return np.arctan2(0.5 * np.linalg.norm(v, axis=-1), 0.5 * (tr - 1.0))


def _angdiff(a, b):
    return np.abs((a - b + np.pi) % (2 * np.pi) - np.pi)


def _random_q(model, rng, n):
    lo, hi = model.limits[:, 0], model.limits[:, 1]
    return rng.uniform(lo, hi, size=(n, 6))


def _check_solutions(model, T, Q, V):
    """Every valid branch reproduces its target; invalid ones are NaN."""
    assert Q.shape == (len(T), 8, 6) and V.shape == (len(T), 8)
    assert np.all(np.isnan(Q[~V]))
    assert np.all(np.isfinite(Q[V]))
    idx = np.nonzero(V)
    T2 = model.fk(Q[idx])
    dp = np.linalg.norm(T2[:, :3, 3] - T[idx[0], :3, 3], axis=-1)
    dr = _rot_err(T2[:, :3, :3], T[idx[0], :3, :3])
    assert dp.max() <= POS_TOL, dp.max()
    assert dr.max() <= ROT_TOL, dr.max()


def _contains_original(model, q, Q, V, model_space=False):
    """Per sample: is q among the valid branches, modulo 2 pi (of model joints if model_space)."""
    if model_space:
        q, Q = model.model_joints(q), model.model_joints(Q)
    d = np.where(V, _angdiff(Q, q[:, None]).max(axis=-1), np.inf)
    return d.min(axis=1) < 1e-7


@pytest.mark.parametrize("name", ROBOTS)
def test_round_trip(name):
    model = load_robot(name)
    rng = np.random.default_rng(20240601)
    q = _random_q(model, rng, 500)
    T = model.fk(q)
    Q, V = ik_analytic(model, T)
    _check_solutions(model, T, Q, V)
    # At least 4 valid branches for a reachable target (the front shoulder, all wrist/elbow variants,
    # or the original's own shoulder side), and the original is recovered away from the wrist singularity.
    assert np.all(V.sum(axis=1) >= 4)
    theta5 = opw_from_model(model).opw_angles(q)[:, 4]
    nonsing = np.abs(np.sin(theta5)) > 1e-6
    assert nonsing.sum() > 450
    assert np.all(_contains_original(model, q, Q, V)[nonsing])
    # Returned joints: wrapped into the limits whenever a 2 pi shift allows it.
    lo, hi = model.limits[:, 0], model.limits[:, 1]
    shifted = Q[V][:, None, :] + 2 * np.pi * np.arange(-3, 4)[None, :, None]
    can = np.any((shifted >= lo) & (shifted <= hi), axis=1)
    inside = (Q[V] >= lo) & (Q[V] <= hi)
    assert np.all(inside | ~can)


@pytest.mark.parametrize("name", ROBOTS)
def test_within_limits(name):
    model = load_robot(name)
    rng = np.random.default_rng(7)
    q = _random_q(model, rng, 300)
    T = model.fk(q)
    Q_all, V_all = ik_analytic(model, T)
    Q, V = ik_analytic(model, T, within_limits=True)
    assert np.all(V <= V_all)
    assert np.all(model.within_limits(Q[V]))
    np.testing.assert_allclose(Q[V], Q_all[V], rtol=0, atol=1e-12)  # rad
    theta5 = opw_from_model(model).opw_angles(q)[:, 4]
    nonsing = np.abs(np.sin(theta5)) > 1e-6
    assert np.all(_contains_original(model, q, Q, V)[nonsing])


def test_all_eight_branches_counted():
    counts = {}
    rng = np.random.default_rng(3)
    for name in ROBOTS:
        model = load_robot(name)
        q = _random_q(model, rng, 400)
        _, V = ik_analytic(model, model.fk(q))
        counts[name] = float(np.mean(V.sum(axis=1) == 8))
    # Typical poses of these arms are reachable over the back shoulder as well: 8 branches.
    assert max(counts.values()) > 0.5, counts
    assert all(c > 0.3 for c in counts.values()), counts


def test_kuka_parameters():
    P = opw_from_model(load_robot("kuka_kr150_r3100"))
    assert isinstance(P, OPWParameters)
    got = [P.a1, P.a2, P.b, P.c1, P.c2, P.c3, P.c4]
    np.testing.assert_allclose(got, [350.0, 41.0, 0.0, 675.0, 1350.0, 1400.0, 215.0], atol=1e-9)
    np.testing.assert_allclose(P.T_world_base, np.eye(4), atol=1e-12)
    np.testing.assert_allclose(P.T_flange_ee, np.eye(4), atol=1e-12)
    # OPW forward model at the OPW zero: upright arm, flange above the wrist centre.
    T0 = opw_fk(P, np.zeros(6))
    np.testing.assert_allclose(T0[:3, 3], [350 + 41, 0, 675 + 1350 + 1400 + 215], atol=1e-9)
    assert len(BRANCHES) == 8 and BRANCHES[0] == ("front", "up", "noflip")


def test_wrist_singularity():
    model = load_robot("kuka_kr150_r3100")
    P = opw_from_model(model)
    # Controller joints with OPW theta5 = 0 exactly (KUKA: A5 = 0).
    q = np.array([[0.3, -1.2, 1.0, 0.7, 0.0, -0.4], [-0.5, -0.9, 0.2, -2.0, 0.0, 1.1]])
    assert np.allclose(P.opw_angles(q)[:, 4], 0.0)
    T = model.fk(q)
    Q, V = ik_analytic(model, T)
    _check_solutions(model, T, Q, V)
    # Documented choice: joint 4 = 0 in the noflip branches (pi in the flip ones), joint 6 absorbs.
    noflip = [i for i, b in enumerate(BRANCHES) if b[2] == "noflip"]
    for i in noflip:
        ok = V[:, i]
        assert np.allclose(Q[ok, i, 3], 0.0, atol=1e-12)
        assert np.allclose(_angdiff(Q[ok, i + 1, 3], np.pi), 0.0, atol=1e-12)
    # Near-singular poses still come out exact.
    qn = q.copy()
    qn[:, 4] = [1e-11, -3e-9]
    Tn = model.fk(qn)
    Qn, Vn = ik_analytic(model, Tn)
    _check_solutions(model, Tn, Qn, Vn)


def test_single_pose_and_unreachable():
    model = load_robot("abb_irb140")
    q = np.array([0.2, 0.3, -0.4, 0.5, 0.6, 0.7])
    Q, V = ik_analytic(model, model.fk(q))
    assert Q.shape == (8, 6) and V.shape == (8,)
    assert np.any(V & (_angdiff(Q, q).max(axis=-1) < 1e-9))
    far = np.tile(np.eye(4), (3, 1, 1))
    far[:, :3, 3] = [[1e5, 0, 0], [0, 0, 1e4], [0, -3000, 500]]
    Qf, Vf = ik_analytic(model, far)
    assert not Vf.any()
    assert np.all(np.isnan(Qf))


@pytest.mark.parametrize("model", [
    pytest.param(lambda: load_robot("ur10"), id="ur10"),
    pytest.param(lambda: load_robot("kuka_kr150_r3100").with_params(beta2=0.01), id="kuka-beta2"),
    pytest.param(lambda: load_robot("kuka_kr150_r3100").with_params(d5=1e-3), id="kuka-wrist-offset"),
    pytest.param(lambda: load_robot("abb_irb140").with_params(alpha1=np.radians(-90.01)), id="abb-alpha1"),
    pytest.param(lambda: load_robot("dlr_justin19"), id="justin"),
])
def test_not_analytic(model):
    m = model()
    assert not is_analytic(m)
    with pytest.raises(NotAnalyticError) as exc:
        opw_from_model(m)
    assert isinstance(exc.value, ValueError)
    with pytest.raises(NotAnalyticError):
        ik_analytic(m, np.eye(4))


def test_not_analytic_messages():
    with pytest.raises(NotAnalyticError, match=r"axes 2 and 3 are not parallel \(angle 0\.01 rad"):
        opw_from_model(load_robot("kuka_kr150_r3100").with_params(beta2=0.01))
    with pytest.raises(NotAnalyticError, match="axes 3 and 4 are not perpendicular"):
        opw_from_model(load_robot("ur10"))
    for name in ROBOTS:
        assert is_analytic(load_robot(name))


# ---------------------------------------------------------------------- other model kinds
def _rpy(R):
    return np.arctan2(R[2, 1], R[2, 2]), -np.arcsin(R[2, 0]), np.arctan2(R[1, 0], R[0, 0])


def _as_urdf(model, rng):
    """The same robot as a URDF-kind model with randomly rotated joint frames and axes."""
    from robocal.kinematics.links import elementary_transforms, link_operations, OP_RZ

    links, prev = [], np.eye(4)
    for k, L in enumerate(model.links):
        static = np.eye(4)
        theta0 = 0.0
        for code, pname, moves in link_operations(L):
            if moves:
                theta0 = L.params[pname]
                continue
            static = static @ elementary_transforms(code, L.params[pname])
        G = np.eye(4)
        G[:3, :3] = frame_from_xyz_rpy([0, 0, 0], rng.uniform(-1.2, 1.2, 3))[:3, :3]
        toff = rng.uniform(-1, 1)
        origin = prev @ elementary_transforms(OP_RZ, theta0 - toff) @ G
        roll, pitch, yaw = _rpy(origin[:3, :3])
        params = dict(x=origin[0, 3], y=origin[1, 3], z=origin[2, 3], roll=roll, pitch=pitch, yaw=yaw, theta=toff)
        axis = tuple(G[:3, :3].T @ np.array([0.0, 0.0, 1.0]))
        links.append(Link(L.name, "revolute", "urdf", params, k - 1, axis))
        prev = G.T @ static
    tool = frame_from_xyz_rpy([10.0, -20.0, 150.0], [0.1, -0.2, 0.3])
    ee = EndEffector("tool", 5, prev @ tool)
    base = frame_from_xyz_rpy([500.0, -200.0, 30.0], [0.02, -0.03, 1.0])
    urdf = model.replace(kind="urdf", links=links, end_effectors=[ee], T_world_base=base)
    # Reference: the original model with the same base and tool.
    ref = model.replace(end_effectors=[EndEffector("tool", 5, tool)], T_world_base=base)
    return urdf, ref


@pytest.mark.parametrize("name", ["kuka_kr150_r3100", "fanuc_r2000ic_165f"])
def test_urdf_kind_with_base_and_tool(name):
    rng = np.random.default_rng(11)
    urdf, ref = _as_urdf(load_robot(name), rng)
    q = _random_q(ref, rng, 200)
    np.testing.assert_allclose(urdf.fk(q), ref.fk(q), atol=1e-9)
    T = urdf.fk(q)
    Q, V = ik_analytic(urdf, T)
    _check_solutions(urdf, T, Q, V)
    assert np.all(_contains_original(urdf, q, Q, V))
    # Same solutions as from the plain model with that base and tool.
    Qr, Vr = ik_analytic(ref, T)
    np.testing.assert_array_equal(V, Vr)
    assert np.all(_angdiff(Q[V], Qr[V]) < 1e-8)


def test_general_coupling():
    base = load_robot("kuka_kr150_r3100")
    rng = np.random.default_rng(5)
    M = np.eye(6) + 0.3 * rng.standard_normal((6, 6))
    model = base.replace(coupling=base.coupling @ M, limits=np.tile([-10.0, 10.0], (6, 1)))
    qm = rng.uniform(-2.5, 2.5, size=(200, 6))
    q = qm @ np.linalg.inv(model.coupling).T
    T = model.fk(q)
    Q, V = ik_analytic(model, T)
    _check_solutions(model, T, Q, V)
    P = opw_from_model(model)
    nonsing = np.abs(np.sin(P.opw_angles(q)[:, 4])) > 1e-6
    assert np.all(_contains_original(model, q, Q, V, model_space=True)[nonsing])


def test_rotated_base_matches():
    model = load_robot("kawasaki_bx200l")
    T_wb = np.eye(4)
    T_wb[:3, :3] = rot_z(0.7) @ frame_from_xyz_rpy([0, 0, 0], [np.pi, 0, 0])[:3, :3]   # hanging robot
    T_wb[:3, 3] = [100.0, 200.0, 3000.0]
    hung = model.replace(T_world_base=T_wb)
    rng = np.random.default_rng(9)
    q = _random_q(hung, rng, 200)
    T = hung.fk(q)
    Q, V = ik_analytic(hung, T)
    _check_solutions(hung, T, Q, V)
    assert np.all(_contains_original(hung, q, Q, V)[np.abs(q[:, 4]) > 1e-6])


def test_shoulder_singularity_and_stretched_arm():
    model = load_robot("abb_irb140")   # b = 0: the wrist centre can lie on axis 1
    P = opw_from_model(model)
    k, phi = np.hypot(P.a2, P.c3), np.arctan2(P.a2, P.c3)
    t2 = -0.5
    t23 = np.arcsin(-(P.a1 + P.c2 * np.sin(t2)) / k) - phi
    theta = np.array([[0.3, t2, t23 - t2, 0.4, 0.5, 0.6],     # wrist centre on axis 1
                      [0.3, 0.2, -phi, 0.4, 0.5, 0.6]])       # elbow stretched (reach boundary)
    q = P.controller_joints(theta)
    T = model.fk(q)
    Q, V = ik_analytic(model, T)
    _check_solutions(model, T, Q, V)
    assert V[0].all()
    np.testing.assert_allclose(Q[0, :4, 0], 0.0, atol=1e-12)          # documented choice: q1 = 0 in front
    assert V[1].sum() == 4                                            # back shoulder out of reach
    assert _contains_original(model, q[1:], Q[1:], V[1:])[0]
