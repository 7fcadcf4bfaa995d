"""Issue 34 items 4 and 5: point-only calibrations solve on normal equations summed per block of
poses (robocal.calib._normal), never forming the Jacobian. The reference is the general path (the
full Jacobian, ``Problem.evaluate``) on the same problem: the same iterations, stop reason and
identifiability verdicts, and estimates equal to far below their standard deviations. Both are
also judged against the simulated truth."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from robocal.calib import CalibrationProblem, solve
from robocal.calib import _normal
from robocal.sim.tracker_campaigns import reflector_campaign


def _problem(n_poses=60, seed=5, three_targets=False, missing=False):
    return reflector_campaign("ur10", n_poses=n_poses, seed=seed, three_targets=three_targets, missing=missing)


def _both(problem, monkeypatch, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        fast = solve(problem, **kw)
        with monkeypatch.context() as m:
            m.setattr(_normal, "supports", lambda p: False)
            general = solve(problem, **kw)
    return fast, general


@pytest.mark.parametrize("three_targets, missing", [(False, False), (True, True)])
def test_normal_equations_give_the_general_solution(monkeypatch, three_targets, missing):
    problem, truth = _problem(three_targets=three_targets, missing=missing)
    assert _normal.supports(problem)
    fast, general = _both(problem, monkeypatch)
    assert fast.converged and general.converged
    assert fast.iterations == general.iterations and fast.reason == general.reason
    assert fast.identifiability.identifiable == general.identifiability.identifiable
    assert [d["why"] for d in fast.identifiability.dropped] == [d["why"] for d in general.identifiability.dropped]
    ok = np.isfinite(general.std)
    # equal to rounding: 1e-6 of a standard deviation (they differ by ~1e-10 in practice: docs/calibration.md,
    # figure "calibration:normal equations agreement")
    assert np.all(np.abs(fast.values - general.values)[ok] <= 1e-6 * general.std[ok])
    np.testing.assert_allclose(fast.std[ok], general.std[ok], rtol=1e-8)
    assert fast.rms_after == pytest.approx(general.rms_after, rel=1e-9)
    assert fast.sigma0 == pytest.approx(general.sigma0, rel=1e-9)
    assert fast.rank == general.rank
    # the Jacobian, never formed by the solve, is evaluated on demand at the final state
    np.testing.assert_allclose(fast.jacobian, problem.evaluate(fast.state)[1], rtol=0, atol=1e-9)
    # and both recovered the simulated base frame (tracker 0.02 mm per coordinate)
    base = fast.value("base")[0]
    assert np.linalg.norm(base[:3, 3] - truth[:3, 3]) < 1.0  # mm


def test_normal_equations_in_blocks_equal_one_block():
    problem, _ = _problem(n_poses=50, three_targets=True, missing=True)
    state = problem.initial_state()
    r, J, _ = problem.evaluate(state)
    r1, ne1 = _normal.PointNormalEquations(problem, pose_block=7).evaluate(state)
    r2, ne2, R = _normal.PointNormalEquations(problem, pose_block=1000).r_factor(state)
    np.testing.assert_array_equal(r1, r)
    np.testing.assert_array_equal(r2, r)
    scale = np.abs(J.T @ J).max()
    np.testing.assert_allclose(ne1.JtJ, J.T @ J, rtol=0, atol=1e-12 * scale)
    np.testing.assert_allclose(ne2.Jtr, J.T @ r, rtol=0, atol=1e-12 * np.abs(J.T @ r).max())
    np.testing.assert_allclose(R.T @ R, J.T @ J, rtol=0, atol=1e-12 * scale)


def test_other_problems_take_the_general_path():
    problem, _ = _problem(n_poses=30)
    assert not _normal.supports(CalibrationProblem(problem.model, problem.q, problem.targets, problem.points,
                                                   stations=np.arange(30) % 2, point_sigma_mm=0.02))
    problem.evaluate = problem.evaluate  # an instance's own evaluate is read by the general path
    assert not _normal.supports(problem)
