"""The LM damping rules (issue 34 item 3): ``Problem.damping = "tenfold"`` (the default) and ``"gain"``
(Nielsen's rule) reach the same minimum by the same stop rules; an unknown rule is refused. Judged
against the simulated truth and against each other (far below the standard deviations)."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from robocal.calib import CalibrationProblem, Target, solve
from robocal.robots import load_robot
from robocal.sim import LaserTracker, VirtualRobot


def _problem(seed=3, n_poses=50):
    nominal = load_robot("ur10")
    robot = VirtualRobot.perturbed(nominal, seed, joint_noise_deg=0.0)
    rng = np.random.default_rng(seed)
    tracker = LaserTracker.placed(seed, 1, sigma_mm=0.02)
    q = robot.random_configurations(n_poses, rng, margin=0.1)
    pts = np.array(tracker.measure(robot, q, rng).points)
    targets = [Target("r0", None, tuple(tracker.reflectors[0] + 2.0))]
    return CalibrationProblem(nominal, q, targets, pts, base_initial="fit", point_sigma_mm=0.02), robot


def _solve(problem, damping, **kw):
    problem.damping = damping
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return solve(problem, **kw)


@pytest.mark.parametrize("prior", [0.0, 1e-3])
def test_gain_rule_reaches_the_tenfold_rules_minimum(prior):
    problem, robot = _problem()
    ten = _solve(problem, "tenfold", prior_weight=prior)
    gain = _solve(problem, "gain", prior_weight=prior)
    assert ten.converged and gain.converged
    ok = np.isfinite(ten.std)
    # the same least-squares minimum: within a hundredth of a standard deviation
    assert np.all(np.abs(gain.values - ten.values)[ok] <= 0.01 * ten.std[ok])
    assert gain.rms_after == pytest.approx(ten.rms_after, rel=1e-6)
    # and the simulated truth within the noise: the fitted points to 3 x the tracker's 0.02 mm
    assert gain.rms_after < 3 * 0.02


def test_unknown_damping_rule_is_refused():
    problem, _ = _problem(n_poses=20)
    with pytest.raises(ValueError, match="damping"):
        _solve(problem, "halving")
