"""Simulated camera self-calibration runs: a robot photographs a board with its own camera
(issue 15; docs/self-calibration-simulator.md).

Two set-ups, one output:

* **humanoid** (``nao_h25``): the head camera ``camera_top`` sees a board held in a hand
  (``chains=("left_hand", "right_hand")``); the board mounts on the hands are part of the truth;
* **industrial** (a 6R arm): a camera on the flange (``camera_end_effector="flange"``) sees a
  board fixed in the world (``chains=("world",)``).

The hidden truth: joint zero offsets (uniform within +-``joint_offsets_deg`` on every joint that
moves the camera or a board, or a dict name -> deg), optionally link-length errors
(``length_sigma_mm``), the camera mount (a small error on the nominal ``T_ee_camera``) and the
board transforms. Effects a calibration model does not contain: joint-reading noise on every log
row (``joint_noise_deg``), a camera/robot clock offset and capture jitter, and the renderer's blur,
lighting and sensor noise (:class:`~robocal.sim.cameras.camera_render.RenderSettings`).

Timeline (robot clock): the robot moves from pose to pose (``move_s`` + 0.5 s per 30 deg of
the largest joint travel, a smooth profile), dwells ``dwell_s``, and the camera captures at a
random moment of the dwell's middle half. The joint log streams at ``log_rate_hz`` throughout
(moves included). Frame time stamps are on the camera clock: ``t_camera = t_robot +
clock_offset_s + N(0, jitter_s)``.

A fraction ``partial_fraction`` of extra images (per chain) shows the board only partly (25-85 %
of the corners inside the image): a pipeline must reject them.

Files (:func:`write_self_calibration_files`): ``images/img_000.png``...; ``joint_log.csv``
(``robocal-joint-log/1``); ``frames.csv`` (``robocal-frames/1``); ``camera.json``; ``truth.json``.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ...camera import Camera
from ...io.atomic import atomic_write_text
from ...io.boards import Board, board_image, parse_board
from ...io.camera_files import write_camera_json
from ...io.images import write_png
from ...io.joint_log_files import write_frames, write_joint_log
from ...robots import load_robot
from ...transforms import compose, invert_transforms, so3_exp, transforms_from
from .camera_cell import default_camera
from .camera_render import BoardRenderer, RenderSettings
from ..robot import parameter_kinds
from .self_calibration_views import ViewLimits, hand_configurations, world_board_configurations

__all__ = ["SelfCalibrationRun", "simulate_self_calibration", "capture_schedule", "write_self_calibration_files", "nao_top_camera",
           "nominal_hand_board_mount", "board_surface", "DEFAULT_BOARD", "DEFAULT_WORLD_BOARD", "OUTPUT_NAMES", "TRUTH_FORMAT"]

#: a checkerboard a NAO hand can hold: 7 x 4 inner corners (8 x 5 squares, COLS + ROWS odd so its
#: orientation is unique), 12 mm squares: 96 x 60 mm pattern
DEFAULT_BOARD = "checkerboard:7x4:12mm"
#: the industrial variant's board, fixed in the cell
DEFAULT_WORLD_BOARD = "checkerboard:9x6:25mm"
OUTPUT_NAMES = ["images", "joint_log.csv", "frames.csv", "camera.json", "truth.json"]
TRUTH_FORMAT = "robocal-self-calibration-truth/1"


def nao_top_camera() -> Camera:
    """NAO V5's top camera (MT9M114, 1280x960, 60.9 deg horizontal / 47.6 deg vertical field of
    view, Aldebaran "Video camera" page): fx = 640 / tan(30.45 deg) = 1088.3 px, fy = 480 /
    tan(23.8 deg) = 1088.6 px; the principal point a few pixels off centre and a mild barrel
    distortion are assumptions (no published intrinsics)."""
    fx = 640.0 / math.tan(math.radians(60.9 / 2))
    fy = 480.0 / math.tan(math.radians(47.6 / 2))
    return Camera(fx, fy, 643.2, 476.9, (-0.045, 0.06, 2e-4, -1.5e-4, 0.0), "brown", (1280, 960))


def nominal_hand_board_mount(board: Board) -> np.ndarray:
    """(4, 4) [mm] the nominal board frame in a NAO hand frame: a plate under the hand, the board's
    axes along the hand's (board x = hand x, board y = hand y, board z = hand z; a checkerboard's
    z points into the print, so the printed face looks out of the hand's -z side, the palm at the
    zero pose), its centre 15 mm ahead of and 25 mm below the hand frame's origin (a design choice
    of this simulator)."""
    R = np.eye(3)
    centre = board.object_points().mean(axis=0)
    return transforms_from(R, np.array([15.0, 0.0, -25.0]) - R @ centre)


@dataclass(frozen=True, eq=False)
class SelfCalibrationRun:
    """A simulated run (module docstring); all lengths mm, angles rad, times s.

    robot / true_robot: nominal and true models; camera: the true camera; camera_end_effector;
    chains; board; T_ee_camera_nominal / T_ee_camera (4, 4): the camera in its end-effector frame;
    T_ee_board_nominal / T_ee_board: {chain: (4, 4)} the board in the chain's end-effector frame
    (``"world"``: in the world frame); joint_offsets_rad: {joint: true - nominal zero offset}
    [rad] (``truth.json`` has them in degrees, ``joint_offsets_deg``); parameter_errors:
    {parameter: true - nominal} [mm or rad]. Per image (N): ``images`` names, ``chain_of_image``,
    ``fully_visible``, ``q_true`` (N, n) controller joints at capture (noise-free readings),
    ``T_camera_board`` (N, 4, 4), ``image_points_true`` (N, P, 2) [px] (NaN behind the camera),
    ``image_points`` (N, P, 2): those plus Gaussian ``pixel_noise`` (an image-free stand-in for a
    detector), ``capture_times`` (robot clock) and ``frame_times`` (camera clock). The log:
    ``log_times`` (M,), ``log_joints`` (M, n) (with reading noise), ``log_pose`` (M,) the image
    index whose move or dwell a row belongs to.
    """

    robot: object
    true_robot: object
    camera: Camera
    camera_end_effector: str
    chains: tuple
    board: Board
    T_ee_camera_nominal: np.ndarray
    T_ee_camera: np.ndarray
    T_ee_board_nominal: dict
    T_ee_board: dict
    joint_offsets_rad: dict
    parameter_errors: dict
    images: tuple
    chain_of_image: tuple
    fully_visible: np.ndarray
    q_true: np.ndarray
    T_camera_board: np.ndarray
    image_points_true: np.ndarray
    image_points: np.ndarray
    capture_times: np.ndarray
    frame_times: np.ndarray
    log_times: np.ndarray
    log_joints: np.ndarray
    log_pose: np.ndarray
    settings: dict = field(default_factory=dict)

    @property
    def n_images(self) -> int:
        return len(self.images)


def _joints_moving(model, end_effectors) -> list:
    """Link indices of the moving joints that move any of ``end_effectors``."""
    anc = np.zeros(len(model.links), dtype=bool)
    for e in end_effectors:
        anc |= model._ee_ancestors[model.end_effector_index(e)]  # noqa: SLF001
    return [k for k in np.flatnonzero(anc) if model.links[k].moves]


def _true_model(nominal, moved_links, offsets, length_sigma_mm, rng):
    """(true model, {joint: offset rad}, {parameter: error}) with joint offsets on ``moved_links``."""
    values = nominal.params.values.copy()
    kinds = parameter_kinds(nominal)
    errors, joint_offsets = {}, {}
    for k in moved_links:
        link = nominal.links[k]
        i = nominal.params.index(f"theta{k + 1}") if link.joint_type == "revolute" else None
        if i is None:
            continue
        if isinstance(offsets, dict):
            delta = math.radians(float(offsets.get(link.name, 0.0)))
        else:
            delta = math.radians(rng.uniform(-float(offsets), float(offsets)))
        values[i] += delta
        joint_offsets[link.name] = delta
    if length_sigma_mm > 0:
        on_chain = np.isin(nominal.params.link_of, moved_links) & nominal.params.free & (kinds == "length")
        values[on_chain] += rng.normal(0.0, length_sigma_mm, int(on_chain.sum()))
    true = nominal.with_params(values)
    d = values - nominal.params.values
    errors = {n: float(v) for n, v in zip(nominal.params.names, d) if v != 0.0}
    return true, joint_offsets, errors


def _reach_mm(model, end_effector) -> float:
    """The largest distance [mm] of ``end_effector`` from the base origin over 2000 seeded random
    configurations (the scale of the cell)."""
    q = np.random.default_rng(0).uniform(model.limits[:, 0], model.limits[:, 1], (2000, model.n_joints))
    q = np.where(np.isfinite(q), q, 0.0)
    p = compose(invert_transforms(model.T_world_base), model.fk(q, end_effector))[:, :3, 3]
    return float(np.max(np.linalg.norm(p, axis=1)))


def _small_transform(rng, mm: float, deg: float) -> np.ndarray:
    return transforms_from(so3_exp(rng.normal(0.0, math.radians(deg), 3)), rng.normal(0.0, mm, 3))


def _timeline(q_images: np.ndarray, q_start: np.ndarray, rng, *, move_s, dwell_s, log_rate_hz, t0):
    """Capture times (N,) and the joint stream (times (M,), joints (M, n), pose (M,)) of visiting
    ``q_images`` in order from ``q_start`` (module docstring)."""
    path = np.vstack([q_start, q_images])
    t = t0
    segments = []  # (t_start, t_arrive, t_leave, q_from, q_to, pose index)
    capture = []
    for k in range(len(q_images)):
        travel = float(np.max(np.abs(path[k + 1] - path[k])))
        duration = move_s + 0.5 * travel / math.radians(30.0)
        arrive = t + duration
        leave = arrive + dwell_s
        capture.append(arrive + dwell_s * rng.uniform(0.25, 0.75))
        segments.append((t, arrive, leave, path[k], path[k + 1], k))
        t = leave
    times = np.arange(t0, t, 1.0 / log_rate_hz)
    joints = np.empty((len(times), path.shape[1]))
    pose = np.empty(len(times), dtype=int)
    for (ts, ta, tl, qa, qb, k) in segments:
        sel = (times >= ts) & (times < tl)
        s = np.clip((times[sel] - ts) / (ta - ts), 0.0, 1.0)
        s = 0.5 - 0.5 * np.cos(np.pi * s)  # smooth start and stop
        joints[sel] = qa + s[:, None] * (qb - qa)
        pose[sel] = k
    return np.array(capture), times, joints, pose


def capture_schedule(n_images: int, rng, *, dwell_s: float = 1.0, move_s: float = 2.0, rate_hz: float = 20.0,
                     clock_offset_s: float = 0.012, jitter_s: float = 0.004):
    """The timing of a simple capture run (fixed move and dwell times, for tests and benchmarks that
    draw their own views; :func:`simulate_self_calibration` has its own travel-dependent timeline):
    the robot moves to each pose, dwells, the camera fires in the middle of the dwell. Returns
    ``(image_times (N,) on the camera clock, log_times (M,) on the controller clock, log_pose (M,)
    the pose index the robot is at, -1 while moving)`` [s]."""
    period = dwell_s + move_s
    t_pose = 1.0 + np.arange(n_images) * period
    log_t = np.arange(0.0, t_pose[-1] + dwell_s + 1.0, 1.0 / rate_hz)
    k = np.floor((log_t - 1.0 + dwell_s / 2) / period).astype(int)
    at = (k >= 0) & (k < n_images) & (np.abs(log_t - t_pose[np.clip(k, 0, n_images - 1)]) <= dwell_s / 2)
    pose = np.where(at, k, -1)
    image_t = t_pose + clock_offset_s + rng.normal(0.0, jitter_s, n_images)
    return image_t, log_t, pose


def simulate_self_calibration(robot, *, chains=("left_hand", "right_hand"), camera_end_effector: str | None = None,
                              n_images_per_chain: int = 40, joint_offsets_deg=3.0, length_sigma_mm: float = 0.0,
                              joint_noise_deg: float = 0.05, pixel_noise: float = 0.3,
                              board: str | Board | None = None, camera: Camera | None = None,
                              camera_mount_error=(1.0, 0.5), board_mount_error=(2.0, 1.5),
                              partial_fraction: float = 0.1, board_bow_mm: float = 0.0,
                              clock_offset_s: float = 0.035, jitter_s: float = 0.004,
                              log_rate_hz: float = 20.0, move_s: float = 1.0, dwell_s: float = 1.0,
                              render: RenderSettings | None = None, seed: int = 0, out_dir=None,
                              overwrite: bool = False, progress=None) -> SelfCalibrationRun:
    """Simulate a camera self-calibration run (module docstring); with ``out_dir`` also render the
    images and write the files (:func:`write_self_calibration_files`).

    robot: a shipped robot name, a robot file path or a :class:`~robocal.kinematics.RobotModel`;
    chains: end effectors holding a board, or ``("world",)`` for a board fixed in the world;
    camera_end_effector: default ``"camera_top"`` (board in a hand) or the robot's first end
    effector (``"flange"``, board in the world); joint_offsets_deg: the half-width of the uniform
    joint offsets [deg] or {joint name: deg}; joint_noise_deg: reading noise per log row [deg];
    pixel_noise: sigma of ``image_points`` [px] (the images carry the renderer's effects instead);
    camera_mount_error / board_mount_error: (mm, deg) sigmas of the true mounts around the nominal;
    camera: default :func:`nao_top_camera` (hands) or :func:`~robocal.sim.cameras.camera_cell.default_camera`;
    board_bow_mm: the board is bent (a cylinder along its x axis) so that its middle lies this far
    from the plane of its ends, along the board's +z (:func:`board_surface`): the true corners and the
    images follow the bent board, a calibration model with a flat board does not.
    """
    nominal = load_robot(robot) if isinstance(robot, (str, Path)) else robot
    chains = tuple(chains)
    world = chains == ("world",)
    if not chains or ("world" in chains and not world):
        raise ValueError(f"chains must be end effectors holding a board, or ('world',) alone; got {chains}")
    if n_images_per_chain < 1:
        raise ValueError(f"n_images_per_chain must be at least 1, got {n_images_per_chain}")
    if not 0.0 <= partial_fraction <= 1.0:
        raise ValueError(f"partial_fraction must be within [0, 1], got {partial_fraction}")
    if camera_end_effector is None:
        camera_end_effector = nominal.end_effectors[0].name if world else "camera_top"
    for e in ((camera_end_effector,) + (() if world else chains)):
        nominal.end_effector_index(e)  # KeyError naming the known ones
    b = board if isinstance(board, Board) else parse_board(board or (DEFAULT_WORLD_BOARD if world else DEFAULT_BOARD))
    cam = camera or (default_camera() if world else nao_top_camera())
    ss = np.random.SeedSequence(int(seed))
    rng_truth, rng_views, rng_time, rng_noise = (np.random.default_rng(s) for s in ss.spawn(4))

    moved = _joints_moving(nominal, (camera_end_effector,) + (() if world else chains))
    true, joint_offsets_rad, errors = _true_model(nominal, moved, joint_offsets_deg, length_sigma_mm, rng_truth)
    X = b.object_points()
    n_part = int(round(partial_fraction * n_images_per_chain))
    if world:
        # camera ~100 mm off the flange looking along the tool axis; the board face up on the floor of
        # the cell, half the robot's reach in front of it
        T_cee_nom = transforms_from(so3_exp(np.array([0.0, 0.0, math.pi / 2])), np.array([60.0, -40.0, 110.0]))
        T_board_nom = {"world": compose(nominal.T_world_base, transforms_from(
            so3_exp(np.array([math.pi, 0.0, 0.0])) @ so3_exp(np.array([0.0, 0.0, rng_truth.uniform(-np.pi, np.pi)])),
            np.array([0.5, 0.08, 0.0]) * _reach_mm(nominal, camera_end_effector)))}
    else:
        T_cee_nom = np.eye(4)
        T_board_nom = {c: nominal_hand_board_mount(b) for c in chains}
    T_cee = compose(T_cee_nom, _small_transform(rng_truth, *camera_mount_error))
    T_board = {c: compose(T, _small_transform(rng_truth, *board_mount_error)) for c, T in T_board_nom.items()}

    q_list, chain_of, full_of = [], [], []
    for c in chains:
        if world:
            qf, qp = world_board_configurations(nominal, true, cam, X, b.front_z, T_board[c], T_cee, n_images_per_chain,
                                                n_part, rng_views, camera_ee=camera_end_effector, pitch_mm=b.pitch_mm)
        else:
            qf, qp = hand_configurations(true, cam, c, X, b.front_z, T_board[c], n_images_per_chain, n_part, rng_views,
                                         camera_ee=camera_end_effector, T_cee_camera=T_cee,
                                         limits=ViewLimits(margin_px=20.0, depth_mm=(100.0, 450.0)), pitch_mm=b.pitch_mm)
        q = np.vstack([qf, qp])
        flags = np.r_[np.ones(len(qf), bool), np.zeros(len(qp), bool)]
        order = rng_views.permutation(len(q))  # partial views interleaved with the others
        q_list.append(q[order])
        full_of.append(flags[order])
        chain_of += [c] * len(q)
    q_img = np.vstack(q_list)
    fully = np.concatenate(full_of)

    T_cam = compose(true.fk(q_img, camera_end_effector), T_cee)
    if world:
        T_wb = np.broadcast_to(T_board["world"], (len(q_img), 4, 4))
    else:
        T_wb = np.stack([compose(true.fk(q_img[k], c), T_board[c]) for k, c in enumerate(chain_of)])
    T_cb = compose(invert_transforms(T_cam), T_wb)
    surface = board_surface(b, board_bow_mm)
    X_true = X if surface is None else np.column_stack([X[:, :2], surface(X[:, 0], X[:, 1])])
    p = np.einsum("nij,pj->npi", T_cb[:, :3, :3], X_true) + T_cb[:, None, :3, 3]
    px = cam.project(np.where(p[..., 2:] > 1.0, p, [0.0, 0.0, 1.0]).reshape(-1, 3)).pixels.reshape(len(q_img), len(X), 2)
    px[p[..., 2] <= 1.0] = np.nan
    noisy = px + rng_noise.normal(0.0, pixel_noise, px.shape)

    q_start = q_img[0] if world else np.clip(np.zeros(nominal.n_joints), nominal.limits[:, 0], nominal.limits[:, 1])
    t0 = 100.0 + rng_time.uniform(0.0, 50.0)
    capture, log_t, log_q, log_pose = _timeline(q_img, q_start, rng_time, move_s=move_s, dwell_s=dwell_s,
                                                log_rate_hz=log_rate_hz, t0=t0)
    log_q = log_q + rng_noise.normal(0.0, math.radians(joint_noise_deg), log_q.shape)
    frame_t = capture + clock_offset_s + rng_time.normal(0.0, jitter_s, len(capture))
    names = tuple(f"img_{k:03d}.png" for k in range(len(q_img)))
    settings = {"seed": int(seed), "n_images_per_chain": int(n_images_per_chain), "partial_fraction": partial_fraction,
                "board_bow_mm": float(board_bow_mm),
                "joint_offsets_deg": joint_offsets_deg if not isinstance(joint_offsets_deg, dict) else "given",
                "length_sigma_mm": length_sigma_mm, "joint_noise_deg": joint_noise_deg, "pixel_noise_px": pixel_noise,
                "camera_mount_error_mm_deg": list(camera_mount_error), "board_mount_error_mm_deg": list(board_mount_error),
                "clock_offset_s": clock_offset_s, "jitter_s": jitter_s, "log_rate_hz": log_rate_hz, "move_s": move_s,
                "dwell_s": dwell_s}
    run = SelfCalibrationRun(
        robot=nominal, true_robot=true, camera=cam, camera_end_effector=camera_end_effector, chains=chains, board=b,
        T_ee_camera_nominal=T_cee_nom, T_ee_camera=T_cee, T_ee_board_nominal=T_board_nom, T_ee_board=T_board,
        joint_offsets_rad=joint_offsets_rad, parameter_errors=errors, images=names, chain_of_image=tuple(chain_of),
        fully_visible=fully, q_true=q_img, T_camera_board=T_cb, image_points_true=px, image_points=noisy,
        capture_times=capture, frame_times=frame_t, log_times=log_t, log_joints=log_q, log_pose=log_pose,
        settings=settings)
    if out_dir is not None:
        write_self_calibration_files(run, out_dir, render=render, overwrite=overwrite, progress=progress)
    return run


def board_surface(board: Board, bow_mm: float):
    """``surface(x, y) -> z`` [mm, board frame] of a board bent into a cylinder along its x axis:
    z = bow (1 - ((x - xc) / hx)^2) with xc, hx the middle and half length of the printed pattern
    (the object points' extent plus one pitch each side); ``None`` for a flat board (bow 0)."""
    if bow_mm == 0.0:
        return None
    X = board.object_points()
    x0, x1 = X[:, 0].min() - board.pitch_mm, X[:, 0].max() + board.pitch_mm
    xc, hx, bow = 0.5 * (x0 + x1), 0.5 * (x1 - x0), float(bow_mm)

    def surface(x, y):
        return bow * (1.0 - ((x - xc) / hx) ** 2) + 0.0 * y

    return surface


def _texel_mm(board: Board) -> float:
    return board.pitch_mm / max(int(np.ceil(board.pitch_mm / 0.1)), 1)


def _matrix(T) -> list:
    return [[float(v) for v in row] for row in np.asarray(T)]


def truth_document(run: SelfCalibrationRun) -> dict:
    """The hidden truth of ``run`` as the ``truth.json`` document (units in its ``units`` key)."""
    m = run.robot
    cam = run.camera
    link_of_cee = m.end_effectors[m.end_effector_index(run.camera_end_effector)]
    # the true camera in the frame of the link carrying the camera end effector (NAO: CameraTop),
    # and in the frame of the last moving joint before it (NAO: HeadPitch, after its motion)
    T_link_camera = compose(link_of_cee.T_link_ee, run.T_ee_camera)
    k = link_of_cee.link
    while k >= 0 and not m.links[k].moves:
        k = m.links[k].parent
    if k >= 0:
        q0 = np.clip(np.zeros(m.n_joints), m.limits[:, 0], m.limits[:, 1])
        tm = run.true_robot
        T_joint_world = invert_transforms(tm.link_frames(q0)[int(np.searchsorted(m.moving, k))])
        T_joint_camera = compose(T_joint_world, tm.fk(q0, run.camera_end_effector), run.T_ee_camera)
    else:
        T_joint_camera = compose(invert_transforms(m.T_world_base), m.fk(np.zeros(m.n_joints), run.camera_end_effector),
                                 run.T_ee_camera)
    return {
        "format": TRUTH_FORMAT, "robot": m.name, "setup": "board_in_world" if run.chains == ("world",) else "board_in_hand",
        "chains": list(run.chains), "camera_end_effector": run.camera_end_effector, "board": run.board.spec,
        "units": "lengths mm, angles deg, times s; matrices are 4x4 homogeneous [mm]",
        "joint_offsets_deg": {k: math.degrees(v) for k, v in run.joint_offsets_rad.items()},
        "parameter_errors": {k: (math.degrees(v) if m.params.units[m.params.index(k)] == "rad" else v)
                             for k, v in run.parameter_errors.items()},
        "camera": {"fx": cam.fx, "fy": cam.fy, "cx": cam.cx, "cy": cam.cy, "distortion": list(cam.distortion),
                   "model": cam.model, "image_size": list(cam.image_size)},
        "camera_mount": {"end_effector": run.camera_end_effector, "T_ee_camera": _matrix(run.T_ee_camera),
                         "T_ee_camera_nominal": _matrix(run.T_ee_camera_nominal),
                         "link": m.links[link_of_cee.link].name if link_of_cee.link >= 0 else "base",
                         "T_link_camera": _matrix(T_link_camera),
                         "joint": m.links[k].name if k >= 0 else "base", "T_joint_camera": _matrix(T_joint_camera),
                         "T_head_camera": _matrix(T_joint_camera)},
        "boards": {c: {"T_ee_board": _matrix(run.T_ee_board[c]), "T_ee_board_nominal": _matrix(run.T_ee_board_nominal[c]),
                       "frame": "world" if c == "world" else c} for c in run.chains},
        "clock": {"offset_s": run.settings["clock_offset_s"], "jitter_s": run.settings["jitter_s"],
                  "meaning": "frame time (camera clock) = capture time (robot clock) + offset_s + N(0, jitter_s)"},
        "settings": run.settings,
        "images": [{"image": n, "chain": c, "fully_visible": bool(f), "capture_time_robot_s": float(tc),
                    "frame_time_s": float(tf), "q_true_deg": [float(v) for v in np.degrees(q)],
                    "T_camera_board": _matrix(T),
                    "image_points_true_px": [[float(v) for v in row] for row in np.nan_to_num(pts, nan=-1.0)]}
                   for n, c, f, tc, tf, q, T, pts in zip(run.images, run.chain_of_image, run.fully_visible,
                                                         run.capture_times, run.frame_times, run.q_true,
                                                         run.T_camera_board, run.image_points_true)],
        "joint_names": list(m.controller_joints),
    }


def write_self_calibration_files(run: SelfCalibrationRun, out_dir, *, render: RenderSettings | None = None,
                                 overwrite: bool = False, progress=None) -> dict:
    """Render the images and write the run's files into ``out_dir`` (module docstring); every file
    is written atomically and none is replaced unless ``overwrite``. ``progress(i, n, text)`` after
    each image. Returns ``{role: path}``."""
    out = Path(out_dir)
    if not overwrite:
        for name in OUTPUT_NAMES:
            if (out / name).exists():
                raise FileExistsError(f"{out / name}: exists; pass overwrite=True to replace it")
    (out / "images").mkdir(parents=True, exist_ok=True)
    texture, affine = board_image(run.board, _texel_mm(run.board))
    renderer = BoardRenderer(run.camera, texture, affine, render or RenderSettings(blur_px=0.8),
                             surface=board_surface(run.board, run.settings.get("board_bow_mm", 0.0)))
    rng = np.random.default_rng(np.random.SeedSequence([run.settings["seed"], 7]))
    for i, (name, T) in enumerate(zip(run.images, run.T_camera_board), 1):
        write_png(out / "images" / name, renderer.render(T, rng), overwrite=overwrite)
        if progress is not None:
            progress(i, run.n_images, f"rendered {name}")
    m = run.robot
    note = (f"simulated self-calibration of {m.name}, seed {run.settings['seed']}; reading noise "
            f"{run.settings['joint_noise_deg']} deg per row")
    paths = {"images": out / "images"}
    paths["joint_log"] = write_joint_log(out / "joint_log.csv", run.log_times, run.log_joints, m.controller_joints,
                                         robot=m.name, angle_unit="deg", notes=[note], overwrite=overwrite)
    paths["frames"] = write_frames(out / "frames.csv", run.images, run.frame_times, overwrite=overwrite,
                                   notes=[f"capture times on the camera clock ({run.camera_end_effector})"])
    camera_tmp = out / ".camera.json.tmp"
    write_camera_json(camera_tmp, run.camera)
    paths["camera"] = atomic_write_text(out / "camera.json", camera_tmp.read_text(), overwrite=overwrite)
    camera_tmp.unlink()
    paths["truth"] = atomic_write_text(out / "truth.json", json.dumps(truth_document(run), indent=1) + "\n",
                                       overwrite=overwrite)
    return paths
