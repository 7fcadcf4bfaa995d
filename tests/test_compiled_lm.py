"""Issue 34 item 5: the Levenberg-Marquardt loop of point-only calibrations run in compiled code
(robocal.calib._lm_compiled / _lm_kernels) against robocal's Python loop on the same problem:
the same iterations, stop reasons, convergence verdicts and identifiability, estimates equal to
far below their standard deviations; both judged against the simulated truth of a campaign with
effects the model lacks (transmission error, warm-up growth, tracker scale)."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from robocal.calib import CalibrationProblem, Target, solve
from robocal.calib import _lm_compiled, _normal
from robocal.calib.solve import NotConvergedWarning
from robocal.robots import load_robot
from robocal.sim import LaserTracker, VirtualRobot
from robocal.sim.tracker_campaigns import effects_tracker_campaign as _campaign
from robocal.sim.tracker_campaigns import plain_tracker_campaign as _robot_campaign


def _solve(problem, monkeypatch, loop, **kw):
    with monkeypatch.context() as m:
        m.setenv(_lm_compiled.ENV, "always" if loop == "compiled" else "never")
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            res = solve(problem, **kw)
    return res, [w for w in caught if issubclass(w.category, NotConvergedWarning)]


def _assert_same(a, b, sigmas=1e-9):
    assert a.iterations == b.iterations
    assert a.reason == b.reason and a.converged == b.converged
    assert a.identifiability.identifiable == b.identifiability.identifiable
    assert a.rank == b.rank
    ok = np.isfinite(b.std)
    # equal to rounding: the normal equations are summed in another order (~1e-11 sigma in practice)
    assert np.all(np.abs(a.values - b.values)[ok] <= sigmas * b.std[ok])
    np.testing.assert_allclose(a.std[ok], b.std[ok], rtol=1e-8)
    np.testing.assert_allclose(a.residuals_before, b.residuals_before, rtol=0, atol=1e-9)
    np.testing.assert_allclose(a.residuals_after, b.residuals_after, rtol=0, atol=1e-8)
    assert a.sigma0 == pytest.approx(b.sigma0, rel=1e-10)
    assert a.condition_number == pytest.approx(b.condition_number, rel=1e-6)


@pytest.mark.parametrize("robot, n_targets, missing, auto", [
    ("abb_irb140", 1, False, False),  # the benchmark's shape: the identifiable geometry, all solved
    ("abb_irb140", 1, False, True),   # identifiability chooses the columns (an active subset)
    ("ur10", 3, True, True),          # three reflectors, one held fixed, missing points
])
def test_compiled_loop_equals_python_loop(monkeypatch, robot, n_targets, missing, auto):
    problem, truth, _ = _campaign(robot, n_targets=n_targets, missing=missing, identifiable_only=not auto)
    assert _normal.supports(problem)
    compiled, w_c = _solve(problem, monkeypatch, "compiled", auto_identifiable=auto)
    python, w_p = _solve(problem, monkeypatch, "python", auto_identifiable=auto)
    assert python.converged and not w_c and not w_p
    _assert_same(compiled, python)
    # judged at the truth: the base frame of the simulated robot in the tracker frame (effects the
    # model lacks bias it by a few tenths of a millimetre at most)
    base = compiled.value("base")[0]
    assert np.linalg.norm(base[:3, 3] - truth[:3, 3]) < 1.0  # mm
    assert compiled.rms_after < 0.1  # mm: the effects are ~0.02-0.05 mm, the start several mm
    assert compiled.rms_before > 10 * compiled.rms_after


@pytest.mark.parametrize("tols, reason", [(dict(ftol=0.0), "chi-square change and its estimated remainder below"),
                                          (dict(chi2_tol=0.0), "relative cost reduction below ftol")])
def test_compiled_loop_stops_for_the_same_reason(monkeypatch, tols, reason):
    problem, _, _ = _campaign(n_poses=60, seed=3, identifiable_only=True)
    compiled, _ = _solve(problem, monkeypatch, "compiled", auto_identifiable=False, **tols)
    python, _ = _solve(problem, monkeypatch, "python", auto_identifiable=False, **tols)
    assert compiled.converged and compiled.reason.startswith(reason)
    _assert_same(compiled, python)


@pytest.mark.parametrize("tols", [dict(chi2_tol=0.0, ftol=0.0), dict(chi2_tol=0.0, ftol=0.0, xtol=0.0)])
def test_compiled_loop_at_the_precision_floor(monkeypatch, tols):
    # with the statistical and cost criteria off, both loops iterate down to rounding; there, whether a
    # step of ~1e-12 sigma still lowers the cost is decided by the last bits of two sums taken in
    # different orders, so the stop may be "step below xtol" in one and "no step reduces the cost at
    # a stationary point" in the other -- both converged, never "not at a minimum"
    problem, _, _ = _campaign(n_poses=60, seed=3, identifiable_only=True)
    compiled, _ = _solve(problem, monkeypatch, "compiled", auto_identifiable=False, **tols)
    python, _ = _solve(problem, monkeypatch, "python", auto_identifiable=False, **tols)
    for res in (compiled, python):
        assert res.converged
        assert res.reason == "step below xtol" or res.reason.startswith("no step reduces the cost at a stationary")
    # the Python loop's kernels may run in numpy or compiled (robocal.kinematics._backend): a third
    # rounding path, so the last few rounding-level steps may differ by a few iterations
    assert abs(compiled.iterations - python.iterations) <= 4
    ok = np.isfinite(python.std)
    assert np.all(np.abs(compiled.values - python.values)[ok] <= 1e-8 * python.std[ok])


def test_compiled_loop_reports_an_unconverged_solve(monkeypatch):
    problem, _, _ = _campaign(n_poses=60, seed=4, identifiable_only=True)
    compiled, w_c = _solve(problem, monkeypatch, "compiled", auto_identifiable=False, max_iterations=2)
    python, w_p = _solve(problem, monkeypatch, "python", auto_identifiable=False, max_iterations=2)
    assert not compiled.converged and compiled.iterations == 2
    assert compiled.reason == "maximum iterations reached"
    assert len(w_c) == 1 and "did not converge" in str(w_c[0].message) and len(w_p) == 1
    _assert_same(compiled, python)


def test_compiled_loop_only_where_it_applies(monkeypatch):
    problem, _, _ = _campaign(n_poses=40, seed=6, identifiable_only=True)
    monkeypatch.setenv(_lm_compiled.ENV, "never")
    assert not _lm_compiled.use_compiled(problem, 40)
    monkeypatch.setenv(_lm_compiled.ENV, "always")
    assert _lm_compiled.use_compiled(problem, 40)
    # progress(iteration, cost) gets the Python loop's calls (after the compiled loop returns)
    seen = {}
    for loop in ("always", "never"):
        monkeypatch.setenv(_lm_compiled.ENV, loop)
        calls = seen[loop] = []
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            res = solve(problem, auto_identifiable=False, progress=lambda it, cost, calls=calls: calls.append((it, cost)))
        assert [it for it, _ in calls] == list(range(1, res.iterations + 1))
    np.testing.assert_allclose([c for _, c in seen["always"]], [c for _, c in seen["never"]], rtol=1e-9)
    # a robust loss keeps the Python loop (reweighting per iteration)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        huber = solve(problem, auto_identifiable=False, loss="huber")
    assert huber.converged


def test_compile_ahead_gives_the_solver_s_specialisation(monkeypatch):
    # compile_kernels() compiles the loop for the argument types a real solve passes (one
    # specialisation: a second one would cost another ~6 s compile in the first real solve)
    from numba import typeof

    from robocal.calib import _lm_kernels

    problem, _, _ = _campaign(n_poses=20, seed=7, identifiable_only=True)
    pk = _lm_compiled._packed(problem)
    real = _lm_compiled._kernel_args(pk, problem.initial_state(), np.ones(pk.n, dtype=bool), np.zeros(7))
    seen = []
    monkeypatch.setattr(_lm_kernels, "lm_points", lambda *a: seen.append(a))
    _lm_compiled.compile_kernels()
    assert [typeof(a) for a in seen[0]] == [typeof(a) for a in real]


def test_compiled_loop_on_coupled_joints(monkeypatch):
    # FANUC's J2/J3 coupling: the model joints are a linear map of the controller's
    problem = _robot_campaign("fanuc_r2000ic_165f")
    assert not np.allclose(problem.model.coupling, np.eye(6))
    compiled, _ = _solve(problem, monkeypatch, "compiled")
    python, _ = _solve(problem, monkeypatch, "python")
    assert python.converged
    _assert_same(compiled, python)


def test_compiled_loop_on_a_urdf_robot(monkeypatch):
    # rotations and translations about arbitrary axes (URDF joints, OP_RU / OP_TU). A hard start: ~40
    # heavily damped iterations whose costs agree to ~1e-11 between the loops all the way; at the
    # precision floor one loop may refuse a step of ~1e-12 relative cost the other takes, so the last
    # iteration and the converged stop's wording may differ there (both converged, same estimates)
    problem = _robot_campaign("hilti_trailblazer")
    codes = set(problem.model._op_code.tolist())
    assert {6, 7} <= codes  # OP_RU, OP_TU
    costs = {}
    results = {}
    for loop in ("compiled", "python"):
        calls = costs[loop] = []
        results[loop], _ = _solve(problem, monkeypatch, loop, progress=lambda it, c, calls=calls: calls.append(c))
    compiled, python = results["compiled"], results["python"]
    assert compiled.converged and python.converged
    assert abs(compiled.iterations - python.iterations) <= 3
    n = min(len(costs["compiled"]), len(costs["python"])) - 1
    np.testing.assert_allclose(costs["compiled"][:n], costs["python"][:n], rtol=1e-8)
    ok = np.isfinite(python.std)
    assert np.all(np.abs(compiled.values - python.values)[ok] <= 1e-3 * python.std[ok])
    assert compiled.rms_after == pytest.approx(python.rms_after, rel=1e-9)


@pytest.mark.parametrize("case", ["base fixed", "no geometry", "targets fixed"])
def test_compiled_loop_with_blocks_held(monkeypatch, case):
    # the column map without a base frame, without geometry, or with the target points known
    nominal = load_robot("ur10")
    vr = VirtualRobot.perturbed(nominal, 3, joint_noise_deg=0.0)
    rng = np.random.default_rng(3)
    tracker = LaserTracker.placed(3, 3, sigma_mm=0.02)
    q = vr.random_configurations(50, rng, margin=0.1)
    pts = np.array(tracker.measure(vr, q, rng).points)
    T = tracker.T_tracker_world @ vr.true_model.T_world_base
    known = case == "targets fixed"
    targets = [Target(f"r{k}", None, tuple(tracker.reflectors[k] + (0.0 if known else 2.0)), free=not known)
               for k in range(3)]
    kw = {"base fixed": dict(estimate_base=False, base_initial=T), "no geometry": dict(free=[], base_initial="fit"),
          "targets fixed": dict(base_initial="fit")}[case]
    problem = CalibrationProblem(nominal, q, targets, pts, point_sigma_mm=0.02, **kw)
    compiled, _ = _solve(problem, monkeypatch, "compiled")
    python, _ = _solve(problem, monkeypatch, "python")
    assert python.converged
    _assert_same(compiled, python)


def test_auto_compiles_once_the_process_has_solved_enough_points(monkeypatch):
    """``auto``: a study of many small solves switches to the compiled loop once the points it solved in
    the Python loop are worth the loop's compile (counted, so every machine takes the same path)."""
    import types

    import robocal.calib
    from robocal.calib import _lm_compiled

    # a process where the loop is not compiled and not in the cache (whatever this test process did)
    stub = types.SimpleNamespace(lm_points=types.SimpleNamespace(signatures=[]))
    monkeypatch.setattr(robocal.calib, "_lm_kernels", stub, raising=False)
    monkeypatch.setitem(__import__("sys").modules, "robocal.calib._lm_kernels", stub)
    monkeypatch.delenv(_lm_compiled.ENV, raising=False)
    monkeypatch.setattr(_lm_compiled, "_cache_checked", True)
    monkeypatch.setattr(_lm_compiled, "_points_solved", _lm_compiled.COMPILE_AFTER_POINTS - 150)
    assert not _lm_compiled.use_compiled(None, 100)  # 50 points short of the sum
    assert _lm_compiled.use_compiled(None, 100)  # the sum reached
    monkeypatch.setenv(_lm_compiled.ENV, "never")
    assert not _lm_compiled.use_compiled(None, 10**9)


def test_compiled_loop_leaves_its_start_state_as_it_was(monkeypatch):
    """A solve started from another result's state (calibrate's baseline fit -> the calibration) must
    not change that state: the 'before' figures are computed from it afterwards. The compiled loop once
    updated the start's base frame in place (the walk-through's held-out 'before' moved 1.70 -> 1.93 mm)."""
    problem, _, _ = _campaign(n_poses=40, seed=5)
    start, _ = _solve(problem, monkeypatch, "python", max_iterations=1)
    bases = np.array(start.state.bases, copy=True)
    targets = np.array(start.state.targets, copy=True)
    params = np.array(start.state.params, copy=True)
    res, _ = _solve(problem, monkeypatch, "compiled", state0=start.state, auto_identifiable=False)
    assert res.iterations > 0 and np.abs(res.state.bases - bases).max() > 1e-9  # the solve moved the base
    assert np.array_equal(start.state.bases, bases)
    assert np.array_equal(np.asarray(start.state.targets), targets)
    assert np.array_equal(start.state.params, params)
