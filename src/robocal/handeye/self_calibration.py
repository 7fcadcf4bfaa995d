"""Camera-based kinematic self-calibration of one or several chains at once (issue 15; METHODS.md
section 3, "Camera self-calibration": a robot's own camera photographs a board carried by one of
its end effectors, or fixed in the world, and Levenberg-Marquardt minimises the reprojection error
over the joint offsets of every chain involved).

For image i with the board on carrier ``b_i`` (an end effector, or the world) the board's corners
``X`` are seen at ``u = project(C^-1 A_i^-1 B_i T_b X)`` with ``A_i`` the camera's end effector
and ``B_i`` the carrier (identity for the world), both from forward kinematics at the reported
joints with one geometry block, ``C`` = ``T_ee_camera`` (the camera mount) and ``T_b`` the board
on its carrier (:class:`~robocal.calib.residuals.FlangeReprojectionResidual` with
``target_end_effector``). All chains are solved jointly in one problem on the calibration core.

1. Per image the board pose by PnP (:func:`.pnp.solve_pnp`); images without a pose are skipped.
2. Start: the camera mount as given, else the better (smaller initial reprojection cost, every
   corner in front of the camera) of the identity (the end effector is the camera's optical
   frame) and Shah's AX = ZB per carrier with ``B_i^-1 A_i`` as the "flange" poses (with several
   degrees of joint-offset error the nominal chain can put Shah's mount half a metre off); each
   board transform the chordal mean of ``B_i^-1 A_i C T_camera_board_i``.
3. One problem: joint offsets of every joint on a path from the base to the camera or to a carrier
   (plus ``link_parameters``), the camera mount, one board transform per carrier, optionally the
   intrinsics. What the images cannot determine is held and named by the core's identifiability
   analysis; :attr:`SelfCalibration.joint_report` says per joint which chains it is on and why a
   held one is held (a joint on the path to the camera and to every board -- a torso joint -- cancels;
   the last joint of a board's arm trades against that board's transform; the last joint before
   the camera against the camera mount).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np

from ..calib import Problem, solve
from ..calib.blocks import FramesBlock, GaussianPrior, RobotGeometry, VectorBlock
from ..calib.residuals import FlangeReprojectionResidual
from ..calib.solve import NotConvergedWarning
from ..camera import Camera
from ..kinematics.links import link_operations
from ..transforms import invert_transforms
from .motions import HandEyeError
from .pnp import solve_pnp
from .refine import _intrinsics_block, _pixel_sigma, mean_transform
from .solve import solve_robot_world_hand_eye

__all__ = ["SelfCalibration", "solve_self_calibration", "assign_carriers", "WORLD"]

#: carrier name of a board fixed in the robot's base frame
WORLD = "world"


@dataclass(frozen=True)
class SelfCalibration:
    """The result of :func:`solve_self_calibration` (transforms (4, 4) [mm]).

    model: the calibrated robot model; joint_offset_names (k,) the estimated parameters (``theta<k>``,
    link parameters) and joint_offsets (k,) their corrections [rad | mm], 0 for held ones;
    joint_offset_sigma (k,) their 1-sigma (NaN where held); camera_mount: T_ee_camera;
    boards: {carrier: T_carrier_board}; camera: refined or as given; residuals_px (N, P, 2)
    detected minus projected with the calibrated model (NaN where not detected / skipped);
    rms_px; per_image_rms_px (N,); pixel_sigma [px] used to weight corners; identifiability: the
    core's report; joint_report: one dict per candidate joint offset (name, joint, chains: the end
    effectors it moves, loops: the carriers whose images it affects, identifiable, why); converged; message; skipped {image index: reason}; variable_names,
    values, std: every free variable of the solve; variance_factor: sqrt(weighted residual sum /
    redundancy), 1 when the corners scatter as ``pixel_sigma`` says; above 1 the reported sigmas
    are scaled by it (a posteriori), and above 1.5 the message says so: unmodelled effects such as
    joint-reading noise, which moves a whole image at once, make even those sigmas too small.
    """

    model: object
    joint_offset_names: tuple
    joint_offsets: np.ndarray
    joint_offset_sigma: np.ndarray
    camera_mount: np.ndarray
    boards: dict
    camera: Camera
    residuals_px: np.ndarray
    rms_px: float
    per_image_rms_px: np.ndarray
    pixel_sigma: float
    identifiability: object
    joint_report: list
    converged: bool
    message: str
    skipped: dict
    variable_names: tuple
    values: np.ndarray
    std: np.ndarray
    iterations: int = 0
    variance_factor: float = float("nan")


def _chain_parameters(model, end_effectors) -> dict:
    """{parameter index: [end effectors it moves]} over ``end_effectors`` (names)."""
    idx = [model.end_effector_index(e) for e in end_effectors]
    masks = model.kinematics_with(np.zeros((1, model.n_joints)), T_world_base=np.eye(4), end_effectors=idx)[3]
    out: dict = {}
    for name, m in zip(end_effectors, masks):
        for p in np.flatnonzero(m):
            out.setdefault(int(p), []).append(name)
    return out


def _offset_candidates(model) -> list:
    """[(parameter name, joint/link name)] of every moving joint's offset."""
    out = []
    for k, link in enumerate(model.links):
        for _code, pname, moves in link_operations(link):
            if moves:
                out.append((f"{pname}{k + 1}", link.name))
    return out


def _correctable_joints(model, geometry) -> tuple:
    """(controller columns, positions in ``geometry``'s variables) of the joints whose reading
    drives exactly one model joint with factor 1 and whose offset the block holds."""
    cols, pos = [], []
    names = list(geometry.names)
    for c in range(model.n_joints):
        rows = np.flatnonzero(model.coupling[:, c])
        if len(rows) != 1 or model.coupling[rows[0], c] != 1.0 or np.count_nonzero(model.coupling[rows[0]]) != 1:
            continue
        k = int(model.moving[rows[0]])
        for _code, pname, moves in link_operations(model.links[k]):
            if moves and f"{pname}{k + 1}" in names:
                cols.append(c)
                pos.append(names.index(f"{pname}{k + 1}"))
    return np.array(cols, dtype=int), np.array(pos, dtype=int)


def solve_self_calibration(model, joints, image_points, target_points, camera: Camera, carriers, *,
                           camera_end_effector: str, camera_mount=None, link_parameters=(),
                           refine_intrinsics=False, pixel_sigma: float | None = None,
                           min_points: int = 6, joint_noise_deg: float | None = None) -> SelfCalibration:
    """Joint offsets of every chain involved, the camera mount and the board transforms from images.

    model: a :class:`~robocal.kinematics.model.RobotModel` (a tree is fine); joints (N, n) [rad |
    mm] the controller joints at each image; image_points (N, P, 2) [px], NaN where not detected
    (an image with NaN rows only is skipped); target_points (P, 3) [mm]; camera: the intrinsics;
    carriers: N names, the end effector holding the board in each image or ``"world"``;
    camera_end_effector: the end effector that carries the camera; camera_mount (4, 4) [mm]:
    nominal T_ee_camera (default: the identity or Shah's AX = ZB, whichever fits better); link_parameters: further
    parameter names of the model to estimate (e.g. ``["a2", "d4"]``); refine_intrinsics: as
    :func:`~robocal.handeye.refine.refine_hand_eye`; pixel_sigma [px]: the corner noise (default:
    from the PnP residuals); joint_noise_deg: 1-sigma of each joint reading [deg]: every image gets
    a correction of each joint of the chains involved with that Gaussian prior (errors in
    variables; a reading's noise moves a whole image at once, which corner weights alone cannot
    describe); ``None``: readings exact.

    Raises :class:`HandEyeError` naming the problem (counts that differ, unknown end effectors,
    fewer than 3 usable images of a carrier, joints that look like degrees).
    """
    q_all = np.asarray(joints, dtype=float)
    uv_all = np.asarray(image_points, dtype=float)
    X = np.asarray(target_points, dtype=float)
    carriers = [str(c) for c in carriers]
    N = len(uv_all)
    if q_all.shape != (N, model.n_joints):
        raise HandEyeError(f"joints: expected ({N}, {model.n_joints}) [rad] for {N} images, got {q_all.shape}")
    if len(carriers) != N:
        raise HandEyeError(f"{len(carriers)} carriers for {N} images: one per image")
    if np.nanmax(np.abs(q_all)) > 4 * np.pi:
        raise HandEyeError("joints exceed two turns: they look like degrees; the solver takes radians")
    ee_names = [e.name for e in model.end_effectors]
    for name in {camera_end_effector, *carriers} - {WORLD}:
        if name not in ee_names:
            raise HandEyeError(f"robot {model.name} has no end effector {name!r}; it has {', '.join(ee_names)}")
    T_ct, _, reasons = solve_pnp(camera, X, uv_all, min_points=min_points)
    good = np.all(np.isfinite(T_ct), axis=(1, 2))
    skipped = {int(i): reasons[i] or "no pose of the board found in this image" for i in np.flatnonzero(~good)}
    groups = {c: np.flatnonzero(good & (np.array(carriers) == c)) for c in dict.fromkeys(carriers)}
    for c, idx in groups.items():
        if len(idx) < 3:
            raise HandEyeError(f"board on {c!r}: {len(idx)} usable images, need at least 3")

    cam_ee = model.end_effector_index(camera_end_effector)

    def frames(q, carrier):
        A = model.kinematics_with(q, T_world_base=np.eye(4), end_effectors=[cam_ee])[0][:, 0]
        if carrier == WORLD:
            return A, np.tile(np.eye(4), (len(q), 1, 1))
        return A, model.kinematics_with(q, T_world_base=np.eye(4),
                                        end_effectors=[model.end_effector_index(carrier)])[0][:, 0]

    if camera_mount is None:  # candidates: the end effector is the optical frame, or Shah per carrier
        starts = [np.eye(4)]
        for c, idx in groups.items():
            A, B = frames(q_all[idx], c)
            starts.append(solve_robot_world_hand_eye(invert_transforms(B) @ A, T_ct[idx], setup="eye_in_hand")[0])
    else:
        starts = [np.asarray(camera_mount, dtype=float)]

    def boards_for(C0):
        out = {}
        for c, idx in groups.items():
            A, B = frames(q_all[idx], c)
            out[c] = mean_transform(invert_transforms(B) @ A @ C0 @ T_ct[idx])
        return out

    # the joint offsets of every chain involved
    chains = [camera_end_effector] + [c for c in groups if c != WORLD]
    moved = _chain_parameters(model, chains)
    pnames = model.params.names
    candidates = [(n, j) for n, j in _offset_candidates(model) if pnames.index(n) in moved]
    names = [n for n, _ in candidates] + [p for p in link_parameters if p not in dict(candidates)]
    geometry = RobotGeometry(model, names, name="joint_offsets")
    cam = _intrinsics_block(camera, refine_intrinsics)
    sigma = float(pixel_sigma) if pixel_sigma is not None else _pixel_sigma(uv_all[good], T_ct[good], camera, X)

    corrections = {}
    if joint_noise_deg is not None:
        if not joint_noise_deg > 0:
            raise HandEyeError(f"joint_noise_deg: expected a positive number, got {joint_noise_deg!r}")
        cols, pos = _correctable_joints(model, geometry)
        for c, idx in groups.items():
            names_c = [f"dq_{c}{i}.{model.controller_joints[j]}" for i in range(len(idx)) for j in cols]
            corrections[c] = (VectorBlock(f"dq_{c}", names_c, ["rad"] * len(names_c), np.zeros((len(idx), len(cols))),
                                          prior=GaussianPrior(np.radians(joint_noise_deg)), group="corrections"),
                              dict(correction_columns=cols, correction_params=pos))

    def build(C0):
        mount = FramesBlock("camera_mount", C0, group="base")
        boards = {c: FramesBlock(f"board_{c}", T, group="targets") for c, T in boards_for(C0).items()}
        residuals = []
        for c, idx in groups.items():
            kw = dict(target_end_effector=c) if c != WORLD else {}
            if c in corrections:
                kw.update(joint_corrections=corrections[c][0], **corrections[c][1])
            residuals.append(FlangeReprojectionResidual(cam, mount, boards[c], uv_all[idx], X, model=model,
                                                        q=q_all[idx], geometry=geometry, end_effector=cam_ee,
                                                        invert=True, sigma=sigma, **kw))
        problem = Problem([cam, mount, *boards.values(), geometry, *(b for b, _ in corrections.values())],
                          residuals)
        r = problem.evaluate(problem.initial_state(), jacobian=False)[0]
        cost = float(np.mean(r ** 2)) if np.all(np.isfinite(r)) else np.inf
        return cost, problem

    cost, problem = min((build(C0) for C0 in starts), key=lambda t: t[0])
    if not np.isfinite(cost):
        raise HandEyeError("no start puts the board in front of the camera in every image: check the robot file, "
                           "the joints (radians) and which end effector carries the camera and the board")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", NotConvergedWarning)
        result = solve(problem)
    state = dict(zip([b.name for b in problem.parameter_blocks], result.state))
    params = state["joint_offsets"]
    calibrated = model.with_params(params)
    value = state["cam"]
    refined = Camera(*value[:4], tuple(value[4:]), camera.model, camera.image_size)
    C, boards = state["camera_mount"][0], {c: state[f"board_{c}"][0] for c in groups}

    # back-projection with the calibrated model at the reported joints
    res_px = np.full_like(uv_all, np.nan)
    for c, idx in groups.items():
        A, B = (calibrated.kinematics_with(q_all[idx], T_world_base=np.eye(4), end_effectors=[cam_ee])[0][:, 0],
                np.tile(np.eye(4), (len(idx), 1, 1)) if c == WORLD else calibrated.kinematics_with(
                    q_all[idx], T_world_base=np.eye(4), end_effectors=[calibrated.end_effector_index(c)])[0][:, 0])
        T = invert_transforms(C)[None] @ invert_transforms(A) @ B @ boards[c][None]
        p = np.einsum("nij,pj->npi", T[:, :3, :3], X) + T[:, None, :3, 3]
        res_px[idx] = uv_all[idx] - refined.project(p.reshape(-1, 3)).pixels.reshape(len(idx), -1, 2)
    norms = np.linalg.norm(res_px, axis=2)
    ok = np.isfinite(norms)
    rms = float(np.sqrt(np.mean(norms[ok] ** 2))) if ok.any() else float("nan")
    with np.errstate(invalid="ignore"):
        per_image = np.sqrt(np.nanmean(np.where(ok, norms ** 2, np.nan), axis=1))

    offsets = params[geometry.index] - geometry.initial[geometry.index]
    r_after = np.asarray(result.residuals_after)
    redundancy = max(len(r_after) - int(result.rank), 1)
    s0 = float(np.sqrt(np.sum(r_after ** 2) / redundancy))
    scale = max(1.0, s0)
    std_all = np.asarray(result.std) * scale
    std_of = dict(zip(result.names, std_all))
    sig = np.array([std_of.get(n, np.nan) for n in geometry.names])
    dropped = {d["name"]: d for d in result.identifiability.dropped}
    report = []
    for n, joint in candidates:
        on = moved[pnames.index(n)]
        d = dropped.get(n)
        why = None
        if d is not None:
            why = d["why"]
            if set(on) >= set(chains) and len(chains) > 1:
                why = f"on the path to the camera and to every board ({', '.join(on)}): it cancels; " + why
        loops = [c for c in groups if (camera_end_effector in on) != (c in on)]
        report.append({"name": n, "joint": joint, "chains": list(on), "loops": loops, "identifiable": d is None,
                       "why": why})
    msg = (f"{'converged' if result.converged else 'NOT CONVERGED (' + result.reason + ')'} after "
           f"{result.iterations} iterations; {int(good.sum())} of {N} images on {len(groups)} carrier(s), "
           f"RMS {rms:.3f} px")
    if s0 > 1.5:
        msg += (f"; residuals {s0:.1f}x the corner noise {sigma:.3g} px: joint-reading noise or effects the model "
                "lacks (sigmas scaled by it, still optimistic)")
    if dropped:
        msg += "; not identifiable (held): " + ", ".join(dropped)
    return SelfCalibration(
        model=calibrated, joint_offset_names=tuple(geometry.names), joint_offsets=offsets, joint_offset_sigma=sig,
        camera_mount=C, boards=boards, camera=refined, residuals_px=res_px, rms_px=rms, per_image_rms_px=per_image,
        pixel_sigma=sigma, identifiability=result.identifiability, joint_report=report,
        converged=bool(result.converged), message=msg, skipped=skipped, variable_names=tuple(result.names),
        values=np.asarray(result.values), std=std_all, iterations=int(result.iterations), variance_factor=s0)


def assign_carriers(model, joints, image_points, target_points, camera: Camera, carriers, *,
                    camera_end_effector: str, camera_mount=None, min_points: int = 6, max_distance_mm: float = 250.0,
                    min_ratio: float = 1.5):
    """Which end effector holds the board in each image, when several may: ``(names (N,) or None,
    distances (N, C) [mm], reasons (N,) None or why no carrier was assigned)``.

    The board's centre is placed by PnP and the nominal kinematics (``camera_mount`` default the
    identity: the end effector is the camera's optical frame) and assigned to the nearest carrier
    origin if it is within ``max_distance_mm`` and ``min_ratio`` times nearer than the next one
    (joint offsets of a few degrees move it by tens of millimetres, the hands are further apart).
    """
    carriers = [str(c) for c in carriers]
    if WORLD in carriers:
        raise HandEyeError("a board in the world and a board in a hand cannot be told apart automatically; "
                           "give one carrier")
    q = np.asarray(joints, dtype=float)
    X = np.asarray(target_points, dtype=float)
    T_ct, _, why = solve_pnp(camera, X, np.asarray(image_points, dtype=float), min_points=min_points)
    C0 = np.eye(4) if camera_mount is None else np.asarray(camera_mount, dtype=float)
    ees = [model.end_effector_index(camera_end_effector)] + [model.end_effector_index(c) for c in carriers]
    T = model.kinematics_with(q, T_world_base=np.eye(4), end_effectors=ees)[0]
    centre = np.append(X.mean(axis=0), 1.0)
    board_in_base = (T[:, 0] @ C0 @ T_ct @ centre)[:, :3]
    dist = np.linalg.norm(board_in_base[:, None, :] - T[:, 1:, :3, 3], axis=2)
    names, reasons = [], []
    for i in range(len(q)):
        if not np.all(np.isfinite(dist[i])):
            names.append(None)
            reasons.append(why[i] or "no pose of the board found in this image")
            continue
        order = np.argsort(dist[i])
        near = dist[i, order[0]]
        second = dist[i, order[1]] if len(order) > 1 else np.inf
        if near > max_distance_mm:
            names.append(None)
            reasons.append(f"the board is {near:.0f} mm from the nearest carrier ({carriers[order[0]]}); more than "
                           f"{max_distance_mm:g} mm: which end effector holds it?")
        elif second < min_ratio * near:
            names.append(None)
            reasons.append(f"the board is {near:.0f} mm from {carriers[order[0]]} and {second:.0f} mm from "
                           f"{carriers[order[1]]}: cannot tell which holds it")
        else:
            names.append(carriers[order[0]])
            reasons.append(None)
    return names, dist, reasons
