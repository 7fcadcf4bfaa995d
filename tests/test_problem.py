"""Every measurement model of the calibration problem: analytic Jacobian against finite
differences, and recovery from each kind of measurement."""

import numpy as np

from robocal.calib import CalibrationProblem, Target, solve
from robocal.robots import load_robot
from robocal.sim import LaserTracker, VirtualRobot
from robocal.transforms import so3_exp


def _rich_problem(seed=0):
    nominal = load_robot("kuka_kr150_r3100")
    robot = VirtualRobot.perturbed(nominal, seed, joint_noise_deg=0.0)
    rng = np.random.default_rng(seed)
    q = robot.random_configurations(12, rng, margin=0.1)
    targets = [Target("r1", None, (30.0, 40.0, 100.0)), Target("r2", None, (-50.0, 10.0, 80.0))]
    pts = rng.normal(0, 1000, (12, 2, 3))
    pts[3, 1] = np.nan  # a missing measurement
    rot = so3_exp(rng.normal(0, 1, (12, 3)))
    stations = np.array([0] * 6 + [1] * 6)
    dist = [(0, 1, 0, 500.0), (2, 7, 1, 800.0)]
    plane = [(4, 0, 0), (5, 1, 0), (9, 0, 0)]
    base = np.eye(4)
    base[:3, :3] = so3_exp(np.array([0.1, -0.2, 0.3]))
    base[:3, 3] = [2000.0, -500.0, 100.0]
    prob = CalibrationProblem(nominal, q, targets, pts, stations=stations, base_initial=base, rotations=rot,
                              distances=dist, on_plane=plane, planes_initial=[[0.3, 1.2, 800.0]])
    return prob


def test_problem_jacobian_matches_finite_differences_for_every_measurement_kind():
    prob = _rich_problem()
    state = prob.retract(prob.initial_state(), np.random.default_rng(1).normal(0, 1e-3, prob.n_variables))
    r, J, labels = prob.evaluate(state)
    assert set(labels[:, 1]) == {0, 1, 2, 3}
    assert J.shape == (len(r), prob.n_variables)
    h = 1e-6
    for c in range(prob.n_variables):
        d = np.zeros(prob.n_variables)
        d[c] = h
        rp = prob.evaluate(prob.retract(state, d), jacobian=False)[0]
        rm = prob.evaluate(prob.retract(state, -d), jacobian=False)[0]
        fd = -(rp - rm) / (2 * h)  # J is the derivative of the prediction: r(x + dx) = r - J dx
        err = np.max(np.abs(fd - J[:, c])) / max(1.0, np.max(np.abs(fd)))
        assert err < 1e-6, (prob.names[c], err)


def test_six_d_pose_measurements_recover_the_tool_orientation_parameters():
    """With orientations measured, the last link's rotation parameters become identifiable."""
    nominal = load_robot("ur10")
    robot = VirtualRobot.perturbed(nominal, 3, joint_noise_deg=0.0)
    tracker = LaserTracker.placed(4, reflectors=3, sigma_mm=0.01)
    rng = np.random.default_rng(5)
    q = robot.random_configurations(60, rng, margin=0.1)
    meas = tracker.measure(robot, q, rng, orientation=True)
    targets = [Target(n, None, tuple(p)) for n, p in zip(meas.targets, tracker.reflectors)]
    only_points = CalibrationProblem(nominal, q, targets, meas.points, point_sigma_mm=0.01, base_initial="fit")
    res_p = solve(only_points)
    assert res_p.converged and res_p.rms_after < 0.03
    # three free reflectors: the full-pose count 4R + 2P + 6 = 30 (base and flange frame
    # included) plus the triangle's 3 shape parameters; the last link's parameters trade off
    # against the reflector positions; UR10's three parallel axes leave only d2 + d3 + d4, and
    # the beta2, beta3 the loader adds for them (issue 31) bring the two lost ranks back
    assert res_p.rank == 33
    assert {"d3", "d4"} <= set(res_p.identifiability.dropped_names)
    assert {"theta6", "alpha6"} <= set(res_p.identifiability.dropped_names)
    # one reflector plus the measured flange orientation: alpha6 and theta6 become identifiable.
    # The orientation comes from fitting the ~100 mm reflector triangle, so its noise is about
    # 0.01 mm / 100 mm = 1e-4 rad: weight rotations 0.01 / 1e-4 = 100 mm per rad.
    single = CalibrationProblem(nominal, q, targets[:1], meas.points[:, :1], point_sigma_mm=0.01,
                                base_initial="fit", rotations=meas.rotations, rotation_weight=100.0)
    res_r = solve(single)
    assert res_r.converged
    for name in ("theta6", "alpha6"):
        assert name in res_r.identifiability.identifiable
        i = single.names.index(name)
        true = robot.true_model.params.values[nominal.params.index(name)]
        assert abs(res_r.values[i] - true) < 4 * res_r.std[i]


def test_ballbar_distances_calibrate_without_any_frame():
    """Distances between the same point at pairs of poses (a ballbar or a length artefact) need no
    instrument frame: with the base fixed, they identify the arm geometry on their own."""
    nominal = load_robot("ur10")
    robot = VirtualRobot.perturbed(nominal, 8, joint_noise_deg=0.0)
    rng = np.random.default_rng(9)
    q = robot.random_configurations(240, rng, margin=0.1)
    tool = np.array([0.0, 0.0, 150.0])
    T = robot.true_poses(q)
    p = T[:, :3, :3] @ tool + T[:, :3, 3]
    pairs = [(2 * i, 2 * i + 1) for i in range(120)]
    d = [np.linalg.norm(p[a] - p[b]) + rng.normal(0, 0.005) for a, b in pairs]
    dist = [(a, b, 0, di) for (a, b), di in zip(pairs, d)]
    prob = CalibrationProblem(nominal, q, [Target("ball", None, tuple(tool), free=False)], None,
                              estimate_base=False, distances=dist, point_sigma_mm=0.005)
    res = solve(prob)
    assert res.converged
    r_before = prob.evaluate(prob.initial_state(), jacobian=False)[0] * 0.005
    r_after = res.residuals_after * 0.005
    assert np.sqrt(np.mean(r_before**2)) > 0.2
    assert np.sqrt(np.mean(r_after**2)) < 0.01
    # a distance is blind to where the robot stands: the unknown base would be unidentifiable
    assert {"theta1", "d1"} <= set(res.identifiability.dropped_names)


def test_points_on_a_plane_identify_the_plane_and_the_robot():
    nominal = load_robot("kuka_kr150_r3100")
    robot = VirtualRobot.perturbed(nominal, 12, joint_noise_deg=0.0)
    rng = np.random.default_rng(13)
    tool = np.array([0.0, 0.0, 200.0])
    # poses whose probe touches the plane z = 600 mm (base frame), found by IK on the true robot
    from robocal.kinematics.ik import ik_numeric

    q0 = robot.random_configurations(300, rng, margin=0.15)
    T0 = robot.true_poses(q0)
    tip = T0[:, :3, :3] @ tool + T0[:, :3, 3]
    target = T0.copy()
    shift = np.zeros((len(q0), 3))
    shift[:, 2] = 600.0 - tip[:, 2]
    target[:, :3, 3] += shift
    res_ik = ik_numeric(robot.true_model, target, q0)
    q = res_ik.q[res_ik.converged][:150]
    on_plane = [(i, 0, 0) for i in range(len(q))]
    prob = CalibrationProblem(nominal, q, [Target("tip", None, tuple(tool), free=False)], None, estimate_base=False,
                              on_plane=on_plane, planes_initial=[[0.0, np.pi / 2 - 0.01, 590.0]], point_sigma_mm=0.01)
    res = solve(prob)
    assert res.converged
    # the plane height and d1 both shift the probe along base z: d1 is reported and held, so the
    # fitted height is only known up to the robot's d1 error (0.5 mm standard deviation here)
    dropped = {d["name"]: d for d in res.identifiability.dropped}
    assert "plane0.offset" in [p for p, _ in dropped["d1"]["trades_off_with"]]
    off = prob.names.index("plane0.offset")
    assert abs(res.values[off] - 600.0) < 1.5
    assert np.max(np.abs(res.residuals_after)) * 0.01 < 1e-6
