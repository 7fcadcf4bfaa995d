"""A simulated hand-eye cell: a camera on the flange (eye-in-hand) or fixed in the cell
(eye-to-hand), a board, robot poses that show the board, and the hidden truth (issue 14).

Views: the camera looks at the board centre from a random direction within ``max_tilt_deg`` of
the board normal (on the printed side), at a random distance, with a random roll about its axis
and a small random aim offset; views whose board points leave the image (with a margin) are drawn
again. The flange poses follow from the truth; the *reported* flange poses carry the robot's pose
noise (``pose_noise_mm`` per axis, ``pose_noise_deg`` per axis), as a controller's would.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...camera import Camera
from ...transforms import compose, invert_transforms, so3_exp, transforms_from

__all__ = ["HandEyeTruth", "simulate_hand_eye_poses", "default_camera", "robot_joints", "reachable", "SETUPS"]

SETUPS = ("eye_in_hand", "eye_to_hand")


def default_camera() -> Camera:
    """A 1280x1024 industrial camera with a 8 mm lens (fx = fy = 1600 px) and moderate distortion."""
    return Camera(1600.0, 1600.0, 641.5, 509.0, (-0.12, 0.09, 4e-4, -3e-4, 0.0), "brown", (1280, 1024))


@dataclass(frozen=True)
class HandEyeTruth:
    """The hidden truth and the data of a simulated cell, all [mm].

    setup: ``"eye_in_hand"`` | ``"eye_to_hand"``; camera_pose: T_flange_camera or T_base_camera;
    target_pose: T_base_target or T_flange_target; T_base_flange_true (N, 4, 4): the flange as it
    was; T_base_flange (N, 4, 4): as the controller reports it (with pose noise);
    T_camera_target (N, 4, 4): the board seen from the camera.
    """

    setup: str
    camera: Camera
    camera_pose: np.ndarray
    target_pose: np.ndarray
    T_base_flange_true: np.ndarray
    T_base_flange: np.ndarray
    T_camera_target: np.ndarray
    pose_noise_mm: float
    pose_noise_deg: float


def _look_at(eye: np.ndarray, centre: np.ndarray, roll: float) -> np.ndarray:
    """T_target_camera: camera at ``eye`` looking at ``centre`` (board frame), rolled by ``roll``."""
    z = centre - eye
    z /= np.linalg.norm(z)
    helper = np.array([0.0, 1.0, 0.0]) if abs(z[1]) < 0.9 else np.array([1.0, 0.0, 0.0])
    x = np.cross(helper, z)
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    R = np.stack([x, y, z], axis=1) @ so3_exp(np.array([0.0, 0.0, roll]))
    return transforms_from(R, eye)


def _views(camera: Camera, object_points: np.ndarray, front_z: int, n: int, rng, max_tilt_deg: float,
           margin_px: float) -> np.ndarray:
    """(n, 4, 4) T_camera_target whose board points all fall inside the image."""
    centre = object_points.mean(axis=0)
    extent = float(np.max(np.linalg.norm(object_points - centre, axis=1)))
    w, h = camera.image_size
    # distance at which the board spans about 60 % of the smaller image side
    base_distance = 2.0 * extent * min(camera.fx, camera.fy) / (0.6 * min(w, h))
    out = []
    for _ in range(200 * n):
        tilt = np.radians(rng.uniform(5.0, max_tilt_deg))
        azimuth = rng.uniform(0, 2 * np.pi)
        direction = np.array([np.sin(tilt) * np.cos(azimuth), np.sin(tilt) * np.sin(azimuth), front_z * np.cos(tilt)])
        distance = base_distance * rng.uniform(0.85, 1.3)
        aim = centre + rng.normal(0.0, 0.08 * extent, 3) * np.array([1, 1, 0])
        T_target_camera = _look_at(centre + distance * direction, aim, rng.uniform(-np.pi, np.pi))
        T_camera_target = invert_transforms(T_target_camera)
        p = (T_camera_target[:3, :3] @ object_points.T).T + T_camera_target[:3, 3]
        px = camera.project(p).pixels
        if np.all(np.isfinite(px)) and px[:, 0].min() > margin_px and px[:, 1].min() > margin_px \
                and px[:, 0].max() < w - 1 - margin_px and px[:, 1].max() < h - 1 - margin_px:
            out.append(T_camera_target)
            if len(out) == n:
                return np.array(out)
    raise RuntimeError(f"could not place {n} views of the board inside the image; check the camera and board")


def _pose_noise(n: int, rng, sigma_mm: float, sigma_deg: float) -> np.ndarray:
    return transforms_from(so3_exp(rng.normal(0.0, np.radians(sigma_deg), (n, 3))), rng.normal(0.0, sigma_mm, (n, 3)))


def simulate_hand_eye_poses(object_points: np.ndarray, *, setup: str = "eye_in_hand", n_images: int = 15,
                            camera: Camera | None = None, front_z: int = -1, pose_noise_mm: float = 0.05,
                            pose_noise_deg: float = 0.01, max_tilt_deg: float = 40.0, margin_px: float = 40.0,
                            seed: int = 0, accept=None) -> HandEyeTruth:
    """A cell with random truth and ``n_images`` views of the board (module docstring).

    object_points (P, 3) [mm]: the board's points (to keep them in view); front_z: the board's
    :attr:`~robocal.io.boards.Board.front_z` (the camera stays on the printed side); accept:
    optional ``accept(T_base_flange (M, 4, 4)) -> (M,) bool`` (e.g. a robot's reach): views are then
    drawn from 4 x ``n_images`` candidates, the first accepted ones kept.
    """
    if setup not in SETUPS:
        raise ValueError(f"setup must be one of {', '.join(SETUPS)}, got {setup!r}")
    rng = np.random.default_rng(seed)
    camera = camera or default_camera()
    n_draw = n_images if accept is None else 4 * n_images
    T_camera_target = _views(camera, np.asarray(object_points, float), front_z, n_draw, rng, max_tilt_deg, margin_px)
    if setup == "eye_in_hand":
        # camera about 100 mm off the flange, looking roughly along the tool axis
        camera_pose = transforms_from(so3_exp(rng.normal(0, 0.3, 3)), np.array([60.0, -40.0, 110.0]) + rng.normal(0, 10, 3))
        # the board on the table in front of the robot, rotated arbitrarily about its normal
        target_pose = transforms_from(so3_exp(np.array([0.0, 0.0, rng.uniform(-np.pi, np.pi)]))
                                      @ so3_exp(np.array([np.pi, 0.0, 0.0])), np.array([1100.0, 150.0, 50.0]))
        # T_base_flange = T_base_target T_target_camera T_camera_flange
        T_true = compose(target_pose, invert_transforms(T_camera_target), invert_transforms(camera_pose))
    else:
        camera_pose = transforms_from(so3_exp(np.array([np.pi, 0.0, 0.0]) + rng.normal(0, 0.2, 3)),
                                      np.array([1000.0, -200.0, 1500.0]) + rng.normal(0, 20, 3))
        target_pose = transforms_from(so3_exp(rng.normal(0, 0.3, 3)), np.array([0.0, 0.0, 120.0]) + rng.normal(0, 10, 3))
        # T_base_flange = T_base_camera T_camera_target T_target_flange
        T_true = compose(camera_pose, T_camera_target, invert_transforms(target_pose))
    if accept is not None:
        keep = np.flatnonzero(accept(T_true))[:n_images]
        if len(keep) < n_images:
            raise ValueError(f"only {len(keep)} of {n_draw} drawn views are accepted (robot reach?); need {n_images}")
        T_camera_target, T_true = T_camera_target[keep], T_true[keep]
    T_reported = compose(T_true, _pose_noise(n_images, rng, pose_noise_mm, pose_noise_deg))
    return HandEyeTruth(setup, camera, camera_pose, target_pose, T_true, T_reported, T_camera_target,
                        float(pose_noise_mm), float(pose_noise_deg))


def _feasible_branches(model, q, valid) -> np.ndarray:
    """``valid`` (N, B) narrowed to the branches ``q`` (N, B, n) the robot can take on its floor
    (docs/cells.md: no link at the floor or in another link)."""
    from ...calib.cell import default_cell, feasible

    valid = np.array(valid, dtype=bool, copy=True)
    if valid.any():
        valid[valid] = feasible(default_cell(), model, q[valid])
    return valid


def _ik_branches(model, T_base_flange: np.ndarray):
    from ...kinematics.ik_analytic import ik_analytic, is_analytic

    if not is_analytic(model):
        raise ValueError(f"robot {model.name}: joints for the simulated cell need a 6R robot with a spherical wrist "
                         "(closed-form inverse kinematics)")
    T = np.asarray(model.T_world_base) @ np.asarray(T_base_flange, dtype=float).reshape(-1, 4, 4)
    q, valid = ik_analytic(model, T, within_limits=True)
    valid = _feasible_branches(model, q, valid)
    cost = np.where(valid, np.nansum(q ** 2, axis=2), np.inf)
    best = np.argmin(cost, axis=1)
    rows = np.arange(len(T))
    return q[rows, best], np.isfinite(cost[rows, best])


def reachable(model, T_base_flange: np.ndarray) -> np.ndarray:
    """(N,) bool: which flange poses (N, 4, 4) [mm, base frame] ``model`` reaches within its limits."""
    return _ik_branches(model, T_base_flange)[1]


def robot_joints(model, T_base_flange: np.ndarray) -> np.ndarray:
    """(N, n) controller joints [rad] that put ``model``'s flange at ``T_base_flange`` (N, 4, 4) [mm,
    the model's base frame]: its closed-form inverse kinematics within the joint limits, the branch
    closest to the zero configuration among those the robot can take on its floor (docs/cells.md). ``ValueError`` naming the poses it cannot reach."""
    q, ok = _ik_branches(model, T_base_flange)
    if not ok.all():
        raise ValueError(f"robot {model.name} cannot reach the flange poses of images {np.flatnonzero(~ok).tolist()} "
                         "within its joint limits; choose another robot or seed")
    return q
