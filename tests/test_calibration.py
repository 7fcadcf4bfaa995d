"""The calibration engine on simulated campaigns: recovery to the noise floor, identifiability,
uncertainty that matches the real spread, robust losses, pose selection, bad input."""

import numpy as np
import pytest

from robocal.calib import CalibrationProblem, ProblemError, Target, rigid_fit, solve
from robocal.calib.poses import pose_jacobians, select_poses
from robocal.calib.uncertainty import predicted_point_std
from robocal.calib.validation import holdout_errors, train_holdout_split
from robocal.robots import load_robot
from robocal.sim import LaserTracker, VirtualRobot
from robocal.sim.campaign_effects_fit import effects_campaign_fit, noise_limited_holdout_mse

TOOL = np.array([30.0, 40.0, 100.0])
SIGMA = 0.02


def campaign(name, seed, n_train=100, n_hold=200, tool=TOOL, sigma=SIGMA):
    """A perturbed robot measured by a tracker in its own unknown frame (no encoder noise)."""
    nominal = load_robot(name)
    robot = VirtualRobot.perturbed(nominal, seed, joint_noise_deg=0.0)
    tracker = LaserTracker.placed(seed + 100, reflectors=np.atleast_2d(tool), sigma_mm=sigma)
    rng = np.random.default_rng(seed + 200)
    q = robot.random_configurations(n_train + n_hold, rng, margin=0.1)
    meas = tracker.measure(robot, q, rng)
    truth = tracker.true_points(robot, q).reshape(len(q), 1, 3)
    return nominal, robot, q, meas.points, truth, n_train


def fit(nominal, q, points, sigma=SIGMA, **kw):
    prob = CalibrationProblem(nominal, q, [Target("r1", None, (0.0, 0.0, 50.0))], points,
                              point_sigma_mm=sigma, base_initial="fit")
    return prob, solve(prob, **kw)


expected_holdout_mse = noise_limited_holdout_mse  # sigma^2 trace(J_h (J^T J)^-1 J_h^T) / N_h (identifiable set)


@pytest.mark.parametrize("name", ["kuka_kr150_r3100", "ur10", "ur10_dh_beta"])
def test_simulated_campaign_reaches_the_noise_floor(name):
    """Issue acceptance: 100 poses, 0.02 mm tracker noise, unknown base 6 + tool 3, every
    identifiable DH (+beta) parameter and joint offset free: holdout error within 10 % of the
    noise-limited optimum, identified parameters within 3 reported standard deviations."""
    mse, mse_opt, z_scores = [], [], []
    for seed in range(4):
        nominal, robot, q, pts, truth, n = campaign(name, seed)
        prob, res = fit(nominal, q[:n], pts[:n])
        assert res.converged, res.summary()
        pred = prob.predict_points(res.state, q=q[n:])
        mse.append(np.mean(np.sum((pred - truth[n:]) ** 2, axis=-1)))
        mse_opt.append(expected_holdout_mse(prob, res, q[n:], SIGMA))
        true_vals = robot.true_model.params.values
        # a kept parameter that others trade off against estimates their combination (UR10's d2
        # absorbs d3 and d4 of its parallel axes), so only parameters free of trade-offs are compared
        partners = {p for d in res.identifiability.dropped for p, _ in d["trades_off_with"]}
        for i, nm in enumerate(prob.free_params):
            if nm in res.identifiability.identifiable and nm not in partners:
                z_scores.append((res.values[i] - true_vals[nominal.params.index(nm)]) / res.std[i])
    ratio = np.sqrt(np.mean(mse) / np.mean(mse_opt))
    assert 0.9 < ratio < 1.1, ratio
    assert np.sqrt(np.mean(mse)) < 0.02  # about 0.010-0.012 mm for these settings
    # |z| is normal-distributed: over ~70 estimates a pair of correlated ones can pass 3 by chance
    z = np.abs(np.array(z_scores))
    assert np.all(z < 4), z.max()
    assert np.mean(z < 3) >= 0.95
    assert 0.8 < np.sqrt(np.mean(z**2)) < 1.2  # the reported std is the real scale of the errors


@pytest.mark.parametrize("name", ["kuka_kr150_r3100", "ur10"])
def test_unmodelled_effects_bias_the_fit_as_first_order_theory_predicts(name):
    """The same campaign on the ``realistic`` preset of :mod:`robocal.sim.campaign_effects`:
    reducer transmission error (0.005 / 0.003 deg once / twice per revolution), 20 ppm warm-up
    of the arm during the campaign and a 5 ppm tracker scale error -- effects the DH (+beta)
    model lacks. The test above ("within 3 sigma" on a simulator equal to the model) cannot see
    them; here the tolerance the effects allow is derived from the hidden truth, to first order:
    with ``e`` the effect in the training measurements (measured minus the true robot's
    geometric points, noise-free) and ``J`` the fit's Jacobian, the estimate is biased by
    ``delta = J^+ e``; the hold-out error then is ``Jh delta - e_h`` (``e_h``: the effect in where
    the robot really was) plus the noise part of the test above.

    Asserted: every compared parameter within 3-4 sigma of truth + delta (as in the test above),
    the plain "within 3 sigma of truth" claim fails (the effects are far above the noise: the
    test can tell), and the hold-out RMS against where the robot really was within 10 % of the
    first-order prediction and far above the noise floor. Measured: naive max |z| 10-28, hold-out
    0.08 mm (UR10) and 0.17 mm (KR150) against 0.011 mm at the noise floor (docs/testing.md)."""
    z_naive, z_bias, ho, ho_pred, ho_floor = [], [], [], [], []
    for seed in range(2):
        c = effects_campaign_fit(name, seed, tool_mm=TOOL, sigma_mm=SIGMA)  # robocal.sim.campaign_effects_fit
        assert c["result"].converged, c["result"].summary()
        z_naive += list(c["z_naive"])
        z_bias += list(c["z_bias"])
        ho.append(c["holdout_mse"])
        ho_pred.append(c["predicted_mse"])
        ho_floor.append(c["floor_mse"])
    z_bias, z_naive = np.abs(z_bias), np.abs(z_naive)
    assert np.all(z_bias < 4), z_bias.max()
    assert np.mean(z_bias < 3) >= 0.95
    assert 0.5 < np.sqrt(np.mean(z_bias**2)) < 1.5
    assert z_naive.max() > 5, z_naive.max()  # the effects are visible: "within 3 sigma of truth" is false
    assert 0.9 < np.sqrt(np.mean(ho) / np.mean(ho_pred)) < 1.1, (ho, ho_pred)
    assert np.sqrt(np.mean(ho)) > 4 * np.sqrt(np.mean(ho_floor))  # far above the noise floor


def test_ur10_in_dh_beta_form_identifies_what_plain_dh_cannot():
    """UR10's parallel axes 2-3-4: plain DH alone shows only d2 + d3 + d4 (two parameters lost);
    with Hayati's beta on links 2 and 3 the count is the full 27 of a 6R arm measured by points.
    The plain-DH file gets beta2 and beta3 from the loader (its axes are parallel, issue 31), so
    both files now reach 27; holding the two betas gives plain DH's 25 back."""
    ranks = {}
    for name in ("ur10", "ur10_dh_beta"):
        nominal, robot, q, pts, truth, n = campaign(name, 12)
        prob, res = fit(nominal, q[:n], pts[:n])
        ranks[name] = (res.rank, set(res.identifiability.dropped_names))
    assert ranks["ur10"][0] == 27 and {"beta2", "beta3"}.isdisjoint(ranks["ur10"][1])
    assert ranks["ur10_dh_beta"][0] == 27
    nominal, robot, q, pts, truth, n = campaign("ur10", 12)
    held = nominal.with_free([n_ not in ("beta2", "beta3") for n_ in nominal.params.names])
    _, res = fit(held, q[:n], pts[:n])
    assert res.rank == 25 and {"d3", "d4"} <= set(res.identifiability.dropped_names)
    assert {"beta2", "beta3"}.isdisjoint(ranks["ur10_dh_beta"][1])


def test_identifiability_reports_tradeoffs_and_keeps_a_maximal_set():
    nominal, robot, q, pts, truth, n = campaign("kuka_kr150_r3100", 11)
    prob, res = fit(nominal, q[:n], pts[:n])
    dropped = {d["name"]: d for d in res.identifiability.dropped}
    # d1 is a translation along base z, theta1 a rotation about it: the unknown base absorbs both
    assert {"theta1", "d1"} <= set(dropped)
    assert any(p.startswith("base.") for p, _ in dropped["d1"]["trades_off_with"])
    # the last link's parameters move the (unknown) reflector only the way its own offset does
    assert {"d6", "a6"} <= set(dropped)
    # 24 geometry + 6 base + 3 tool = 33 variables; a 6R arm measured by points has 27 (4R + 2P + 6 - 3)
    assert res.rank == 27 and len(res.identifiability.identifiable) == 27
    # nothing identifiable was dropped: adding any dropped column back loses rank
    _, J, _ = prob.evaluate(res.state)
    keep = [prob.names.index(nm) for nm in res.identifiability.identifiable]
    base_rank = np.linalg.matrix_rank(J[:, keep] / np.linalg.norm(J[:, keep], axis=0), tol=1e-6)
    for nm in dropped:
        c = prob.names.index(nm)
        cols = keep + [c]
        Js = J[:, cols] / np.maximum(np.linalg.norm(J[:, cols], axis=0), 1e-300)
        assert np.linalg.matrix_rank(Js, tol=1e-6) == base_rank, nm


@pytest.mark.parametrize("name", ["kuka_kr150_r3100", "ur10"])
def test_tool_point_on_the_joint6_axis_hides_two_more_parameters(name):
    """An unknown reflector on the joint-6 axis no longer turns with joint 6: theta6 has no effect
    at all, and a5, alpha5 become indistinguishable from the reflector's own offset, so the
    identifiable set shrinks by two compared with a reflector off the axis."""
    from robocal.calib import analyse_identifiability

    nominal = load_robot(name)
    q = VirtualRobot.perturbed(nominal, 5).random_configurations(100, np.random.default_rng(5), margin=0.1)
    reports = {}
    for label, tool in (("off_axis", (30.0, 40.0, 100.0)), ("on_axis", (0.0, 0.0, 120.0))):
        prob = CalibrationProblem(nominal, q, [Target("r1", None, tool)], None)
        _, J = prob.predict_points(prob.initial_state(), jacobian=True)
        reports[label] = analyse_identifiability(J.reshape(-1, prob.n_variables), prob.names, prob.blocks)
    off, on = reports["off_axis"], reports["on_axis"]
    assert on.rank == off.rank - 2
    assert set(on.dropped_names) - set(off.dropped_names) == {"a5", "alpha5"}
    why = {d["name"]: d["why"] for d in on.dropped}
    assert "no effect" in why["theta6"]


def test_reported_standard_deviations_match_the_monte_carlo_spread():
    """Re-measure the same poses with 150 noise draws: the spread of each estimate matches the
    standard deviation the solver reports (within +-20 %)."""
    nominal = load_robot("ur10")
    robot = VirtualRobot.perturbed(nominal, 21, joint_noise_deg=0.0)
    tracker = LaserTracker.placed(22, reflectors=np.atleast_2d(TOOL), sigma_mm=SIGMA)
    rng = np.random.default_rng(23)
    q = robot.random_configurations(60, rng, margin=0.1)
    truth = tracker.true_points(robot, q).reshape(len(q), 1, 3)
    base = None
    estimates, stds = [], None
    for _ in range(150):
        noisy = truth + rng.normal(0.0, SIGMA, truth.shape)
        prob = CalibrationProblem(nominal, q, [Target("r1", None, tuple(TOOL))], noisy, point_sigma_mm=SIGMA,
                                  base_initial="fit" if base is None else base)
        res = solve(prob)
        base = res.state.bases[0]
        active = np.isfinite(res.std) & (prob.blocks == "geometry")
        estimates.append(res.values[active])
        stds = res.std[active]
    spread = np.std(np.array(estimates), axis=0, ddof=1)
    ratio = spread / stds
    assert np.all((ratio > 0.8) & (ratio < 1.2)), ratio
    assert abs(np.median(ratio) - 1.0) < 0.1


def test_predicted_uncertainty_matches_real_prediction_errors():
    errs, preds = [], []
    for seed in range(3):
        nominal, robot, q, pts, truth, n = campaign("kuka_kr150_r3100", 30 + seed)
        prob, res = fit(nominal, q[:n], pts[:n])
        pred = prob.predict_points(res.state, q=q[n:])
        errs.append(np.sum((pred - truth[n:]) ** 2, axis=-1).ravel())
        preds.append(predicted_point_std(prob, res, q[n:]).ravel() ** 2)
    ratio = np.sqrt(np.mean(np.concatenate(errs)) / np.mean(np.concatenate(preds)))
    assert 0.8 < ratio < 1.2, ratio


def test_robust_loss_reports_the_outlier_poses():
    nominal, robot, q, pts, truth, n = campaign("ur10", 41)
    bad = [3, 17, 58, 80]
    corrupted = pts[:n].copy()
    corrupted[bad] += np.array([4.0, -3.0, 2.0])
    prob_clean, res_clean = fit(nominal, q[:n], pts[:n])
    for loss in ("huber", "cauchy"):
        prob, res = fit(nominal, q[:n], corrupted, loss=loss)
        assert sorted(o["pose"] for o in res.outliers) == bad, res.outliers
        assert all("robust scale" in o["reason"] for o in res.outliers)
        pred = prob.predict_points(res.state, q=q[n:])
        err = np.sqrt(np.mean(np.sum((pred - truth[n:]) ** 2, axis=-1)))
        assert err < 0.05, (loss, err)
    prob, res = fit(nominal, q[:n], corrupted)  # plain least squares is dragged away
    pred = prob.predict_points(res.state, q=q[n:])
    assert np.sqrt(np.mean(np.sum((pred - truth[n:]) ** 2, axis=-1))) > 0.1


def test_truncated_svd_and_lm_agree():
    nominal, robot, q, pts, truth, n = campaign("kuka_kr150_r3100", 51)
    _, lm = fit(nominal, q[:n], pts[:n])
    _, svd = fit(nominal, q[:n], pts[:n], method="svd")
    assert svd.converged
    active = np.isfinite(lm.std)
    assert np.all(np.abs(lm.values[active] - svd.values[active]) < 1e-3 * lm.std[active] + 1e-9)


def test_holdout_validation_and_split():
    train, hold = train_holdout_split(120, 0.25, seed=3)
    assert len(hold) == 30 and len(np.intersect1d(train, hold)) == 0
    assert np.array_equal(hold, train_holdout_split(120, 0.25, seed=3)[1])
    nominal, robot, q, pts, truth, n = campaign("ur10", 61)
    prob, res = fit(nominal, q[:n], pts[:n])
    v = holdout_errors(prob, res, q[n:], pts[n:])
    # the 'before' state already has the fitted base, so the error is the robot's own (mm level)
    assert v["position_before"]["rms"] > 0.3
    assert v["position_after"]["rms"] < 0.05
    assert v["position_after"]["p95"] <= v["position_after"]["max"]


def test_pose_selection_beats_random_pose_sets():
    nominal = load_robot("kuka_kr150_r3100")
    robot = VirtualRobot.perturbed(nominal, 71, joint_noise_deg=0.0)
    q = robot.random_configurations(400, np.random.default_rng(72), margin=0.1)
    prob = CalibrationProblem(nominal, q, [Target("r1", None, tuple(TOOL))], None)
    Jb = pose_jacobians(prob)
    sel = select_poses(Jb, 30, names=prob.names, blocks=prob.blocks)
    assert len(set(sel["indices"].tolist())) == 30
    assert np.all(robot.nominal.within_limits(q[sel["indices"]]))
    from robocal.calib.identifiability import observability_indices

    cols = [prob.names.index(nm) for nm in sel["identifiable"]]
    rng = np.random.default_rng(73)
    random_o1 = [observability_indices(Jb[rng.choice(400, 30, replace=False)].reshape(-1, Jb.shape[-1])[:, cols])["O1"]
                 for _ in range(20)]
    assert sel["selected_O1"] > max(random_o1)


def test_rigid_fit_recovers_a_transform():
    rng = np.random.default_rng(81)
    A = rng.normal(0, 500, (20, 3))
    from robocal.transforms import so3_exp

    T = np.eye(4)
    T[:3, :3] = so3_exp(np.array([0.3, -1.2, 2.0]))
    T[:3, 3] = [1000.0, -2000.0, 300.0]
    B = A @ T[:3, :3].T + T[:3, 3]
    assert np.allclose(rigid_fit(A, B), T, atol=1e-9)
    with pytest.raises(ValueError, match="collinear"):
        rigid_fit(np.outer(np.arange(5.0), [1, 2, 3]), np.outer(np.arange(5.0), [1, 2, 3]))


# ----------------------------------------------------------------------------- bad input
def test_bad_input_errors_name_the_problem():
    nominal, robot, q, pts, truth, n = campaign("ur10", 91, n_train=30, n_hold=0)
    tgt = [Target("r1", None, (0.0, 0.0, 50.0))]
    q_nan = q.copy()
    q_nan[4, 2] = np.nan
    with pytest.raises(ProblemError, match="pose 4, joint J3"):
        CalibrationProblem(nominal, q_nan, tgt, pts)
    with pytest.raises(ProblemError, match=r"expected shape \(30, 1, 3\)"):
        CalibrationProblem(nominal, q, tgt, pts[:, 0])
    with pytest.raises(ProblemError, match="metres given as millimetres"):
        CalibrationProblem(nominal, q, tgt, pts / 1000.0, base_initial="fit")
    with pytest.raises(ValueError, match="too few measurements"):
        solve(CalibrationProblem(nominal, q[:5], tgt, pts[:5], base_initial="fit"))
    with pytest.raises(KeyError, match="did you mean"):
        CalibrationProblem(nominal, q, tgt, pts, free=["alpah2"])


def test_rank_deficient_pose_set_is_reported_not_solved_silently():
    # poses that only move joint 1: the arm geometry beyond it cannot be separated
    nominal, robot, q, pts, truth, n = campaign("ur10", 92, n_train=40, n_hold=0)
    q1 = np.tile(q[0], (40, 1))
    q1[:, 0] = np.linspace(-2.5, 2.5, 40)
    tracker = LaserTracker.placed(193, reflectors=np.atleast_2d(TOOL), sigma_mm=SIGMA)
    meas = tracker.measure(robot, q1, np.random.default_rng(0))
    prob = CalibrationProblem(nominal, q1, [Target("r1", None, (0.0, 0.0, 50.0))], meas.points,
                              point_sigma_mm=SIGMA, base_initial="fit")
    res = solve(prob)
    assert len(res.identifiability.dropped) >= 15
    assert np.all(np.isnan(res.std[[prob.names.index(d) for d in res.identifiability.dropped_names]]))
    assert "not identifiable" in res.summary()
