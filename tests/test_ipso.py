"""IPSO (issue 13): the swarm's pieces, its objective against the problem's residuals, bad input,
and the acceptance runs on the ER10L-C10 simulation (seeded)."""

import numpy as np
import pytest
from scipy.stats import qmc

from robocal.calib.swarm import (SwarmInputError, SwarmObjective, constriction_factor, halton_swarm, objective_at,
                                 run_pso, solve_swarm)
from robocal.workflows.calibration.ipso_study import er10l_experiment, pose_errors, run_method


def test_constriction_factor_is_clercs():
    assert constriction_factor(2.05, 2.05) == pytest.approx(0.7298, abs=5e-5)
    with pytest.raises(SwarmInputError, match="c1 \\+ c2 > 4"):
        constriction_factor(2.0, 2.0)


def test_halton_start_covers_the_box_better_than_random():
    lo, up = -np.r_[np.full(12, 0.01), np.full(12, 0.5)], np.r_[np.full(12, 0.01), np.full(12, 0.5)]
    x, v = halton_swarm(lo, up, 20, seed=3)
    assert x.shape == v.shape == (20, 24)
    assert np.all((x >= lo) & (x <= up)) and np.all(np.abs(v) <= (up - lo) / 2)
    u = (x - lo) / (up - lo)
    assert np.all(u.min(axis=0) < 0.2) and np.all(u.max(axis=0) > 0.8)  # every dimension spans the box
    assert np.all([(np.sum(c < 0.5) >= 6) and (np.sum(c >= 0.5) >= 6) for c in u.T])  # both halves, balanced
    rng = np.random.default_rng(0)
    random_disc = [qmc.discrepancy(rng.random((20, 24))) for _ in range(20)]
    assert qmc.discrepancy(u) < np.median(random_disc)
    x2, _ = halton_swarm(lo, up, 20, seed=3)
    assert np.array_equal(x, x2)


def test_pso_minimises_a_quadratic_deterministically():
    target = np.linspace(-0.5, 0.5, 6)

    def fun(X):
        return np.sum((X - target) ** 2, axis=1)

    a = run_pso(fun, -np.ones(6), np.ones(6), particles=20, generations=300, seed=1)
    b = run_pso(fun, -np.ones(6), np.ones(6), particles=20, generations=300, seed=1)
    assert a.best_f < 1e-10 and np.array_equal(a.best_x, b.best_x)
    assert np.all(np.diff(a.history) <= 0) and len(a.history) == 301


@pytest.mark.parametrize("kw, match", [
    (dict(lower=[], upper=[]), "empty"), (dict(lower=[1.0], upper=[0.0]), "inverted"),
    (dict(lower=[0.0], upper=[0.0]), "inverted"), (dict(particles=0), "particles"),
    (dict(generations=0), "generations"), (dict(lower=[np.nan], upper=[1.0]), "finite")])
def test_bad_swarm_input_is_a_clear_error(kw, match):
    args = dict(lower=[-1.0], upper=[1.0], particles=5, generations=5)
    args.update(kw)
    with pytest.raises(SwarmInputError, match=match):
        run_pso(lambda X: np.sum(X**2, axis=1), args.pop("lower"), args.pop("upper"), **args)


def test_non_finite_objective_is_counted_never_chosen():
    def fun(X):
        f = np.sum((X - 0.3) ** 2, axis=1)
        return np.where(X[:, 0] > 0.5, np.nan, f)  # "FK blows up" in part of the box

    out = run_pso(fun, -np.ones(2), np.ones(2), particles=10, generations=100, seed=0)
    assert np.isfinite(out.best_f) and out.best_x[0] <= 0.5 and out.non_finite > 0
    with pytest.raises(SwarmInputError, match="not finite for any particle"):
        run_pso(lambda X: np.full(len(X), np.inf), -np.ones(2), np.ones(2), particles=4, generations=3)


@pytest.fixture(scope="module")
def er10l_deg():
    return er10l_experiment(0, "deg")


def test_swarm_objective_is_objective_7_of_the_problems_residuals(er10l_deg):
    prob = er10l_deg.problem
    obj = SwarmObjective(prob)
    rng = np.random.default_rng(1)
    X = rng.uniform(-1, 1, (6, prob.n_variables)) * np.where(np.array(prob.units) == "rad", 0.01, 0.5)
    ref = [objective_at(prob, prob.retract(prob.initial_state(), x)) for x in X]
    np.testing.assert_allclose(obj(X), ref, rtol=1e-10)
    # by hand: mean over poses of |dp|^2 + k |d delta|^2 with k = 1000^2 mm^2/rad^2
    T = er10l_deg.nominal.fk(prob.residual_blocks[0].chain.q)
    rb_p, rb_r = prob.residual_blocks[:2]
    dp = np.sum((rb_p.measured - T[:, :3, 3]) ** 2, axis=1)
    c = np.clip((np.einsum("nij,nij->n", rb_r.measured, T[:, :3, :3]) - 1) / 2, -1, 1)
    assert obj(np.zeros((1, prob.n_variables)))[0] == pytest.approx(np.mean(dp + 1e6 * np.arccos(c) ** 2), rel=1e-8)


def test_ipso_plus_lm_matches_lm_and_ipso_improves_on_nominal(er10l_deg):
    """Acceptance (issue 13): degree-scale joint noise. Measured on seed 0: nominal 12.5 mm, IPSO
    alone 1.31 mm (a factor 9.5), LM and IPSO+LM 1.19 mm, noise floor 1.14 mm."""
    exp = er10l_deg
    nominal_mm = pose_errors(exp.nominal, exp.q_hold, exp.p_hold, exp.R_hold)[0]
    lm = run_method(exp, "lm")
    both = run_method(exp, "ipso+lm", seed=0)
    ipso = run_method(exp, "ipso", seed=0)
    assert abs(both["holdout_mm"] - lm["holdout_mm"]) <= 0.05 * lm["holdout_mm"]
    assert nominal_mm / ipso["holdout_mm"] >= 8.0, (nominal_mm, ipso["holdout_mm"])
    assert lm["holdout_mm"] <= 1.10 * exp.floor_mm


@pytest.mark.filterwarnings("ignore::robocal.calib.solve.NotConvergedWarning")  # 60 generations: still improving
def test_swarm_result_records_history_and_is_deterministic(er10l_deg):
    prob = er10l_deg.problem
    a = solve_swarm(prob, generations=60, seed=4)
    b = solve_swarm(prob, generations=60, seed=4)
    assert a.method == "ipso" and a.generations == 60 and a.history.shape == (61,)
    assert np.array_equal(a.values, b.values) and np.all(np.diff(a.history) <= 0)
    assert a.objective == pytest.approx(a.history[-1], rel=1e-9) and a.objective < a.objective_before
    assert set(a.search) == set(a.identifiability.identifiable) and len(a.search) == 24
    assert np.all(a.upper == np.where(np.array([prob.units[prob.names.index(n)] for n in a.search]) == "rad",
                                      0.01, 0.5))
    with pytest.raises(SwarmInputError, match="method"):
        solve_swarm(prob, method="pso")


def test_cli_ipso_records_method_generations_objective(tmp_path):
    import json

    from click.testing import CliRunner

    from robocal.cli import main as cli

    r = CliRunner()
    data = tmp_path / "ur10.csv"
    assert r.invoke(cli, ["simulate", "tracker", "ur10_dh_beta", "--poses", "40", "--noise", "0.02", "--seed", "1",
                          "--out", str(data)]).exit_code == 0
    res = r.invoke(cli, ["calibrate", "ur10_dh_beta", str(data), "--out", str(tmp_path / "cal"), "--method", "ipso+lm",
                         "--generations", "40", "--particles", "8", "--seed", "3", "--no-report"])
    assert res.exit_code == 0, res.output
    d = json.loads((tmp_path / "cal" / "result.json").read_text())
    assert d["method"] == "ipso+lm" and d["generations"] == 40 and d["objective"] > 0
    assert len(d["solver"]["swarm"]["history"]) == 41 and d["solver"]["swarm"]["particles"] == 8
    bad = r.invoke(cli, ["calibrate", "ur10_dh_beta", str(data), "--out", str(tmp_path / "c2"), "--method", "ipso",
                         "--loss", "huber", "--no-report"])
    assert bad.exit_code != 0 and "plain squared errors" in bad.output


def _objective_at_steps(prob, cols, X):
    """Objective (7) from Problem.evaluate at each row of X (steps of the variables ``cols``)."""
    ref = []
    for x in X:
        step = np.zeros(prob.n_variables)
        step[cols] = x
        ref.append(objective_at(prob, prob.retract(prob.initial_state(), step)))
    return ref


@pytest.mark.parametrize("search_base", [False, True])
def test_swarm_objective_with_points_and_searched_targets(search_base):
    """Tracker problem (PointResidual): the compiled sum (base fixed, targets searched) and the
    numpy path (base searched) both equal objective (7) from Problem.evaluate."""
    from robocal.workflows.calibration.ipso_study import tracker_experiment

    prob = tracker_experiment(0, n_train=30).problem
    names = [n for n, b in zip(prob.names, prob.column_blocks) if search_base or b != "base"]
    obj = SwarmObjective(prob, names=names)
    assert bool(obj._groups) != search_base
    cols = [prob.names.index(n) for n in names]
    rng = np.random.default_rng(2)
    X = rng.uniform(-1, 1, (5, len(names))) * np.where(np.array(prob.units)[cols] == "rad", 0.01, 0.5)
    ref = _objective_at_steps(prob, cols, X)
    np.testing.assert_allclose(obj(X), ref, rtol=1e-12)


@pytest.mark.parametrize("search_base", [False, True])
def test_swarm_objective_skips_missing_readings_like_the_problem(search_base):
    """Three reflectors with readings lost (NaN: a broken beam) at some poses: the compiled sum and
    the numpy path leave them out exactly as Problem.evaluate does, and the NaN never leaks into f."""
    from robocal.calib import CalibrationProblem, Target
    from robocal.robots import load_robot
    from robocal.sim import LaserTracker, VirtualRobot
    from robocal.sim.tracker import reflector_triangle

    nominal = load_robot("ur10_dh_beta")
    vr = VirtualRobot.perturbed(nominal, 4, joint_noise_deg=0.0)
    tracker = LaserTracker.placed(5, reflectors=reflector_triangle(), sigma_mm=0.02)
    rng = np.random.default_rng(6)
    q = vr.random_configurations(30, rng, margin=0.1)
    pts = tracker.measure(vr, q, rng).points.copy()
    lost = rng.random(pts.shape[:2]) < 0.2
    lost[0] = False                      # every reflector keeps enough readings
    pts[lost] = np.nan
    targets = [Target(f"r{k}", None, tuple(p)) for k, p in enumerate(reflector_triangle())]
    prob = CalibrationProblem(nominal, q, targets, pts, point_sigma_mm=0.02, base_initial="fit")
    names = [n for n, b in zip(prob.names, prob.column_blocks) if search_base or b != "base"]
    obj = SwarmObjective(prob, names=names)
    assert bool(obj._groups) != search_base
    cols = [prob.names.index(n) for n in names]
    X = rng.uniform(-1, 1, (4, len(names))) * np.where(np.array(prob.units)[cols] == "rad", 0.01, 0.5)
    ref = _objective_at_steps(prob, cols, X)
    f = obj(X)
    assert np.all(np.isfinite(f)) and lost.sum() > 10
    np.testing.assert_allclose(f, ref, rtol=1e-12)


def test_study_reports_tracker_orientation_against_truth_and_per_seed_rows():
    """The UR10 tracker study measures no orientation, yet the table reports the identified flange
    orientation against the simulation's truth (LM: 0.023 and 0.095 deg on seeds 0, 1); per-seed CSV rows agree
    with the medians."""
    import csv
    import io

    from robocal.workflows.calibration.ipso_study import compare, per_seed_csv, tracker_experiment

    table = compare(tracker_experiment, [0, 1], methods=("lm",))
    assert 0.0 < table["lm"]["holdout_deg"] < 0.1
    text = per_seed_csv({"UR10 tracker": table})
    rows = list(csv.DictReader(io.StringIO(text.split("\n", 1)[1])))
    assert [r["seed"] for r in rows] == ["0", "1"] and {r["method"] for r in rows} == {"lm"}
    deg = sorted(float(r["holdout_deg"]) for r in rows)
    assert abs(np.median(deg) - table["lm"]["holdout_deg"]) < 1e-5 * table["lm"]["holdout_deg"]
