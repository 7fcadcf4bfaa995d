"""Forward kinematics reference values, kernels against plain numpy, Jacobians against finite
differences for every model kind, model conversions, URDF round trips, numerical IK."""

from pathlib import Path

import numpy as np
import pytest

from robocal.io.urdf import UrdfError, read_urdf, write_urdf
from robocal.kinematics.convert import dh_to_mdh, mdh_to_urdf, to_urdf_kind
from robocal.kinematics.ik import ik_numeric
from robocal.robots import RobotFileError, list_robots, load_robot, parse_robot
from robocal.transforms import so3_log

DATASETS = Path(__file__).resolve().parents[2] / "shared" / "datasets"
ALL_ROBOTS = list_robots()


def random_joints(model, n, rng, span=2.5):
    lo = np.maximum(model.limits[:, 0], -span)
    hi = np.minimum(model.limits[:, 1], span)
    pris = np.array([abs(lo_) > 10 or abs(hi_) > 10 for lo_, hi_ in zip(model.limits[:, 0], model.limits[:, 1])])
    lo = np.where(pris & np.isfinite(model.limits[:, 0]), model.limits[:, 0], lo)
    hi = np.where(pris & np.isfinite(model.limits[:, 1]), model.limits[:, 1], hi)
    return rng.uniform(lo, hi, (n, model.n_joints))


def perturbed(model, rng, scale=0.01):
    """Model with every parameter moved a little, so no test relies on zeros in nominal tables."""
    return model.with_params(model.params.values + rng.normal(0.0, scale, len(model.params)))


# ----------------------------------------------------------------------------- reference values
def _dh(theta, d, a, alpha):
    ct, st, ca, sa = np.cos(theta), np.sin(theta), np.cos(alpha), np.sin(alpha)
    return np.array([[ct, -st * ca, st * sa, a * ct], [st, ct * ca, -ct * sa, a * st], [0, sa, ca, d], [0, 0, 0, 1]])


# Universal Robots, "DH parameters for calculations of kinematics and dynamics" (UR10, CB3), mm / rad
UR10_D = [127.3, 0.0, 0.0, 163.941, 115.7, 92.2]
UR10_A = [0.0, -612.0, -572.3, 0.0, 0.0, 0.0]
UR10_ALPHA = [np.pi / 2, 0.0, 0.0, np.pi / 2, -np.pi / 2, 0.0]


def test_ur10_zero_pose_matches_published_value():
    T = load_robot("ur10").fk(np.zeros(6))
    # at zero joints the tool flange sits at (a2 + a3, -(d4 + d6), d1 - d5)
    assert np.allclose(T[:3, 3], [-1184.3, -256.141, 11.6], atol=1e-9)
    assert np.allclose(T[:3, :3], [[1, 0, 0], [0, 0, -1], [0, 1, 0]], atol=1e-12)


def test_ur10_matches_published_dh_product_at_random_configurations():
    rng = np.random.default_rng(0)
    q = rng.uniform(-np.pi, np.pi, (25, 6))
    T = load_robot("ur10").fk(q)
    for qi, Ti in zip(q, T):
        ref = np.eye(4)
        for i in range(6):
            ref = ref @ _dh(qi[i], UR10_D[i], UR10_A[i], UR10_ALPHA[i])
        assert np.allclose(Ti, ref, atol=1e-9)


def test_kawasaki_bx200l_table_2_1_hand_derived_pose():
    # Controller J1 = 90 deg makes the model's theta1 = -90 + 90 = 0 (joint 1 runs opposite).
    # Walking table 2-1 by hand: shoulder (200, 0, 530), upper arm 1160 up, forearm offset 230 up,
    # forearm 1250 along base x, flange 225 further: (1675, 0, 1920); tool z along base x.
    m = load_robot("kawasaki_bx200l")
    T = m.fk(np.radians([90, 0, 0, 0, 0, 0]))
    assert np.allclose(T[:3, 3], [1675.0, 0.0, 1920.0], atol=1e-9)
    assert np.allclose(T[:3, :3], [[0, 0, 1], [-1, 0, 0], [0, -1, 0]], atol=1e-12)
    # at controller zero the same pose is turned by -90 deg about base z... no: by +90 (J1 flips sign)
    T0 = m.fk(np.zeros(6))
    assert np.allclose(T0[:3, 3], [0.0, 1675.0, 1920.0], atol=1e-9)


def test_fanuc_j3_is_the_forearm_angle_to_the_horizon():
    # FANUC J2/J3 interaction: J3 is measured against the horizon, the physical elbow is J2 + J3.
    # Moving J2 alone keeps the forearm's absolute orientation (so the flange orientation, with
    # the wrist at zero); the dataset's "J2 sweep" (J3 = -J2) keeps the elbow rigid instead.
    m = load_robot("fanuc_r2000ic_165f")
    j2 = np.radians(np.linspace(-30, 30, 7))
    q = np.zeros((7, 6))
    q[:, 1] = j2
    R = m.fk(q)[:, :3, :3]
    assert np.allclose(R, R[0], atol=1e-12)
    q[:, 2] = -j2
    assert np.allclose(m.model_joints(q)[:, 2], 0.0)
    d = np.linalg.norm(np.diff(m.fk(q)[:, :3, 3], axis=0), axis=1)
    assert np.ptp(d) < 1e-9  # rigid rotation about the J2 axis: equal chords


def test_justin_passive_torso_joint_is_coupled():
    m = load_robot("dlr_justin19")
    q = np.zeros(19)
    q[1], q[2] = 0.3, 0.5
    qm = m.model_joints(q)
    assert qm[3] == pytest.approx(-0.8)


# ----------------------------------------------------------------------------- kernels
@pytest.mark.parametrize("name", ALL_ROBOTS)
def test_compiled_fk_equals_plain_numpy_products(name):
    rng = np.random.default_rng(1)
    m = perturbed(load_robot(name), rng)
    q = random_joints(m, 40, rng)
    for e in range(len(m.end_effectors)):
        assert np.allclose(m.fk(q, e), m.fk_reference(q, e), atol=1e-9)
    assert np.allclose(m.fk_all(q)[:, 0], m.fk(q), atol=0)
    if m.is_serial:
        assert np.allclose(m.fk_single(np.ascontiguousarray(q[3])), m.fk(q[3]), atol=1e-12)


def test_link_frames_end_at_the_flange():
    m = load_robot("kuka_kr150_r3100")
    q = random_joints(m, 10, np.random.default_rng(2))
    frames = m.link_frames(q)
    assert frames.shape == (10, 6, 4, 4)
    assert np.allclose(frames[:, -1], m.fk(q), atol=1e-9)  # no tool in the file


def test_sincos_polynomial_accuracy():
    from robocal.kinematics._kernels import sincos_array

    x = np.random.default_rng(3).uniform(-1e3, 1e3, 100000)
    x[:4] = [0.0, np.pi / 2, -np.pi, 1e-300]
    s, c = sincos_array(x)
    assert np.max(np.abs(s - np.sin(x))) < 4e-16 * 1e3
    assert np.max(np.abs(c - np.cos(x))) < 4e-16 * 1e3
    small = np.abs(x) < 10
    assert np.max(np.abs(s[small] - np.sin(x[small]))) < 5e-16


# ----------------------------------------------------------------------------- Jacobians
def _fd_models():
    rng = np.random.default_rng(4)
    kuka = perturbed(load_robot("kuka_kr150_r3100"), rng)
    return {
        "dh (ur10)": perturbed(load_robot("ur10"), rng),
        "dh coupled (fanuc)": perturbed(load_robot("fanuc_r2000ic_165f"), rng),
        "dh_beta (kuka)": kuka,
        "mdh (converted kuka)": dh_to_mdh(kuka),
        "urdf (converted kuka)": mdh_to_urdf(dh_to_mdh(kuka)),
        "urdf prismatic (hilti)": perturbed(load_robot("hilti_trailblazer"), rng, 1e-3),
        "mdh tree coupled (justin)": perturbed(load_robot("dlr_justin19"), rng, 1e-3),
    }


FD_MODELS = _fd_models()


def _rel_err(a, b):
    return np.max(np.abs(a - b)) / max(1.0, np.max(np.abs(b)))


@pytest.mark.parametrize("kind", list(FD_MODELS))
def test_joint_jacobian_matches_finite_differences(kind):
    m = FD_MODELS[kind]
    rng = np.random.default_rng(5)
    q = random_joints(m, 6, rng)
    for e in range(len(m.end_effectors)):
        J = m.jacobian(q, e)
        h = 1e-6
        for j in range(m.n_joints):
            dq = np.zeros(m.n_joints)
            dq[j] = h
            Tp, Tm = m.fk(q + dq, e), m.fk(q - dq, e)
            dp = (Tp[:, :3, 3] - Tm[:, :3, 3]) / (2 * h)
            dw = so3_log(Tp[:, :3, :3] @ np.swapaxes(Tm[:, :3, :3], 1, 2)) / (2 * h)
            assert _rel_err(J[:, :3, j], dp) < 1e-6, (kind, e, j)
            assert _rel_err(J[:, 3:, j], dw) < 1e-6, (kind, e, j)


@pytest.mark.parametrize("kind", list(FD_MODELS))
def test_identification_jacobian_matches_finite_differences(kind):
    m = FD_MODELS[kind]
    rng = np.random.default_rng(6)
    q = random_joints(m, 5, rng)
    pts = np.array([[0.0, 0.0, 0.0], [35.0, -20.0, 120.0]])
    e = len(m.end_effectors) - 1
    Jp = m.identification_jacobian(q, points=pts, end_effector=e)
    J6 = m.identification_jacobian(q, end_effector=e)
    h = 1e-6
    v = m.params.values
    for p in range(len(m.params)):
        vp, vm = v.copy(), v.copy()
        vp[p] += h
        vm[p] -= h
        Tp, Tm = m.with_params(vp).fk(q, e), m.with_params(vm).fk(q, e)
        wp = (Tp[:, None, :3, :3] @ pts[None, :, :, None])[..., 0] + Tp[:, None, :3, 3]
        wm = (Tm[:, None, :3, :3] @ pts[None, :, :, None])[..., 0] + Tm[:, None, :3, 3]
        assert _rel_err(Jp[..., p], (wp - wm) / (2 * h)) < 1e-6, (kind, m.params.names[p])
        dw = so3_log(Tp[:, :3, :3] @ np.swapaxes(Tm[:, :3, :3], 1, 2)) / (2 * h)
        assert _rel_err(J6[:, 3:, p], dw) < 1e-6, (kind, m.params.names[p])
        assert np.allclose(J6[:, :3, p], Jp[:, 0, :, p])


def test_parameters_of_other_branches_have_zero_columns():
    m = load_robot("dlr_justin19")
    q = random_joints(m, 3, np.random.default_rng(7))
    J = m.identification_jacobian(q, end_effector="right")
    left = [i for i, k in enumerate(m.params.link_of) if m.links[k].name.startswith("left")]
    assert left and np.all(J[..., left] == 0)


# ----------------------------------------------------------------------------- conversions, URDF
@pytest.mark.parametrize("name", ["ur10", "kuka_kr150_r3100", "kawasaki_bx200l", "fanuc_r2000ic_165f", "abb_irb140"])
def test_dh_to_mdh_to_urdf_keeps_forward_kinematics(name):
    rng = np.random.default_rng(8)
    m = perturbed(load_robot(name), rng)
    q = random_joints(m, 30, rng)
    mdh = dh_to_mdh(m)
    urdf = mdh_to_urdf(mdh)
    assert mdh.kind == "mdh" and urdf.kind == "urdf"
    assert np.allclose(mdh.fk(q), m.fk(q), atol=1e-9)
    assert np.allclose(urdf.fk(q), m.fk(q), atol=1e-9)
    # parameters held fixed stay fixed under their new names (beta2 of the KUKA becomes beta3 in MDH)
    assert mdh.params.free.sum() <= m.params.free.sum()


def test_mdh_tree_converts_to_urdf():
    rng = np.random.default_rng(9)
    m = load_robot("dlr_justin19")
    q = random_joints(m, 10, rng)
    assert np.allclose(to_urdf_kind(m).fk_all(q), m.fk_all(q), atol=1e-9)


@pytest.mark.parametrize("name", ["ur10", "kawasaki_bx200l", "abb_irb140", "kuka_kr150_r3100"])
def test_urdf_write_read_round_trip(name, tmp_path):
    rng = np.random.default_rng(10)
    m = perturbed(load_robot(name), rng)
    path = write_urdf(m, tmp_path / f"{name}.urdf")
    back = read_urdf(path)
    q = random_joints(m, 20, rng)
    assert back.controller_joints == m.controller_joints
    assert np.allclose(back.fk(q), m.fk(q), atol=1e-9)
    with pytest.raises(FileExistsError):
        write_urdf(m, path)


def test_urdf_cannot_express_fanuc_coupling(tmp_path):
    with pytest.raises(UrdfError, match="driven by 2 controller joints"):
        write_urdf(load_robot("fanuc_r2000ic_165f"), tmp_path / "f.urdf")


def test_hilti_robot_file_equals_the_dataset_urdf():
    path = DATASETS / "hilti_trailblazer" / "raw" / "trailblazer.urdf"
    if not path.exists():
        pytest.skip(f"dataset not available at {path}")
    urdf = read_urdf(path, tips=["prism"])
    ship = load_robot("hilti_trailblazer")
    rng = np.random.default_rng(11)
    q = random_joints(ship, 20, rng)
    assert urdf.controller_joints == ship.controller_joints
    assert np.allclose(urdf.fk(q), ship.fk(q), atol=1e-6)


# ----------------------------------------------------------------------------- IK
@pytest.mark.parametrize("name", ["ur10", "kuka_kr150_r3100", "fanuc_r2000ic_165f", "hilti_trailblazer"])
def test_numeric_ik_round_trip(name):
    rng = np.random.default_rng(12)
    m = perturbed(load_robot(name), rng, 1e-3)
    q = random_joints(m, 100, rng)
    q0 = np.clip(q + rng.normal(0, 0.05, q.shape), m.limits[:, 0], m.limits[:, 1])
    res = ik_numeric(m, m.fk(q), q0)
    assert res.all_converged, res.summary()
    T = m.fk(res.q)
    assert np.max(np.linalg.norm(T[:, :3, 3] - m.fk(q)[:, :3, 3], axis=1)) < 1e-6


def test_numeric_ik_redundant_tree_arm():
    rng = np.random.default_rng(13)
    m = load_robot("dlr_justin19")
    q = random_joints(m, 50, rng, span=1.0)
    q0 = q + rng.normal(0, 0.05, q.shape)
    res = ik_numeric(m, m.fk(q, "left"), q0, end_effector="left")
    assert res.all_converged, res.summary()


def test_numeric_ik_reports_unreachable_targets():
    m = load_robot("ur10")
    T = m.fk(np.zeros((3, 6)))
    T[1, :3, 3] = [5000.0, 0.0, 0.0]  # beyond the 1.3 m reach
    res = ik_numeric(m, T, np.zeros((3, 6)) + 0.1, max_iterations=200)
    assert list(res.converged) == [True, False, True]
    assert res.status[1] in ("stalled", "max_iterations")
    assert res.position_error_mm[1] > 3000


# ----------------------------------------------------------------------------- model and files
def test_models_are_immutable():
    m = load_robot("ur10")
    before = m.params.values.copy()
    m2 = m.with_params(a2=-600.0)
    assert np.array_equal(m.params.values, before)
    assert m2.params.values[m2.params.index("a2")] == -600.0
    with pytest.raises(ValueError):
        m.params.values[0] = 1.0
    with pytest.raises(KeyError, match="did you mean"):
        m.params.index("alph2")


def test_kuka_has_24_free_of_30_parameters():
    m = load_robot("kuka_kr150_r3100")
    assert len(m.params) == 30 and int(m.params.free.sum()) == 24
    assert m.params.free[m.params.index("beta2")] and not m.params.free[m.params.index("d2")]


def _minimal(**over):
    data = {"format": "robocal-robot/1", "name": "t", "model": "dh", "length_unit": "mm", "angle_unit": "deg",
            "joints": [{"name": "J1", "theta": 0.0, "d": 100.0, "a": 50.0, "alpha": 90.0}]}
    data.update(over)
    return data


@pytest.mark.parametrize("change, message", [
    ({"model": "dhx"}, "'model' is 'dhx'"),
    ({"length_unit": "inch"}, "'length_unit' is 'inch'"),
    ({"joints": [{"name": "J1", "theta": 0.0, "d": 100.0, "a": 50.0}]}, "joint 'J1': missing parameter 'alpha'"),
    ({"joints": [{"name": "J1", "theta": 0.0, "d": "x", "a": 50.0, "alpha": 0.0}]}, "parameter 'd' must be a finite"),
    ({"joints": [{"name": "J1", "theta": 0.0, "d": 1.0, "a": 5.0, "alpha": 0.0, "limits": [10, -10]}]}, "lower < upper"),
    ({"joints": [{"name": "J1", "theta": 0.0, "d": 1.0, "a": 5.0, "alpha": 0.0, "fixed": ["q"]}]}, "unknown parameters"),
])
def test_bad_robot_files_name_the_problem(change, message):
    with pytest.raises(RobotFileError, match=message) as info:
        parse_robot(_minimal(**change), origin="my_robot.toml")
    assert "my_robot.toml" in str(info.value)


def test_non_finite_joints_are_refused_with_pose_and_joint():
    m = load_robot("ur10")
    q = np.zeros((5, 6))
    q[3, 4] = np.nan
    with pytest.raises(ValueError, match="pose 3, joint J5 is nan"):
        m.fk(q)
    with pytest.raises(ValueError, match=r"shape \(N, 6\)"):
        m.fk(np.zeros((5, 7)))
    # a large batch checks its joints in the threads, range by range: the same error
    from robocal.kinematics._threads import PARALLEL_MIN

    q = np.zeros((PARALLEL_MIN + 10, 6))
    q[PARALLEL_MIN + 7, 1] = np.inf
    with pytest.raises(ValueError, match=f"pose {PARALLEL_MIN + 7}, joint J2 is inf"):
        m.fk(q, out=np.empty((len(q), 4, 4)))
    q[PARALLEL_MIN + 7, 1] = 1e300  # finite values whose sum overflows are fine
    q[PARALLEL_MIN + 8, 1] = 1e308
    q[PARALLEL_MIN + 9, 1] = 1e308
    assert np.isfinite(m.fk(q)[:PARALLEL_MIN]).all()


def test_unknown_robot_suggests_close_names():
    with pytest.raises(RobotFileError, match="Did you mean: ur10"):
        load_robot("ur01")


def test_fk_out_and_threaded_batches_match_the_single_thread_kernel(monkeypatch):
    from robocal.kinematics import _threads

    m = load_robot("ur10")
    q = np.random.default_rng(3).uniform(-3, 3, (5000, 6))
    ref = m.fk(q)
    monkeypatch.setattr(_threads, "PARALLEL_MIN", 100)
    monkeypatch.setattr(_threads, "n_threads", lambda: 3)
    out = np.empty((5000, 4, 4))
    assert m.fk(q, out=out) is out
    # chunked threads, one pose and the scalar kernel may round differently (SIMD body against its
    # remainder loop, fused multiply-add): equal to 1e-9 mm and 1e-12 in the rotation
    tol = np.zeros((4, 4))
    tol[:3, :3], tol[:3, 3] = 1e-12, 1e-9
    assert np.all(np.abs(out - ref) <= tol)
    assert np.all(np.abs(m.fk(q[7]) - ref[7]) <= tol)
    assert np.all(np.abs(m.fk(q[7]) - m.fk_single(q[7])) <= tol)
    with pytest.raises(ValueError, match="out must be"):
        m.fk(q, out=np.empty((5000, 4, 3)))
    with pytest.raises(ValueError, match="not a finite number"):
        m.fk(np.array([0.0, np.nan, 0, 0, 0, 0]))


def _ulps(value, reference):
    """|value - reference| in units in the last place of the reference."""
    return np.abs(value - reference) / np.spacing(np.abs(reference))


def test_sincos_within_2_ulp_of_numpy_over_the_stated_range():
    from robocal.kinematics._kernels import _SINCOS_MAX, sincos_array

    rng = np.random.default_rng(11)
    k = np.arange(-64, 65)
    quarter_turns = np.concatenate([k * np.pi / 4, k * np.pi / 2, k * np.pi])
    edges = np.concatenate([
        quarter_turns, np.nextafter(quarter_turns, np.inf), np.nextafter(quarter_turns, -np.inf),
        [0.0, -0.0, 5e-324, -5e-324, 1e-300, 1e-8, -1e-8, _SINCOS_MAX, -_SINCOS_MAX],
    ])
    x = np.concatenate([rng.uniform(-4, 4, 300_000), rng.uniform(-100, 100, 300_000),
                        rng.uniform(-_SINCOS_MAX, _SINCOS_MAX, 300_000), edges])
    s, c = sincos_array(x)
    assert _ulps(s, np.sin(x)).max() <= 2.0
    assert _ulps(c, np.cos(x)).max() <= 2.0
    assert np.all(s[x == 0.0] == 0.0) and np.all(c[x == 0.0] == 1.0)  # (the sign of -0.0 is not kept)
    # beyond the polynomial's range: libm itself
    huge = np.array([_SINCOS_MAX * 1.001, -3e5, 1e10, 1e300])
    s, c = sincos_array(huge)
    assert np.array_equal(s, np.sin(huge)) and np.array_equal(c, np.cos(huge))


@pytest.mark.parametrize("kind", list(FD_MODELS))
def test_simd_fk_kernel_equals_the_pose_major_kernel(kind):
    """fk / link_frames (blocked structure-of-arrays kernel) against fk_fused (pose by pose, the same
    products): equal to 1e-12 mm and 1e-12 in the rotation, for every end effector, with a batch
    that ends in a partial block and joint angles beyond the polynomial sine's range."""
    from robocal.kinematics import _backend
    from robocal.kinematics._kernels import fk_fused

    m = FD_MODELS[kind]
    rng = np.random.default_rng(12)
    q = random_joints(m, 150, rng)
    revolute = np.abs(m.limits[:, 1] - m.limits[:, 0]) < 100
    q[5, revolute] += 3e5  # libm path
    ref, ref_links = fk_fused(q, m._fused_ints, m._fused_floats, True)
    tol = np.zeros((4, 4))
    tol[:3, :3], tol[:3, 3] = 1e-12, 1e-12
    old = _backend._mode
    _backend.set_kernels("compiled")  # the compiled kernel, not the numpy one auto picks for 150 poses
    try:
        for e in range(len(m.end_effectors)):
            assert np.all(np.abs(m.fk(q, e) - ref[:, e]) <= tol)
            assert np.allclose(m.fk(q[:20], e), m.fk_reference(q[:20], e), atol=1e-9)
        links = m.link_frames(q)
    finally:
        _backend.set_kernels(old)
    assert links.shape == ref_links.shape
    assert np.all(np.abs(links - ref_links) <= tol)
