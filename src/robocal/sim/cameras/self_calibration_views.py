"""Robot configurations for camera self-calibration: where a camera on one end effector sees a
board held by another end effector, or fixed in the world, fully (or, on purpose, only partly) --
the one view simulator behind :mod:`.self_calibration`, the pipeline's tests and
benchmarks/bench_self_calibration.py (issue 15).

Three ways to draw configurations, one test of a view (:func:`classify_views`):

* **any tree, joints in a box** (:func:`visible_configurations`, :func:`simulate_corner_views`):
  joints uniform in a box around ``q_center`` (``q_spread`` per joint, clipped to the limits), full
  views kept; a NAO-style head (HeadYaw/HeadPitch) is aimed at the board instead of drawn;
* **board in a hand** (humanoid, e.g. ``nao_h25``; :func:`hand_configurations`): arm configurations
  are drawn uniformly within the joint limits (a margin kept), the head is aimed at the board centre
  (NAO: HeadYaw/HeadPitch, with the published yaw-dependent head-pitch anti-collision limits) plus a
  random aim error, and full and partial views are both collected;
* **board fixed in the world** (an industrial 6R arm with the camera on its flange;
  :func:`world_board_configurations`): camera views of the board are drawn
  (:func:`robocal.sim.cameras.camera_cell` style), the flange pose follows, the joints come from the
  closed-form inverse kinematics of the nominal model refined on the true model
  (:func:`robocal.kinematics.ik.ik_numeric`).

A view is *full* when every board point projects inside the image with ``margin_px``, lies at a
depth in ``depth_mm`` and the printed face is turned to the camera within ``max_tilt_deg``; given
the board's pitch, the printed pattern's outline must be inside the image too (a detector needs the
outer squares). It is *partial* when it faces the camera and 25-85 % of the points are inside the
image.
"""

from __future__ import annotations

import math

import numpy as np

from ...camera import Camera
from ...kinematics.ik import ik_numeric
from ...transforms import compose, invert_transforms

__all__ = ["ViewLimits", "classify_views", "camera_board_poses", "visible_configurations", "simulate_corner_views",
           "nao_head_pitch_limits", "aim_nao_head", "hand_configurations", "world_board_configurations"]

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


def board_outline(object_points: np.ndarray, pitch_mm: float) -> np.ndarray:
    """(4, 3) [mm] the corners of the printed pattern around the object points: their bounding box
    grown by one pitch (a checkerboard's or ChArUco board's outer squares; a dot grid's dots)."""
    X = np.asarray(object_points, dtype=float)
    (x0, y0), (x1, y1) = X[:, :2].min(axis=0) - pitch_mm, X[:, :2].max(axis=0) + pitch_mm
    return np.array([[x0, y0, 0.0], [x1, y0, 0.0], [x1, y1, 0.0], [x0, y1, 0.0]])


def classify_views(camera: Camera, object_points: np.ndarray, front_z: int, T_camera_board: np.ndarray,
                   limits: ViewLimits, pitch_mm: float | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(full (N,) bool, partial (N,) bool, pixels (N, P, 2))`` of board poses ``T_camera_board``
    (N, 4, 4) [mm]; ``object_points`` (P, 3) [mm]; ``front_z`` the board's printed-face side.
    With ``pitch_mm`` a full view also needs the pattern's outline (:func:`board_outline`) inside
    the image (a detector needs the outer squares, not just the inner corners)."""
    T = np.asarray(T_camera_board, dtype=float).reshape(-1, 4, 4)
    X = np.asarray(object_points, dtype=float)
    if pitch_mm is not None:
        full, _, _ = classify_views(camera, np.vstack([X, board_outline(X, pitch_mm)]), front_z, T, limits)
        _, partial, px = classify_views(camera, X, front_z, T, limits)
        return full, partial & ~full, px
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


def _has_nao_head(model) -> bool:
    return {"HeadYaw", "HeadPitch"} <= set(model.controller_joints)


def _aim_head(model, q: np.ndarray, target_mm: np.ndarray, camera_ee: str, rng, aim_sigma_deg: float) -> None:
    """Set the HeadYaw/HeadPitch columns of ``q`` (N, n) [rad] in place to look at ``target_mm``
    (N, 3) [mm] (:func:`aim_nao_head`) plus a Gaussian aim error ``aim_sigma_deg``, within the joint
    limits and the yaw-dependent pitch limits (:func:`nao_head_pitch_limits`)."""
    lo, hi = model.limits[:, 0], model.limits[:, 1]
    hq = aim_nao_head(model, target_mm, camera_ee) + rng.normal(0.0, math.radians(aim_sigma_deg), (len(q), 2))
    jy, jp = model.controller_joints.index("HeadYaw"), model.controller_joints.index("HeadPitch")
    hq[:, 0] = np.clip(hq[:, 0], lo[jy], hi[jy])
    plo, phi = nao_head_pitch_limits(hq[:, 0])
    hq[:, 1] = np.clip(hq[:, 1], np.maximum(plo, lo[jp]), np.minimum(phi, hi[jp]))
    q[:, jy], q[:, jp] = hq[:, 0], hq[:, 1]


def camera_board_poses(model, q, camera_end_effector: str, T_ee_camera, carrier: str, T_carrier_board) -> np.ndarray:
    """(N, 4, 4) T_camera_board [mm] at joints q (N, n) [rad] of ``model``: the camera at
    ``T_ee_camera`` in ``camera_end_effector``'s frame, the board at ``T_carrier_board`` in the
    ``carrier`` end effector's frame, or in the world frame when ``carrier == "world"``."""
    q = np.atleast_2d(np.asarray(q, dtype=float))
    T_world_camera = compose(model.fk(q, camera_end_effector), T_ee_camera)
    if carrier == "world":
        T_world_board = np.broadcast_to(np.asarray(T_carrier_board, dtype=float), (len(q), 4, 4))
    else:
        T_world_board = compose(model.fk(q, carrier), T_carrier_board)
    return compose(invert_transforms(T_world_camera), T_world_board)


#: what :func:`visible_configurations` accepts by default: 15 px from the border, every point more
#: than 50 mm in front of the camera, the printed face within 55 deg of the viewing direction
BOX_VIEW_LIMITS = dict(margin_px=15.0, depth_mm=(50.0, math.inf), max_tilt_deg=55.0)


def visible_configurations(model, camera: Camera, object_points, *, camera_end_effector: str, T_ee_camera,
                           carrier: str, T_carrier_board, n: int, rng, q_center, q_spread, front_z: int = -1,
                           limits: ViewLimits | None = None, pitch_mm: float | None = None,
                           aim_sigma_deg: float = 4.0, batch: int = 4000, max_batches: int = 100) -> np.ndarray:
    """(n, n_joints) configurations [rad] of ``model`` (the true robot) showing the whole board.

    Joints are uniform in ``q_center +- q_spread`` (clipped to the limits); on a model with a NAO
    head (HeadYaw/HeadPitch) and a board in a hand, the head is aimed at the board centre
    (:func:`aim_nao_head`, aim error ``aim_sigma_deg``). A configuration is kept when
    :func:`classify_views` calls its view full (``limits``, default :data:`BOX_VIEW_LIMITS`; with
    ``pitch_mm`` the board's outline in the image too). ``ValueError`` when fewer than ``n`` are
    found in ``max_batches`` batches of ``batch``."""
    limits = limits or ViewLimits(**BOX_VIEW_LIMITS)
    X = np.asarray(object_points, dtype=float)
    lo, hi = model.limits[:, 0], model.limits[:, 1]
    aim = carrier != "world" and _has_nao_head(model)
    centre_carrier = np.asarray(T_carrier_board, dtype=float)[:3] @ np.r_[X.mean(axis=0), 1.0]
    out = []
    for _ in range(max_batches):
        q = np.clip(q_center + rng.uniform(-1.0, 1.0, (batch, len(q_center))) * q_spread, lo, hi)
        if aim:
            T_carrier = model.fk(q, carrier)
            _aim_head(model, q, T_carrier[:, :3, :3] @ centre_carrier + T_carrier[:, :3, 3], camera_end_effector,
                      rng, aim_sigma_deg)
        T = camera_board_poses(model, q, camera_end_effector, T_ee_camera, carrier, T_carrier_board)
        full, _, _ = classify_views(camera, X, front_z, T, limits, pitch_mm)
        out.extend(q[full])
        if len(out) >= n:
            return np.array(out[:n])
    raise ValueError(f"only {len(out)} of {n} configurations show the whole board; widen q_spread or move the board")


def simulate_corner_views(true_model, camera: Camera, object_points, *, camera_end_effector: str, T_ee_camera,
                          boards: dict, n_per_carrier: int, rng, pixel_noise: float, front_z: int = -1,
                          pitch_mm: float | None = None, max_batches: int = 300):
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
                                    q_center=centre, q_spread=spread, front_z=front_z, pitch_mm=pitch_mm,
                                    max_batches=max_batches)
        T = camera_board_poses(true_model, qc, camera_end_effector, T_ee_camera, c, T_cb)
        p = np.einsum("nij,pj->npi", T[:, :3, :3], X) + T[:, None, :3, 3]
        uv.append(camera.project(p.reshape(-1, 3)).pixels.reshape(len(qc), -1, 2))
        q.append(qc)
        on += [c] * len(qc)
    uv = np.concatenate(uv)
    return np.concatenate(q), np.array(on), uv + rng.normal(0.0, pixel_noise, uv.shape)


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
                        pitch_mm: float | None = None, max_batches: int = 60, batch: int = 4000):
    """``(q_full (n_full, n), q_partial (n_partial, n))`` controller joints [rad] of ``true_model`` at
    which the board held by end effector ``chain`` is fully / partly seen by the camera.

    object_points (P, 3) [mm] and front_z: the board (:class:`robocal.io.boards.Board`); T_ee_board
    (4, 4) [mm]: the board in the ``chain`` end-effector frame; T_cee_camera (4, 4): the true camera
    in the camera end-effector frame (default identity). Arm joints are uniform within the limits
    (5 % margin); the other joints rest; the head looks at the board centre with a Gaussian aim
    error ``aim_sigma_deg``; pitch_mm: the board's pitch, to require its outline in the image too
    (:func:`classify_views`). ``RuntimeError`` if too few views are found.
    """
    limits = limits or ViewLimits()
    T_cc = np.eye(4) if T_cee_camera is None else np.asarray(T_cee_camera, dtype=float)
    arm = _chain_joints(true_model, chain)
    head = _chain_joints(true_model, camera_ee)
    arm = np.setdiff1d(arm, head)
    lo, hi = true_model.limits[:, 0], true_model.limits[:, 1]
    span = hi - lo
    rest = _rest_configuration(true_model)
    nao_head = _has_nao_head(true_model)
    X = np.asarray(object_points, dtype=float)
    centre_ee = T_ee_board[:3, :3] @ X.mean(axis=0) + T_ee_board[:3, 3]
    full, part = [], []
    for _ in range(max_batches):
        q = np.tile(rest, (batch, 1))
        q[:, arm] = rng.uniform(lo[arm] + 0.05 * span[arm], hi[arm] - 0.05 * span[arm], size=(batch, len(arm)))
        T_ee = true_model.fk(q, chain)
        centre = (T_ee[:, :3, :3] @ centre_ee) + T_ee[:, :3, 3]
        ok = centre[:, 0] > 80.0  # the board in front of the face, not in the torso
        q = q[ok]
        if nao_head:
            _aim_head(true_model, q, centre[ok], camera_ee, rng, aim_sigma_deg)
        else:
            q[:, head] = rng.uniform(lo[head], hi[head], size=(len(q), len(head)))
        T_camera_board = camera_board_poses(true_model, q, camera_ee, T_cc, chain, T_ee_board)
        is_full, is_part, _ = classify_views(camera, X, front_z, T_camera_board, limits, pitch_mm)
        full.extend(q[is_full])
        part.extend(q[is_part & ~is_full])
        if len(full) >= n_full and len(part) >= n_partial:
            break
    return _pick(full, part, n_full, n_partial, rng, true_model,
                 f"views of the board in {chain!r}; check the board size and mount")


def _pick(full: list, part: list, n_full: int, n_partial: int, rng, model, what: str):
    """``n_full`` and ``n_partial`` configurations drawn at random from the found ones, as arrays;
    ``RuntimeError`` naming ``what`` when too few were found."""
    if len(full) < n_full or len(part) < n_partial:
        raise RuntimeError(f"{model.name}: only {len(full)} full and {len(part)} partial {what} "
                           f"(need {n_full} and {n_partial})")
    full = np.array(full)[rng.permutation(len(full))[:n_full]]
    part = np.array(part)[rng.permutation(len(part))[:n_partial]] if n_partial else np.empty((0, model.n_joints))
    return full, part


def world_board_configurations(nominal, true_model, camera: Camera, object_points: np.ndarray, front_z: int,
                               T_world_board: np.ndarray, T_flange_camera: np.ndarray, n_full: int, n_partial: int,
                               rng, *, camera_ee: str = "flange", limits: ViewLimits | None = None,
                               max_tilt_deg: float = 40.0, pitch_mm: float | None = None):
    """``(q_full, q_partial)`` [rad] of a 6R arm (``true_model``) whose flange camera
    (``T_flange_camera``, true) sees the board fixed at ``T_world_board`` [mm] fully / partly.

    Views are drawn around the board normal (tilt 5..``max_tilt_deg``, distance so the board spans
    45-75 % of the image), the flange pose follows, the joints are the closed-form IK of ``nominal``
    refined on ``true_model`` (:func:`robocal.kinematics.ik.ik_numeric`); unreachable or misclassified views
    are redrawn."""
    from .camera_cell import _ik_branches, _look_at

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
        q = ik_numeric(true_model, T_world_flange[ok], q0[ok], end_effector=camera_ee, respect_limits=False).q
        q = q[true_model.within_limits(q)]
        T_camera_board = camera_board_poses(true_model, q, camera_ee, T_flange_camera, "world", T_world_board)
        is_full, is_part, _ = classify_views(camera, X, front_z, T_camera_board, limits, pitch_mm)
        full.extend(q[is_full])
        part.extend(q[is_part & ~is_full])
        if len(full) >= n_full and len(part) >= n_partial:
            break
    return _pick(full, part, n_full, n_partial, rng, true_model, "reachable views of the board; check its placement")
