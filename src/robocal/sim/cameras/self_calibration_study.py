"""The industrial variant of camera self-calibration compared with a laser-tracker calibration
(issue 15 item 4): a 6R arm with a wrist camera looking at a board fixed in the cell; joint
offsets and the identifiable link parameters from images only, against a tracker calibration of
the same pose count; both judged on a holdout set measured by a simulated tracker (evaluation only).

The truth: :meth:`VirtualRobot.perturbed` (lengths 0.5 mm, angles 0.05 deg, joint offsets
``offset_sigma_deg``). Views: :func:`robocal.sim.cameras.camera_cell.simulate_hand_eye_poses` (eye-in-hand,
board on a table), the joints by the nominal model's inverse kinematics; the camera sees the board
through the *true* robot at those joints, corners get ``pixel_noise`` [px]. Holdout: 200 random
configurations within the joint limits (10 % margin), one reflector on the flange measured with
0.02 mm noise; each model's predicted reflector positions are rigidly fitted to the measured ones
(the base frame is not part of either comparison) and the RMS distance is reported [mm].
"""

from __future__ import annotations

import warnings

import numpy as np

from ...calib import CalibrationProblem, Target, rigid_fit, solve
from ...handeye.self_calibration import solve_self_calibration
from ...io.boards import parse_board
from ...transforms import invert_transforms
from .camera_cell import default_camera, reachable, robot_joints, simulate_hand_eye_poses
from ..robot import VirtualRobot
from ..tracker import LaserTracker

__all__ = ["compare_with_tracker"]


def compare_with_tracker(nominal, *, n_poses: int = 30, seed: int = 0, pixel_noise: float = 0.3,
                         offset_sigma_deg: float = 0.5, board: str = "checkerboard:9x6:25mm",
                         tracker_sigma_mm: float = 0.02, n_holdout: int = 200) -> dict:
    """Holdout RMS [mm] of the nominal model, the self-calibrated one, a tracker calibration on the
    same poses and one on random poses (module docstring); ratios self-calibration / tracker;
    ``n_fits``, ``n_not_converged`` and ``not_converged`` (labels): the fits behind these figures
    that did not converge (their figures are then not at an optimum)."""
    robot = VirtualRobot.perturbed(nominal, seed, offset_sigma_deg=offset_sigma_deg, joint_noise_deg=0.0)
    b = parse_board(board)
    X = b.object_points()
    cam = default_camera()
    cell = simulate_hand_eye_poses(X, setup="eye_in_hand", n_images=n_poses, camera=cam, front_z=b.front_z, seed=seed,
                                   accept=lambda T: reachable(nominal, T), pose_noise_mm=0.0, pose_noise_deg=0.0,
                                   max_tilt_deg=50.0)
    q = robot_joints(nominal, cell.T_base_flange_true)
    ee = nominal.end_effectors[0].name
    F = robot.true_model.kinematics_with(q, T_world_base=np.eye(4), end_effectors=[0])[0][:, 0]
    T_ct = invert_transforms(cell.camera_pose)[None] @ invert_transforms(F) @ cell.target_pose[None]
    p = np.einsum("nij,pj->npi", T_ct[:, :3, :3], X) + T_ct[:, None, :3, 3]
    rng = np.random.default_rng(seed)
    uv = cam.project(p.reshape(-1, 3)).pixels.reshape(n_poses, -1, 2) + rng.normal(0.0, pixel_noise, (n_poses, len(X), 2))
    w, h = cam.image_size
    uv[~((uv[..., 0] >= 0) & (uv[..., 0] <= w - 1) & (uv[..., 1] >= 0) & (uv[..., 1] <= h - 1))] = np.nan
    free = [n for n, f in zip(nominal.params.names, nominal.params.free) if f]
    sc = solve_self_calibration(nominal, q, uv, X, cam, ["world"] * n_poses, camera_end_effector=ee,
                                link_parameters=free, pixel_sigma=pixel_noise)

    fits = [("self-calibration", bool(sc.converged))]
    tracker = LaserTracker.placed(seed + 1, reflectors=1, sigma_mm=tracker_sigma_mm)
    targets = [Target(n, None, tuple(r)) for n, r in zip((tracker.reflector_names), tracker.reflectors)]

    def tracker_model(q_cal):
        meas = tracker.measure(robot, q_cal, rng)
        problem = CalibrationProblem(nominal, q_cal, targets, meas.points, point_sigma_mm=tracker_sigma_mm,
                                     base_initial="fit")
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            res = solve(problem)
        fits.append((f"tracker calibration {len(fits)}", res.converged))
        return (problem.model_at(res.state).replace(T_world_base=np.eye(4)),
                np.asarray(problem.value(res.state, "targets")).reshape(-1)[:3])

    q_hold = robot.feasible_configurations(n_holdout, rng, margin=0.1)
    measured = tracker.measure(robot, q_hold, rng).points[:, 0]

    def holdout(model, reflector):
        Fh = model.kinematics_with(q_hold, T_world_base=np.eye(4), end_effectors=[0])[0][:, 0]
        pts = Fh[:, :3, :3] @ reflector + Fh[:, :3, 3]
        T = rigid_fit(pts, measured)
        return float(np.sqrt(np.mean(np.sum((pts @ T[:3, :3].T + T[:3, 3] - measured) ** 2, axis=1))))

    refl = tracker.reflectors[0]
    same = holdout(*tracker_model(q))
    rand = holdout(*tracker_model(robot.feasible_configurations(n_poses, rng, margin=0.1)))
    selfcal = holdout(sc.model, refl)
    return {"robot": nominal.name, "n_poses": n_poses, "seed": seed, "nominal_mm": holdout(nominal, refl),
            "self_calibration_mm": selfcal, "tracker_same_poses_mm": same, "tracker_random_poses_mm": rand,
            "ratio_same_poses": selfcal / same, "ratio_random_poses": selfcal / rand,
            "held": [d["name"] for d in sc.identifiability.dropped], "reprojection_rms_px": sc.rms_px,
            "n_fits": len(fits), "n_not_converged": sum(not ok for _, ok in fits),
            "not_converged": [label for label, ok in fits if not ok]}
