"""The hand-eye campaigns with joint offsets (tests/test_handeye_refine.py and docs/handeye.md's
joint-offset figures): an ABB IRB 140 whose joints 2-5 are off by (0.03, -0.04, 0.05, -0.03) deg,
20 images of a 24-corner board, 0.1 px corner noise, 0.02 mm / 0.002 deg flange-pose noise.

* eye-to-hand (seed 7): a fixed camera 700 mm from the board on the flange;
* eye-in-hand (seed 8): the camera on the flange, the board 550 mm in front of it at ``q0``, the
  poses drawn until the whole board is in the image.

Each returns a :class:`OffsetCampaign` with the measured flange poses (from the nominal model, as a
controller reports them), the joints and the true offsets. Lengths mm, angles rad.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...robots import load_robot
from ...transforms import invert_transforms, so3_exp
from .handeye_points import CAMERA_MODELS, board_points, look_at, noisy_poses

__all__ = ["OFFSET_NAMES", "TRUE_OFFSETS_RAD", "OffsetCampaign", "eye_in_hand_campaign", "eye_to_hand_campaign"]

#: the joint-offset variables of the IRB 140 and their hidden true values [rad]
OFFSET_NAMES = tuple(f"theta{k}" for k in range(1, 7))
TRUE_OFFSETS_RAD = np.radians([0.0, 0.03, -0.04, 0.05, -0.03, 0.0])


@dataclass(frozen=True)
class OffsetCampaign:
    """robot (the nominal model), joints (N, 6) [rad], T_base_flange (N, 4, 4) measured flange poses
    [mm], image_points (N, P, 2) [px], target_points (P, 3) [mm], camera, setup."""

    robot: object
    joints: np.ndarray
    T_base_flange: np.ndarray
    image_points: np.ndarray
    target_points: np.ndarray
    camera: object
    setup: str


def _transform(R, t) -> np.ndarray:
    T = np.eye(4)
    T[:3, :3], T[:3, 3] = R, t
    return T


def _flange(robot, q, p=None) -> np.ndarray:
    """Flange poses (N, 4, 4) [mm] at joints q (N, 6) with parameter values p (default nominal)."""
    return robot.kinematics_with(q, p, T_world_base=np.eye(4), end_effectors=[0])[0][:, 0]


def _true_params(robot) -> np.ndarray:
    p = robot.params.values.copy()
    p[[robot.params.index(nm) for nm in OFFSET_NAMES]] += TRUE_OFFSETS_RAD
    return p


def eye_to_hand_campaign(n: int = 20, seed: int = 7) -> OffsetCampaign:
    """A fixed camera looking at a board on the flange (module docstring)."""
    robot, X, camera = load_robot("abb_irb140"), board_points(), CAMERA_MODELS["brown"]
    rng = np.random.default_rng(seed)
    q = np.radians([0.0, 20.0, -10.0, 0.0, 40.0, 0.0]) + rng.uniform(-0.35, 0.35, (n, 6))
    F_true, F_nominal = _flange(robot, q, _true_params(robot)), _flange(robot, q)
    T_ft = _transform(so3_exp(np.array([0.0, np.pi, 0.0])), [-100.0, -70.0, 20.0])  # board facing away
    centre = (F_true @ T_ft)[:, :3, 3].mean(0)
    normal = -(F_true @ T_ft)[:, :3, 2].mean(0)
    T_bc = look_at(centre + 700.0 * normal / np.linalg.norm(normal), centre)
    T_ct = invert_transforms(T_bc)[None] @ F_true @ T_ft
    P = np.einsum("nij,pj->npi", T_ct[:, :3, :3], X) + T_ct[:, None, :3, 3]
    uv = camera.project(P.reshape(-1, 3)).pixels.reshape(n, len(X), 2) + rng.normal(0, 0.1, (n, len(X), 2))
    F_meas = noisy_poses(F_nominal, rng, 0.02, 0.002)
    return OffsetCampaign(robot, q, F_meas, uv, X, camera, "eye_to_hand")


def eye_in_hand_campaign(n: int = 20, seed: int = 8) -> OffsetCampaign:
    """The camera on the flange, a board 550 mm in front of it at q0 (module docstring)."""
    robot, X, camera = load_robot("abb_irb140"), board_points(), CAMERA_MODELS["brown"]
    p_true = _true_params(robot)
    rng = np.random.default_rng(seed)
    q0 = np.radians([0.0, 20.0, 10.0, 0.0, 60.0, 0.0])
    X_fc = _transform(np.eye(3), [0.0, 60.0, 80.0])  # the camera on the flange
    T_bc0 = _flange(robot, q0[None], p_true)[0] @ X_fc
    Z = np.eye(4)  # the board 550 mm in front of the camera at q0, facing it
    Z[:3, :3] = np.column_stack([T_bc0[:3, 0], np.cross(-T_bc0[:3, 2], T_bc0[:3, 0]), -T_bc0[:3, 2]])
    Z[:3, 3] = T_bc0[:3, 3] + 550.0 * T_bc0[:3, 2] - Z[:3, :3] @ np.array([100.0, 70.0, 0.0])
    qs, uvs = [], []
    while len(qs) < n:  # random joint poses whose view keeps the whole board in the image
        qk = q0 + rng.uniform(-0.25, 0.25, 6)
        T_ct = invert_transforms(_flange(robot, qk[None], p_true) @ X_fc)[0] @ Z
        P = X @ T_ct[:3, :3].T + T_ct[:3, 3]
        px = camera.project(P).pixels
        if np.all(P[:, 2] > 100) and np.all((px > 0) & (px < [1279, 1023])):
            qs.append(qk)
            uvs.append(px)
    q = np.array(qs)
    uv = np.array(uvs) + rng.normal(0, 0.1, (n, len(X), 2))
    F_meas = noisy_poses(_flange(robot, q), rng, 0.02, 0.002)
    return OffsetCampaign(robot, q, F_meas, uv, X, camera, "eye_in_hand")
