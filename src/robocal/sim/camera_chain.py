"""A robot photographing a board with its own camera: joint configurations where the board is
fully in view, rendered images, a time-stamped joint log and a frames file (issue 15; the data of
camera self-calibration, :mod:`robocal.handeye.self_calibration`).

The camera sits on one end effector (``T_ee_camera``); the board is held by another end effector
(``T_carrier_board``) or fixed in the world (``carrier="world"``, ``T_base_board``). Joint
configurations are drawn uniformly in a box around ``q_center`` (``q_spread`` per joint) and kept
when every board point projects into the image with a margin, in front of the camera, and the board
faces the camera within ``max_tilt_deg``. The *true* robot (with joint offsets) decides what the
camera sees; the joint log reports the nominal readings (true minus offsets, plus reading noise).
"""

from __future__ import annotations

import numpy as np

from ..camera import Camera
from ..transforms import invert_transforms

__all__ = ["visible_configurations", "camera_board_poses", "capture_schedule", "simulate_corner_views"]


def camera_board_poses(model, q, camera_end_effector, T_ee_camera, carrier, T_carrier_board) -> np.ndarray:
    """(N, 4, 4) T_camera_board at joints q (N, n) [rad] of ``model`` [mm]."""
    cam = model.end_effector_index(camera_end_effector)
    A = model.kinematics_with(q, T_world_base=np.eye(4), end_effectors=[cam])[0][:, 0]
    if carrier == "world":
        B = np.tile(np.eye(4), (len(q), 1, 1))
    else:
        B = model.kinematics_with(q, T_world_base=np.eye(4), end_effectors=[model.end_effector_index(carrier)])[0][:, 0]
    return invert_transforms(A @ T_ee_camera) @ B @ T_carrier_board


def visible_configurations(model, camera: Camera, object_points, *, camera_end_effector: str, T_ee_camera,
                           carrier: str, T_carrier_board, n: int, rng, q_center, q_spread, front_z: int = -1,
                           max_tilt_deg: float = 55.0, margin_px: float = 15.0, batch: int = 4000,
                           max_batches: int = 100) -> np.ndarray:
    """(n, n_joints) configurations [rad] of ``model`` (the true robot) showing the whole board
    (module docstring); ``ValueError`` when fewer are found in ``max_batches`` batches."""
    X = np.asarray(object_points, dtype=float)
    w, h = camera.image_size
    lo, hi = model.limits[:, 0], model.limits[:, 1]
    out = []
    for _ in range(max_batches):
        q = np.clip(q_center + rng.uniform(-1.0, 1.0, (batch, len(q_center))) * q_spread, lo, hi)
        T = camera_board_poses(model, q, camera_end_effector, T_ee_camera, carrier, T_carrier_board)
        p = np.einsum("nij,pj->npi", T[:, :3, :3], X) + T[:, None, :3, 3]
        ok = np.all(p[..., 2] > 50.0, axis=1)
        # the printed side faces the camera: board normal (front_z * z) against the viewing ray
        ray = T[:, :3, 3] / np.linalg.norm(T[:, :3, 3], axis=1, keepdims=True)
        normal = front_z * T[:, :3, 2]
        ok &= np.einsum("ni,ni->n", -ray, normal) > np.cos(np.radians(max_tilt_deg))
        if ok.any():
            px = np.full(p[ok].shape[:2] + (2,), np.nan)
            px = camera.project(p[ok].reshape(-1, 3)).pixels.reshape(px.shape)
            inside = np.all(np.isfinite(px), axis=(1, 2)) & np.all(px[..., 0] > margin_px, axis=1) \
                & np.all(px[..., 1] > margin_px, axis=1) & np.all(px[..., 0] < w - 1 - margin_px, axis=1) \
                & np.all(px[..., 1] < h - 1 - margin_px, axis=1)
            out.extend(q[np.flatnonzero(ok)[inside]])
        if len(out) >= n:
            return np.array(out[:n])
    raise ValueError(f"only {len(out)} of {n} configurations show the whole board; widen q_spread or move the board")


def capture_schedule(n_images: int, rng, *, dwell_s: float = 1.0, move_s: float = 2.0, rate_hz: float = 20.0,
                     clock_offset_s: float = 0.012, jitter_s: float = 0.004):
    """The timing of a capture run: the robot moves to each pose, dwells, the camera fires in the
    middle of the dwell. Returns ``(image_times (N,) on the camera clock, log_times (M,) on the
    controller clock, log_pose (M,) the pose index the robot is at, -1 while moving)``."""
    period = dwell_s + move_s
    t_pose = 1.0 + np.arange(n_images) * period
    log_t = np.arange(0.0, t_pose[-1] + dwell_s + 1.0, 1.0 / rate_hz)
    k = np.floor((log_t - 1.0 + dwell_s / 2) / period).astype(int)
    at = (k >= 0) & (k < n_images) & (np.abs(log_t - t_pose[np.clip(k, 0, n_images - 1)]) <= dwell_s / 2)
    pose = np.where(at, k, -1)
    image_t = t_pose + clock_offset_s + rng.normal(0.0, jitter_s, n_images)
    return image_t, log_t, pose


def simulate_corner_views(true_model, camera: Camera, object_points, *, camera_end_effector: str, T_ee_camera,
                          boards: dict, n_per_carrier: int, rng, pixel_noise: float, front_z: int = -1,
                          max_batches: int = 300):
    """Corner observations without rendering: ``(q (N, n) [rad], carriers (N,), image_points (N, P, 2)
    [px])`` of ``n_per_carrier`` views per board (``boards``: {carrier: T_carrier_board}), the
    projections through the true robot plus Gaussian noise ``pixel_noise`` [px] per coordinate;
    joints drawn anywhere within the limits (:func:`visible_configurations`)."""
    X = np.asarray(object_points, dtype=float)
    q, on, uv = [], [], []
    centre, spread = np.zeros(true_model.n_joints), np.full(true_model.n_joints, np.pi)
    for c, T_cb in boards.items():
        qc = visible_configurations(true_model, camera, X, camera_end_effector=camera_end_effector,
                                    T_ee_camera=T_ee_camera, carrier=c, T_carrier_board=T_cb, n=n_per_carrier, rng=rng,
                                    q_center=centre, q_spread=spread, front_z=front_z, max_batches=max_batches)
        T = camera_board_poses(true_model, qc, camera_end_effector, T_ee_camera, c, T_cb)
        p = np.einsum("nij,pj->npi", T[:, :3, :3], X) + T[:, None, :3, 3]
        uv.append(camera.project(p.reshape(-1, 3)).pixels.reshape(len(qc), -1, 2))
        q.append(qc)
        on += [c] * len(qc)
    uv = np.concatenate(uv)
    return np.concatenate(q), np.array(on), uv + rng.normal(0.0, pixel_noise, uv.shape)
