"""Robot configurations for camera self-calibration: where the robot's camera sees a board fully
(or, on purpose, only partly) -- the geometry part of :mod:`.self_calibration` (issue 15).

Two set-ups:

* **board in a hand** (humanoid, e.g. ``nao_h25``): arm configurations are drawn uniformly within
  the joint limits (a margin kept), the head is aimed at the board centre (NAO: HeadYaw/HeadPitch,
  with the published yaw-dependent head-pitch anti-collision limits) plus a random aim error, and
  the view is classified;
* **board fixed in the world** (an industrial 6R arm with the camera on its flange): camera views
  of the board are drawn (:func:`robocal.sim.camera_cell` style), the flange pose follows, the joints
  come from the closed-form inverse kinematics of the nominal model refined by Newton steps on the
  true model.

A view is *full* when every board point projects inside the image with ``margin_px``, lies at a
depth in ``depth_mm`` and the printed face is turned to the camera within ``max_tilt_deg``; it is
*partial* when it faces the camera and 25-85 % of the points are inside the image.
"""

from __future__ import annotations

import math

import numpy as np

from ..camera import Camera
from ..transforms import compose, invert_transforms, so3_exp, transforms_from

__all__ = ["ViewLimits", "classify_views", "nao_head_pitch_limits", "aim_nao_head", "hand_configurations",
           "world_board_configurations"]

# "H25 - Joints V5 & V4", head anti-collision: HeadYaw [deg] -> HeadPitch min, max [deg]
_HEAD_YAW = np.array([-119.52, -87.49, -62.45, -51.74, -43.32, -27.85, 0.0, 27.85, 43.32, 51.74, 62.45, 87.49, 119.52])
_PITCH_MIN = np.array([-25.73, -18.91, -24.64, -27.50, -31.40, -38.50, -38.50, -38.50, -31.40, -27.50, -24.64, -18.91,
                       -25.73])
_PITCH_MAX = np.array([18.91, 11.46, 17.19, 18.91, 21.20, 24.18, 29.51, 24.18, 21.20, 18.91, 17.19, 11.46, 18.91])


class ViewLimits:
    """What counts as a usable view: ``margin_px`` from the image border, depth range ``depth_mm``
    (near, far) of every board point, ``max_tilt_deg`` between the board's printed-face normal and
    the direction to the camera."""

    def __init__(self, margin_px: float = 20.0, depth_mm=(100.0, 450.0), max_tilt_deg: float = 60.0):
        self.margin_px = float(margin_px)
        self.depth_mm = (float(depth_mm[0]), float(depth_mm[1]))
        self.max_tilt_deg = float(max_tilt_deg)


def classify_views(camera: Camera, object_points: np.ndarray, front_z: int, T_camera_board: np.ndarray,
                   limits: ViewLimits) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(full (N,) bool, partial (N,) bool, pixels (N, P, 2))`` of board poses ``T_camera_board``
    (N, 4, 4) [mm]; ``object_points`` (P, 3) [mm]; ``front_z`` the board's printed-face side."""
    T = np.asarray(T_camera_board, dtype=float).reshape(-1, 4, 4)
    X = np.asarray(object_points, dtype=float)
    p = np.einsum("nij,pj->npi", T[:, :3, :3], X) + T[:, None, :3, 3]
    depth = p[..., 2]
    safe = np.where(depth[..., None] > 1.0, p, np.array([0.0, 0.0, 1.0]))
    px = camera.project(safe.reshape(-1, 3)).pixels.reshape(len(T), len(X), 2)
    px[depth <= 1.0] = np.nan
    w, h = camera.image_size
    m = limits.margin_px
    inside = (np.isfinite(px[..., 0]) & (px[..., 0] > m) & (px[..., 1] > m) & (px[..., 0] < w - 1 - m)
              & (px[..., 1] < h - 1 - m) & (depth > limits.depth_mm[0]) & (depth < limits.depth_mm[1]))
    # printed-face normal (towards a viewer) vs the direction from the board centre to the camera
    normal = front_z * T[:, :3, 2]
    centre = p.mean(axis=1)
    to_camera = -centre / np.linalg.norm(centre, axis=1, keepdims=True)
    facing = np.einsum("ni,ni->n", normal, to_camera) > math.cos(math.radians(limits.max_tilt_deg))
    frac = inside.mean(axis=1)
    full = facing & inside.all(axis=1)
    partial = facing & (frac >= 0.25) & (frac <= 0.85) & (depth.min(axis=1) > limits.depth_mm[0])
    return full, partial, px


def nao_head_pitch_limits(yaw_rad) -> tuple[np.ndarray, np.ndarray]:
    """NAO's head-pitch range [rad] at head yaw ``yaw_rad`` (the anti-collision table, linear in between)."""
    yaw = np.degrees(np.asarray(yaw_rad, dtype=float))
    return np.radians(np.interp(yaw, _HEAD_YAW, _PITCH_MIN)), np.radians(np.interp(yaw, _HEAD_YAW, _PITCH_MAX))


def aim_nao_head(model, target_mm: np.ndarray, camera_ee: str = "camera_top", iterations: int = 6) -> np.ndarray:
    """(N, 2) HeadYaw, HeadPitch [rad] that point ``model``'s camera optical axis at ``target_mm``
    (N, 3) [mm, robot base frame]: a fixed-point iteration on the camera's offset from the neck
    (works for any head whose camera hangs off a yaw-then-pitch neck)."""
    target = np.atleast_2d(np.asarray(target_mm, dtype=float))
    n = len(target)
    j_yaw = model.controller_joints.index("HeadYaw")
    j_pitch = model.controller_joints.index("HeadPitch")
    q = np.zeros((n, model.n_joints))
    for _ in range(iterations):
        T = model.fk(q, camera_ee)
        # the needed change of the optical axis direction, split into yaw and pitch
        d = target - T[:, :3, 3]
        d /= np.linalg.norm(d, axis=1, keepdims=True)
        z = T[:, :3, 2]
        dyaw = np.arctan2(d[:, 1], d[:, 0]) - np.arctan2(z[:, 1], z[:, 0])
        dpitch = -(np.arcsin(np.clip(d[:, 2], -1, 1)) - np.arcsin(np.clip(z[:, 2], -1, 1)))
        q[:, j_yaw] += (dyaw + np.pi) % (2 * np.pi) - np.pi
        q[:, j_pitch] += dpitch
    return q[:, [j_yaw, j_pitch]]


def _rest_configuration(model) -> np.ndarray:
    """(n,) a configuration with the arms hanging down beside the body (NAO), else the middle of
    the limits."""
    lo, hi = model.limits[:, 0], model.limits[:, 1]
    q = np.clip(np.where(np.isfinite(lo + hi), 0.5 * (lo + hi), 0.0), lo, hi)
    rest = {"LShoulderPitch": 80.0, "LShoulderRoll": 8.0, "LElbowYaw": -70.0, "LElbowRoll": -20.0, "LWristYaw": 0.0,
            "RShoulderPitch": 80.0, "RShoulderRoll": -8.0, "RElbowYaw": 70.0, "RElbowRoll": 20.0, "RWristYaw": 0.0,
            "HeadYaw": 0.0, "HeadPitch": 0.0}
    for name, deg in rest.items():
        if name in model.controller_joints:
            k = model.controller_joints.index(name)
            q[k] = np.clip(math.radians(deg), lo[k], hi[k])
    return q


def _chain_joints(model, end_effector: str) -> np.ndarray:
    """Controller joint indices that move ``end_effector``."""
    e = model.end_effector_index(end_effector)
    moving_anc = model._ee_ancestors[e][model.moving]  # noqa: SLF001 (the model's own ancestry table)
    return np.flatnonzero(np.any(model.coupling[moving_anc] != 0.0, axis=0))


def hand_configurations(true_model, camera: Camera, chain: str, object_points: np.ndarray, front_z: int,
                        T_ee_board: np.ndarray, n_full: int, n_partial: int, rng, *, camera_ee: str = "camera_top",
                        T_cee_camera=None, limits: ViewLimits | None = None, aim_sigma_deg: float = 4.0,
                        max_batches: int = 60, batch: int = 4000):
    """``(q_full (n_full, n), q_partial (n_partial, n))`` controller joints [rad] of ``true_model`` at
    which the board held by end effector ``chain`` is fully / partly seen by the camera.

    object_points (P, 3) [mm] and front_z: the board (:class:`robocal.io.boards.Board`); T_ee_board
    (4, 4) [mm]: the board in the ``chain`` end-effector frame; T_cee_camera (4, 4): the true camera
    in the camera end-effector frame (default identity). Arm joints are uniform within the limits
    (5 % margin); the other joints rest; the head looks at the board centre with a Gaussian aim
    error ``aim_sigma_deg``. ``RuntimeError`` if too few views are found.
    """
    limits = limits or ViewLimits()
    T_cc = np.eye(4) if T_cee_camera is None else np.asarray(T_cee_camera, dtype=float)
    arm = _chain_joints(true_model, chain)
    head = _chain_joints(true_model, camera_ee)
    arm = np.setdiff1d(arm, head)
    lo, hi = true_model.limits[:, 0], true_model.limits[:, 1]
    span = hi - lo
    rest = _rest_configuration(true_model)
    nao_head = {"HeadYaw", "HeadPitch"} <= set(true_model.controller_joints)
    X = np.asarray(object_points, dtype=float)
    centre_ee = T_ee_board[:3, :3] @ X.mean(axis=0) + T_ee_board[:3, 3]
    full, part = [], []
    for _ in range(max_batches):
        q = np.tile(rest, (batch, 1))
        q[:, arm] = rng.uniform(lo[arm] + 0.05 * span[arm], hi[arm] - 0.05 * span[arm], size=(batch, len(arm)))
        T_ee = true_model.fk(q, chain)
        centre = (T_ee[:, :3, :3] @ centre_ee) + T_ee[:, :3, 3]
        ok = centre[:, 0] > 80.0  # the board in front of the face, not in the torso
        q, T_ee = q[ok], T_ee[ok]
        if nao_head:
            hq = aim_nao_head(true_model, centre[ok], camera_ee) + rng.normal(0.0, math.radians(aim_sigma_deg),
                                                                             (len(q), 2))
            jy, jp = true_model.controller_joints.index("HeadYaw"), true_model.controller_joints.index("HeadPitch")
            hq[:, 0] = np.clip(hq[:, 0], lo[jy], hi[jy])
            plo, phi = nao_head_pitch_limits(hq[:, 0])
            hq[:, 1] = np.clip(hq[:, 1], np.maximum(plo, lo[jp]), np.minimum(phi, hi[jp]))
            q[:, jy], q[:, jp] = hq[:, 0], hq[:, 1]
        else:
            q[:, head] = rng.uniform(lo[head], hi[head], size=(len(q), len(head)))
        T_cam = compose(true_model.fk(q, camera_ee), T_cc)
        T_camera_board = compose(invert_transforms(T_cam), T_ee, T_ee_board)
        is_full, is_part, _ = classify_views(camera, X, front_z, T_camera_board, limits)
        full.extend(q[is_full])
        part.extend(q[is_part & ~is_full])
        if len(full) >= n_full and len(part) >= n_partial:
            break
    if len(full) < n_full or len(part) < n_partial:
        raise RuntimeError(f"{true_model.name}: only {len(full)} full and {len(part)} partial views of the board in "
                           f"{chain!r} found (need {n_full} and {n_partial}); check the board size and mount")
    full = np.array(full)[rng.permutation(len(full))[:n_full]]
    part = np.array(part)[rng.permutation(len(part))[:n_partial]] if n_partial else np.empty((0, true_model.n_joints))
    return full, part


def _look_at(eye: np.ndarray, centre: np.ndarray, roll: float) -> np.ndarray:
    z = centre - eye
    z = z / np.linalg.norm(z)
    helper = np.array([0.0, 1.0, 0.0]) if abs(z[1]) < 0.9 else np.array([1.0, 0.0, 0.0])
    x = np.cross(helper, z)
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    return transforms_from(np.stack([x, y, z], axis=1) @ so3_exp(np.array([0.0, 0.0, roll])), eye)


def _newton_joints(model, q0: np.ndarray, T_target: np.ndarray, end_effector, iterations: int = 8) -> np.ndarray:
    """Refine joints (N, n) so that ``model``'s ``end_effector`` reaches ``T_target`` (N, 4, 4):
    Gauss-Newton steps with the geometric Jacobian (6 x 6 for a 6R arm)."""
    from ..transforms import so3_log

    q = np.array(q0, dtype=float)
    for _ in range(iterations):
        T = model.fk(q, end_effector)
        dp = T_target[:, :3, 3] - T[:, :3, 3]
        dw = np.array([so3_log(Rt @ R.T) for Rt, R in zip(T_target[:, :3, :3], T[:, :3, :3])])
        J = model.jacobian(q, end_effector)
        err = np.concatenate([dp, dw], axis=1)
        q = q + np.stack([np.linalg.lstsq(J[k], err[k], rcond=None)[0] for k in range(len(q))])
    return q


def world_board_configurations(nominal, true_model, camera: Camera, object_points: np.ndarray, front_z: int,
                               T_world_board: np.ndarray, T_flange_camera: np.ndarray, n_full: int, n_partial: int,
                               rng, *, camera_ee: str = "flange", limits: ViewLimits | None = None,
                               max_tilt_deg: float = 40.0):
    """``(q_full, q_partial)`` [rad] of a 6R arm (``true_model``) whose flange camera
    (``T_flange_camera``, true) sees the board fixed at ``T_world_board`` [mm] fully / partly.

    Views are drawn around the board normal (tilt 5..``max_tilt_deg``, distance so the board spans
    45-75 % of the image), the flange pose follows, the joints are the closed-form IK of ``nominal``
    refined by Newton steps on ``true_model``; unreachable or misclassified views are redrawn."""
    from .camera_cell import _ik_branches

    limits = limits or ViewLimits(margin_px=20.0, depth_mm=(100.0, 5000.0), max_tilt_deg=60.0)
    X = np.asarray(object_points, dtype=float)
    centre = X.mean(axis=0)
    extent = float(np.max(np.linalg.norm(X - centre, axis=1)))
    w, h = camera.image_size
    base_distance = 2.0 * extent * min(camera.fx, camera.fy) / (0.6 * min(w, h))
    T_cam_flange = invert_transforms(T_flange_camera)
    full, part = [], []
    for _ in range(40):
        n = 4 * (n_full + n_partial) + 8
        views = []
        for k in range(n):
            tilt = math.radians(rng.uniform(5.0, max_tilt_deg))
            az = rng.uniform(0, 2 * np.pi)
            direction = np.array([math.sin(tilt) * math.cos(az), math.sin(tilt) * math.sin(az), front_z * math.cos(tilt)])
            aim = centre + rng.normal(0.0, 0.08 * extent, 3) * np.array([1, 1, 0])
            if k % 3 == 2:  # aim off the board: some views show it only partly
                aim = centre + rng.uniform(0.9, 1.5) * extent * np.array([math.cos(az + 1.0), math.sin(az + 1.0), 0.0])
            eye = centre + base_distance * rng.uniform(0.85, 1.3) * direction
            views.append(invert_transforms(_look_at(eye, aim, rng.uniform(-np.pi, np.pi))))
        T_camera_board = np.array(views)
        T_world_flange = compose(T_world_board, invert_transforms(T_camera_board), T_cam_flange)
        T_base_flange = compose(invert_transforms(nominal.T_world_base), T_world_flange)
        q0, ok = _ik_branches(nominal, T_base_flange)
        if not ok.any():
            continue
        q = _newton_joints(true_model, q0[ok], T_world_flange[ok], camera_ee)
        q = q[true_model.within_limits(q)]
        T_cam = compose(true_model.fk(q, camera_ee), T_flange_camera)
        is_full, is_part, _ = classify_views(camera, X, front_z, compose(invert_transforms(T_cam), T_world_board),
                                             limits)
        full.extend(q[is_full])
        part.extend(q[is_part & ~is_full])
        if len(full) >= n_full and len(part) >= n_partial:
            break
    if len(full) < n_full or len(part) < n_partial:
        raise RuntimeError(f"{true_model.name}: only {len(full)} full and {len(part)} partial reachable views of the "
                           f"board found (need {n_full} and {n_partial}); check the board placement")
    return np.array(full[:n_full]), (np.array(part[:n_partial]) if n_partial else np.empty((0, true_model.n_joints)))
