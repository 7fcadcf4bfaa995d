"""Simulated hand-eye data as projected target points (no images): a camera on the flange
(eye-in-hand) or fixed in the cell (eye-to-hand), a planar chessboard-like target, noisy robot
poses and noisy corners. For tests, the hand-eye study and the benchmark (issue 14); the
image-rendering simulator lives beside it.

Every quantity in millimetres and pixels; every random draw from the seed.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...camera import Camera
from ...transforms import invert_transforms, so3_exp

__all__ = ["HandEyeSimulation", "board_points", "simulate_hand_eye", "look_at", "noisy_poses", "CAMERA_MODELS"]

#: cameras of the study (1280 x 1024 px, f = 1400 px, a 12 mm lens on 8.6 um pixels say), by model
CAMERA_MODELS = {
    "none": Camera(1400.0, 1400.0, 640.0, 512.0, (0.0, 0.0, 0.0, 0.0, 0.0), "brown", (1280, 1024)),
    "radial": Camera(1400.0, 1400.0, 640.0, 512.0, (-0.25, 0.12, 0.0, 0.0, 0.0), "brown", (1280, 1024)),
    "brown": Camera(1400.0, 1400.0, 640.0, 512.0, (-0.25, 0.12, 0.0012, -0.0008, -0.03), "brown", (1280, 1024)),
    "division": Camera(1400.0, 1400.0, 640.0, 512.0, (-0.2,), "division", (1280, 1024)),
}


def board_points(cols: int = 11, rows: int = 8, square_mm: float = 20.0, bend_mm: float = 0.0) -> np.ndarray:
    """(rows * cols, 3) [mm] inner corners of a chessboard, origin at the first corner, z = 0; with
    ``bend_mm`` the true board sags by that much in the middle (a paraboloid), an effect a planar
    target model does not have."""
    g = np.stack(np.meshgrid(np.arange(cols, dtype=float), np.arange(rows, dtype=float)), -1).reshape(-1, 2)
    X = np.column_stack([g * square_mm, np.zeros(len(g))])
    if bend_mm:
        c = X[:, :2].mean(0)
        r2 = np.sum((X[:, :2] - c) ** 2, 1)
        X[:, 2] = bend_mm * (1.0 - r2 / r2.max())
    return X


def look_at(eye, target, up_hint=(0.0, 0.0, 1.0), roll=0.0) -> np.ndarray:
    """T (4, 4): a camera frame at ``eye`` with its z axis towards ``target`` (OpenCV: x right, y
    down), rolled by ``roll`` [rad] about z."""
    z = np.asarray(target, float) - np.asarray(eye, float)
    z /= np.linalg.norm(z)
    x = np.cross(z, up_hint)
    if np.linalg.norm(x) < 1e-6:
        x = np.cross(z, (1.0, 0.0, 0.0))
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    T = np.eye(4)
    T[:3, :3] = np.column_stack([x, y, z]) @ so3_exp(np.array([0.0, 0.0, roll]))
    T[:3, 3] = eye
    return T


def noisy_poses(T, rng, sigma_mm: float, sigma_deg: float) -> np.ndarray:
    """Poses T (N, 4, 4) each moved by a random small rotation (sigma_deg per axis, about the
    pose's origin) and translation (sigma_mm per axis)."""
    out = np.array(T, dtype=float)
    N = len(out)
    out[:, :3, :3] = so3_exp(rng.normal(0, np.radians(sigma_deg), (N, 3))) @ out[:, :3, :3]
    out[:, :3, 3] += rng.normal(0, sigma_mm, (N, 3))
    return out


@dataclass(frozen=True)
class HandEyeSimulation:
    """T_base_flange (N, 4, 4) as the controller reports it (with pose noise) and T_base_flange_true;
    image_points (N, P, 2) [px] (noisy, NaN outside the image); target_points (P, 3) [mm] as the
    user knows them (planar) and target_points_true; camera; setup; camera_pose: the true
    ``T_flange_camera`` or ``T_base_camera``; target_pose: the true ``T_base_target`` or
    ``T_flange_target``; T_camera_target (N, 4, 4) true."""

    setup: str
    T_base_flange: np.ndarray
    T_base_flange_true: np.ndarray
    image_points: np.ndarray
    target_points: np.ndarray
    target_points_true: np.ndarray
    camera: Camera
    camera_pose: np.ndarray
    target_pose: np.ndarray
    T_camera_target: np.ndarray


def _view_poses(rng, n, centre, distance, tilt_deg):
    """n camera frames looking at ``centre`` from a cap above it: distance (lo, hi) [mm], tilt from
    the z axis up to ``tilt_deg``, random roll."""
    out = np.empty((n, 4, 4))
    for i in range(n):
        tilt = np.radians(rng.uniform(5.0, tilt_deg))
        az = rng.uniform(0, 2 * np.pi)
        d = rng.uniform(*distance)
        eye = centre + d * np.array([np.sin(tilt) * np.cos(az), np.sin(tilt) * np.sin(az), np.cos(tilt)])
        aim = centre + rng.normal(0, 15.0, 3)
        out[i] = look_at(eye, aim, roll=rng.uniform(-np.pi / 2, np.pi / 2))
    return out


def simulate_hand_eye(seed: int = 0, *, n_images: int = 15, setup: str = "eye_in_hand", camera: Camera | None = None,
                      pixel_noise: float = 0.3, pose_noise_mm: float = 0.05, pose_noise_deg: float = 0.01,
                      board=(11, 8), square_mm: float = 20.0, bend_mm: float = 0.0, tilt_deg: float = 35.0,
                      distance=(450.0, 750.0)) -> HandEyeSimulation:
    """A seeded hand-eye data set (see :class:`HandEyeSimulation`).

    Eye-in-hand: the board lies at about (900, 0, 0) in the base; the camera, about 100 mm off the
    flange and turned, looks at it from ``distance`` with tilts up to ``tilt_deg``; the flange
    poses follow. Eye-to-hand: the camera hangs at (900, 600, 1300) looking down; the board, about
    80 mm off the flange, is shown to it at ``distance`` with tilts up to ``tilt_deg``.
    """
    rng = np.random.default_rng(seed)
    camera = CAMERA_MODELS["brown"] if camera is None else camera
    X_true = board_points(*board, square_mm, bend_mm)
    X = board_points(*board, square_mm)
    centre_t = X[:, :2].mean(0)
    if setup == "eye_in_hand":
        X_fc = np.eye(4)
        X_fc[:3, :3] = so3_exp(rng.normal(0, 0.3, 3)) @ so3_exp(np.array([0.0, 0.0, rng.uniform(-np.pi, np.pi)]))
        X_fc[:3, 3] = rng.normal(0, 40, 3) + np.array([0.0, 60.0, 80.0])
        Z = np.eye(4)
        Z[:3, :3] = so3_exp(np.array([0.0, 0.0, rng.uniform(-np.pi, np.pi)]))
        Z[:3, 3] = np.array([900.0, 0.0, 0.0]) + rng.normal(0, 30, 3)
        centre = Z[:3, :3] @ np.array([*centre_t, 0.0]) + Z[:3, 3]
        T_bc = _view_poses(rng, n_images, centre, distance, tilt_deg)
        F_true = T_bc @ invert_transforms(X_fc)[None]
        T_ct = invert_transforms(T_bc) @ Z[None]
        cam_pose, target_pose = X_fc, Z
    elif setup == "eye_to_hand":
        T_bc = look_at(np.array([900.0, 600.0, 1300.0]), np.array([900.0, 500.0, 0.0]), roll=rng.uniform(-1, 1))
        T_ft = np.eye(4)
        T_ft[:3, :3] = so3_exp(rng.normal(0, 0.3, 3))
        T_ft[:3, 3] = rng.normal(0, 30, 3) + np.array([0.0, 0.0, 80.0])
        # views of the board from the camera: camera-in-board poses on a cap above the board centre
        T_tc = _view_poses(rng, n_images, np.array([*centre_t, 0.0]), distance, tilt_deg)
        T_ct = invert_transforms(T_tc)
        F_true = T_bc[None] @ T_ct @ invert_transforms(T_ft)[None]
        cam_pose, target_pose = T_bc, T_ft
    else:
        raise ValueError(f"setup must be eye_in_hand or eye_to_hand, got {setup!r}")
    P = np.einsum("nij,pj->npi", T_ct[:, :3, :3], X_true) + T_ct[:, None, :3, 3]
    uv = camera.project(P.reshape(-1, 3)).pixels.reshape(n_images, len(X), 2)
    uv = uv + rng.normal(0, pixel_noise, uv.shape)
    w, h = camera.image_size or (1280, 1024)
    outside = (uv[..., 0] < 0) | (uv[..., 0] > w - 1) | (uv[..., 1] < 0) | (uv[..., 1] > h - 1)
    uv[outside] = np.nan
    F_meas = noisy_poses(F_true, rng, pose_noise_mm, pose_noise_deg)
    return HandEyeSimulation(setup, F_meas, F_true, uv, X, X_true, camera, cam_pose, target_pose, T_ct)
