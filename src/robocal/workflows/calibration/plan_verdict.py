"""One identifiability verdict (issue 28 item 4), the set-up of tests/test_plan_verdict.py and of
docs/calibration.md "One identifiability verdict": a UR10 with the reflector on the joint-6 axis
(100 mm along the flange's z, where the nominal geometry alone hides a5 and alpha5), 40 poses
planned in a cell with the tracker at (2500, 0, 500) mm, then calibrations of simulated robots
(perturbed by seeds 11, 12, 13, tracker noise 0.02 mm from one generator seeded 7) on those poses.
Written once, so the test and the documented figures use the same draws."""

from __future__ import annotations

import warnings

import numpy as np

from ...calib import CalibrationProblem, Target, solve
from ...robots import load_robot
from ...sim import VirtualRobot
from .plan_poses import plan_cell, plan_in_cell

__all__ = ["VERDICT_TOOL", "plan_and_calibrations"]

#: the reflector on the flange [mm]: on the joint-6 axis
VERDICT_TOOL = (0.0, 0.0, 100.0)


def plan_and_calibrations(seeds=(11, 12, 13), noise_seed: int = 7) -> tuple:
    """The plan of 40 poses and the calibration of one simulated robot per seed on them.

    Returns
    -------
    plan : dict
        :func:`robocal.workflows.calibration.plan_poses.plan_in_cell`'s result (``q``,
        ``identifiable``, ``names``, ``std`` [mm, rad], ...).
    results : list of CalibrationResult
        One per seed, in the order of ``seeds`` (warnings silenced).
    """
    model = load_robot("ur10")
    cell = plan_cell(model, None, (2500.0, 0.0, 500.0), VERDICT_TOOL)
    plan = plan_in_cell(model, cell, count=40, candidates=400, seed=0, efficiency=False)
    q = plan["q"]
    rng = np.random.default_rng(noise_seed)
    results = []
    for seed in seeds:
        true = VirtualRobot.perturbed(model, seed).true_model
        T = true.fk(q)
        pts = T[:, :3, 3] + T[:, :3, :3] @ np.array(VERDICT_TOOL) + rng.normal(0.0, 0.02, (len(q), 3))
        problem = CalibrationProblem(model, q, [Target("reflector", point=VERDICT_TOOL)], pts[:, None],
                                     base_initial="fit", point_sigma_mm=0.02)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            results.append(solve(problem))
    return plan, results
