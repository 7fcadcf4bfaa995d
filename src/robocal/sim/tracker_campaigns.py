"""The laser-tracker campaigns of tests/test_compiled_lm.py, tests/test_normal_equations.py and of
docs/calibration.md's normal-equations paragraph and "The compiled LM loop": a perturbed robot (no
joint noise) measured by a placed tracker (0.02 mm), built as the point-only ``CalibrationProblem`` the compiled Levenberg-Marquardt loop applies to. Written once, so
the test and the documented figure use the same draws."""

from __future__ import annotations

import numpy as np

from ..calib import CalibrationProblem, Target
from ..robots import load_robot
from .campaign_effects import measure_with_effects
from .robot import VirtualRobot
from .tracker import LaserTracker

__all__ = ["effects_tracker_campaign", "plain_tracker_campaign", "reflector_campaign"]


def effects_tracker_campaign(robot: str = "abb_irb140", n_poses: int = 80, seed: int = 11, n_targets: int = 1,
                             missing: bool = False, identifiable_only: bool = False):
    """A campaign whose robot and tracker have the ``realistic`` effects the model lacks
    (transmission error, warm-up growth, tracker scale: :func:`robocal.sim.campaign_effects.measure_with_effects`).

    Parameters
    ----------
    robot : str
        Library robot name.
    n_poses : int
        Number of poses (random configurations 0.1 rad inside the limits).
    seed : int
        Seed of the robot's perturbation, the tracker placement and the poses; ``seed + 1`` the effects.
    n_targets : int
        Reflectors; each starts 2 mm off per coordinate, the second (index 1) is held fixed.
    missing : bool
        Blank two measured points (pose 3 of the first reflector, pose 7 of the last).
    identifiable_only : bool
        Free only the geometry the data determine (every other model parameter fixed).

    Returns
    -------
    problem : CalibrationProblem
    truth : ndarray, shape (4, 4)
        T_tracker_base of the simulated robot [mm].
    tracker : LaserTracker
    """
    nominal = load_robot(robot)
    vr = VirtualRobot.perturbed(nominal, seed, joint_noise_deg=0.0)
    rng = np.random.default_rng(seed)
    tracker = LaserTracker.placed(seed, n_targets, sigma_mm=0.02)
    q = vr.random_configurations(n_poses, rng, margin=0.1)
    pts = np.array(measure_with_effects(vr, tracker, q, "realistic", seed + 1)["points"])
    if missing:
        pts[3, 0] = np.nan
        pts[7, -1] = np.nan
    targets = [Target(f"r{k}", None, tuple(tracker.reflectors[k] + 2.0), free=(k != 1))
               for k in range(n_targets)]
    problem = CalibrationProblem(nominal, q, targets, pts, base_initial="fit", point_sigma_mm=0.02)
    if identifiable_only:
        from ..calib import analyse_identifiability

        J = problem.evaluate(problem.initial_state())[1]
        keep = set(analyse_identifiability(J, problem.names, problem.blocks).identifiable)
        problem = CalibrationProblem(nominal, q, targets, pts, base_initial="fit", point_sigma_mm=0.02,
                                     free=[n for n in problem.free_params if n in keep])
    truth = tracker.T_tracker_world @ vr.true_model.T_world_base
    return problem, truth, tracker


def plain_tracker_campaign(robot: str, seed: int = 5, n_poses: int = 80) -> CalibrationProblem:
    """A campaign without unmodelled effects: one reflector (starting 2 mm off per coordinate),
    ``n_poses`` random configurations, tracker noise only (seeded by ``seed``): the problem of
    :func:`reflector_campaign` with one reflector."""
    return reflector_campaign(robot, n_poses=n_poses, seed=seed)[0]


def reflector_campaign(robot: str = "ur10", n_poses: int = 60, seed: int = 5, three_targets: bool = False,
                       missing: bool = False):
    """The campaign of tests/test_normal_equations.py: a perturbed robot (no joint noise), a placed
    tracker (0.02 mm), one or three reflectors each starting 2 mm off per coordinate (the first one
    free), tracker noise only.

    Parameters
    ----------
    robot : str
        Library robot name.
    n_poses : int
        Number of poses (random configurations 0.1 rad inside the limits).
    seed : int
        Seed of the robot's perturbation, the tracker placement, the poses and the noise.
    three_targets : bool
        Three reflectors instead of one.
    missing : bool
        Blank two measured points (pose 3 of the first reflector, pose 7 of the last).

    Returns
    -------
    problem : CalibrationProblem
    truth : ndarray, shape (4, 4)
        T_tracker_base of the simulated robot [mm].
    """
    nominal = load_robot(robot)
    vr = VirtualRobot.perturbed(nominal, seed, joint_noise_deg=0.0)
    rng = np.random.default_rng(seed)
    tracker = LaserTracker.placed(seed, 3 if three_targets else 1, sigma_mm=0.02)
    q = vr.random_configurations(n_poses, rng, margin=0.1)
    pts = np.array(tracker.measure(vr, q, rng).points)
    if missing:
        pts[3, 0] = np.nan
        pts[7, -1] = np.nan
    targets = [Target(f"r{k}", None, tuple(tracker.reflectors[k] + 2.0), free=(k == 0)) for k in range(pts.shape[1])]
    problem = CalibrationProblem(nominal, q, targets, pts, base_initial="fit", point_sigma_mm=0.02)
    return problem, tracker.T_tracker_world @ vr.true_model.T_world_base
