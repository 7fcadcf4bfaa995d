"""Hand-eye calibration refined on the reprojection error of every corner (issue 14 items 4 and 5;
METHODS.md section 3, "Hand-eye": linear first, then refine, then show the back-projection).

1. Per image, the target's pose in the camera by PnP on the given camera (:mod:`.pnp`: homography
   start and Levenberg–Marquardt, no OpenCV); images with too few corners are skipped with a reason.
2. Every linear solver (Tsai–Lenz, Park–Martin, Daniilidis on ``AX = XB``; Shah on ``AX = ZB``) on
   those poses; ``method`` picks the start. Degenerate pose sets raise :class:`HandEyeError`
   naming the problem (fewer than 3 usable images, pure translations, one rotation axis only).
3. One problem on the calibration core (:func:`robocal.calib.solve`), the pixel residual of every
   detected corner ``u = project(C^-1 M_i T X)``
   (:class:`~robocal.calib.residuals.ReprojectionResidual`):

   * eye-in-hand: ``C = T_flange_camera``, ``M_i = T_base_flange_i^-1``, ``T = T_base_target``;
   * eye-to-hand: ``C = T_base_camera``, ``M_i = T_base_flange_i``, ``T = T_flange_target``;

   over C and T, optionally the intrinsics and distortion (``refine_intrinsics``) and the robot's
   joint offsets (``joints`` + ``robot`` + ``joint_offsets``: ``M_i`` from forward kinematics,
   :class:`~robocal.calib.residuals.RobotReprojectionResidual`). Covariance from the core, scaled
   by the residual spread; parameters the poses cannot determine are held and named
   (``identifiability``: e.g. joint 1's offset trades off against the target's rotation about the
   base z axis for a wrist camera).
4. Back-projection residuals per image and per corner, in pixels and in millimetres on the target
   (:mod:`.backprojection`).
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from ..calib import Problem, solve
from ..calib.blocks import CameraIntrinsics, FramesBlock, RobotGeometry
from ..calib.residuals import FlangeReprojectionResidual, PosePriorResidual
from ..calib.schur import StructureError, solve_schur
from ..calib.solve import NotConvergedWarning
from ..camera import Camera
from ..kinematics.links import link_operations
from ..transforms import invert_transforms, skew, so3_log
from .backprojection import rms_px, target_plane_residuals
from .motions import SETUPS, HandEyeError
from .pnp import solve_pnp
from .solve import AX_XB_METHODS, solve_hand_eye, solve_robot_world_hand_eye

__all__ = ["HandEyeRefinement", "refine_hand_eye", "LINEAR_METHODS", "joint_offset_names", "mean_transform",
           "rotation_error_deg"]

#: the linear starts by name
LINEAR_METHODS = (*AX_XB_METHODS, "shah")


@dataclass(frozen=True)
class HandEyeRefinement:
    """The result of :func:`refine_hand_eye` (transforms (4, 4) in mm; see the module docstring).

    camera_pose: ``T_flange_camera`` (eye_in_hand) or ``T_base_camera`` (eye_to_hand), named by
    ``camera_pose_frame`` ("flange" | "base"); target_pose: ``T_base_target`` or
    ``T_flange_target`` (``target_pose_frame``); camera: refined or as given; residuals_px,
    residuals_mm (N, P, 2): detected minus projected, in pixels and on the target plane, NaN where
    not detected or the image was skipped; rms_px, per_image_rms_px (N,); sigma_rotation_deg (3,)
    1-sigma of the camera pose's rotation (small rotation about the parent frame's axes);
    sigma_translation_mm (3,); covariance over ``variable_names`` (the core's units: rad, mm, px,
    1); identifiability: the core's report (``dropped`` names what the poses cannot determine);
    linear: {method: (camera_pose, target_pose)} of every linear solver on the same PnP poses (a
    :class:`LinearSolutions` mapping: each solved on first access);
    joint_offsets_rad: the joint-offset corrections (rad; mm for a prismatic joint) in the order of
    ``joint_offset_names``, 0 for held ones, or None; converged; message; T_camera_target (N, 4, 4)
    the per-image PnP poses (NaN for skipped images); skipped: {image index: reason};
    residuals_mm_rms, per_image_rms_mm (N,); outliers: {image index: reason} of the images a robust
    ``loss`` rejected (their residuals are still reported).
    """

    setup: str
    camera_pose: np.ndarray
    camera_pose_frame: str
    target_pose: np.ndarray
    target_pose_frame: str
    camera: Camera
    residuals_px: np.ndarray
    residuals_mm: np.ndarray
    rms_px: float
    per_image_rms_px: np.ndarray
    sigma_rotation_deg: np.ndarray
    sigma_translation_mm: np.ndarray
    covariance: np.ndarray
    variable_names: tuple
    identifiability: object
    linear: dict
    joint_offsets_rad: np.ndarray | None
    converged: bool
    message: str
    T_camera_target: np.ndarray | None = None
    skipped: dict | None = None
    rms_mm: float = float("nan")
    per_image_rms_mm: np.ndarray | None = None
    joint_offset_names: tuple = ()
    outliers: dict | None = None
    noise_estimate: dict | None = None
    warnings: tuple = ()


def joint_offset_names(model) -> list:
    """The joint-offset parameters of a robot model: ``theta<k>`` of a revolute link, ``d<k>`` of
    a prismatic one (the parameter its joint variable adds to), in link order."""
    out = []
    for k, link in enumerate(model.links):
        for _code, pname, moves in link_operations(link):
            if moves:
                out.append(f"{pname}{k + 1}")
    return out


def mean_transform(T) -> np.ndarray:
    """The chordal mean (4, 4) of transforms T (N, 4, 4): rotation by SVD of the summed rotations,
    translation the mean."""
    U, _, Vt = np.linalg.svd(np.sum(T[:, :3, :3], axis=0))
    out = np.eye(4)
    out[:3, :3] = U @ np.diag([1.0, 1.0, np.linalg.det(U @ Vt)]) @ Vt
    out[:3, 3] = T[:, :3, 3].mean(0)
    return out


def _check_inputs(T_base_flange, image_points, target_points, setup):
    if setup not in SETUPS:
        raise HandEyeError(f"unknown set-up {setup!r}; expected eye_in_hand or eye_to_hand")
    F = np.asarray(T_base_flange, dtype=float)
    uv = np.asarray(image_points, dtype=float)
    X = np.asarray(target_points, dtype=float)
    if F.ndim != 3 or F.shape[1:] != (4, 4):
        raise HandEyeError(f"T_base_flange: expected (N, 4, 4) transforms in mm, got shape {F.shape}")
    if uv.ndim != 3 or uv.shape[2] != 2:
        raise HandEyeError(f"image_points: expected (N images, P points, 2) pixels, got shape {uv.shape}")
    if len(F) != len(uv):
        raise HandEyeError(f"{len(F)} flange poses but {len(uv)} images: they must pair one to one")
    if X.shape != (uv.shape[1], 3) or not np.all(np.isfinite(X)):
        raise HandEyeError(f"target_points: expected ({uv.shape[1]}, 3) finite millimetres, got shape {X.shape}")
    if not np.all(np.isfinite(F)):
        bad = np.flatnonzero(~np.isfinite(F).all(axis=(1, 2)))
        raise HandEyeError(f"T_base_flange: pose(s) {bad.tolist()} contain NaN")
    extent = np.ptp(X, axis=0).max()
    if extent < 1.0:
        raise HandEyeError(f"target_points span only {extent:.3g}: expected millimetres (metres given?)")
    reach = np.linalg.norm(F[:, :3, 3], axis=1).max()
    if reach < 5.0:
        raise HandEyeError(f"T_base_flange translations reach only {reach:.3g}: expected millimetres (metres given?)")
    return F, uv, X


class LinearSolutions(Mapping):
    """{method: (camera_pose, target_pose)} of every linear solver (:data:`LINEAR_METHODS`) on the
    same flange poses F (N, 4, 4) and PnP poses C (N, 4, 4) [mm], each solved on first access (the
    refinement needs one start; the others are for the report)."""

    def __init__(self, F, C, setup):
        self._F, self._C, self._setup, self._done = F, C, setup, {}

    def __getitem__(self, method):
        if method not in self._done:
            if method not in LINEAR_METHODS:
                raise KeyError(method)
            F, C, setup = self._F, self._C, self._setup
            if method == "shah":
                self._done[method] = solve_robot_world_hand_eye(F, C, setup=setup)
            else:
                Xc = solve_hand_eye(F, C, setup=setup, method=method)
                if setup == "eye_in_hand":  # T_base_target = F_i X C_i
                    self._done[method] = (Xc, mean_transform(F @ Xc @ C))
                else:  # T_flange_target = F_i^-1 X C_i
                    self._done[method] = (Xc, mean_transform(invert_transforms(F) @ Xc @ C))
        return self._done[method]

    def __iter__(self):
        return iter(LINEAR_METHODS)

    def __len__(self):
        return len(LINEAR_METHODS)

    def __repr__(self):
        return f"LinearSolutions({dict(self)!r})"


def _linear_solutions(F, C, setup) -> LinearSolutions:
    """{method: (camera_pose, target_pose)} of every linear solver, solved on first access."""
    return LinearSolutions(F, C, setup)


def _variance_factors(result, n_pixel_rows) -> np.ndarray:
    """Variance-component factors (3,) for the pixel rows, the correction priors' rotation rows and
    their translation rows: ``sqrt(sum r^2 / redundancy)`` of each group, the redundancy being the
    group's rows minus their share of the fitted unknowns (the trace of the hat matrix over the
    group; Foerstner's estimate). 1 when the assumed sigmas fit the residuals."""
    r = result.residuals_after
    h = getattr(result, "leverage", None)  # hat-matrix diagonal (the structured solve gives it)
    if h is None:
        ok = np.isfinite(np.diag(result.covariance))
        J = result.jacobian[:, ok]
        h = np.einsum("ij,jk,ik->i", J, result.covariance[np.ix_(ok, ok)], J)
    rows = np.arange(len(r))
    prior = rows >= n_pixel_rows
    groups = (~prior, prior & ((rows - n_pixel_rows) % 6 < 3), prior & ((rows - n_pixel_rows) % 6 >= 3))
    out = np.ones(3)
    for k, g in enumerate(groups):
        redundancy = g.sum() - h[g].sum()
        if redundancy > 0.5:
            out[k] = np.sqrt(np.sum(r[g] ** 2) / redundancy)
    return np.clip(out, 0.1, 10.0)


def _pixel_sigma(uv, T_camera_target, camera, X) -> float:
    """The corner noise per coordinate [px] from the per-image PnP residuals (6 pose unknowns per image)."""
    p = np.einsum("nij,pj->npi", T_camera_target[:, :3, :3], X) + T_camera_target[:, None, :3, 3]
    r = uv - camera.project(p.reshape(-1, 3)).pixels.reshape(uv.shape)
    ok = np.all(np.isfinite(r), axis=2)
    dof = max(2 * int(ok.sum()) - 6 * len(uv), 1)
    return max(float(np.sqrt(np.sum(r[ok] ** 2) / dof)), 1e-3)


def _pose_sigmas(result, block_label, T):
    """(sigma_rotation_deg (3,), sigma_translation_mm (3,)) of a frame from the result's covariance:
    the left step (w, v) moves the origin by ``-[t]x w + v``."""
    idx = [result.names.index(f"{block_label}.{c}") for c in ("rx", "ry", "rz", "x", "y", "z")]
    cov = result.covariance[np.ix_(idx, idx)]
    G = np.concatenate([-skew(T[:3, 3]), np.eye(3)], axis=1)
    cov_t = G @ cov @ G.T
    return np.degrees(np.sqrt(np.diag(cov[:3, :3]))), np.sqrt(np.diag(cov_t))


def refine_hand_eye(T_base_flange, image_points, target_points, camera: Camera, *, setup: str = "eye_in_hand",
                    method: str = "shah", refine_intrinsics=False, joints=None, robot=None,
                    joint_offsets: bool = False, loss: str = "linear", min_points: int = 6,
                    end_effector=None, robot_pose_sigma=(0.05, 0.01), pixel_sigma=None,
                    variance_rounds: int = 10, pnp=None) -> HandEyeRefinement:
    """The hand-eye transform refined on the reprojection error of all corners (module docstring).

    T_base_flange (N, 4, 4) [mm]: the controller's flange poses; image_points (N, P, 2) [px], NaN
    where a corner was not detected; target_points (P, 3) [mm] in the target frame; camera: a
    :class:`~robocal.camera.Camera`; setup: ``"eye_in_hand"`` | ``"eye_to_hand"``; method: the
    linear start (``tsai``, ``park``, ``daniilidis``, ``shah``); refine_intrinsics: False, True
    (every intrinsic and distortion parameter) or an iterable of names (``fx``, ``k1`` ...);
    joints (N, n) [rad | mm] + robot (a :class:`~robocal.kinematics.model.RobotModel`) +
    ``joint_offsets=True``: the links come from forward kinematics (the model's base frame,
    ``end_effector`` default its first, usually ``flange``) and the joint offsets are estimated;
    loss: ``"linear"``, ``"huber"`` or ``"cauchy"`` (robust per image, the image's corner rows and its
    flange-correction prior together; images weighted below 0.5 are dropped and listed in
    ``outliers``); images with fewer than ``min_points``
    corners are skipped; robot_pose_sigma: ``(mm, deg)`` 1-sigma of the robot's pose error per
    axis (its repeatability): each image gets a flange-pose correction with that Gaussian prior
    (errors in variables; ``None``: the flange poses are taken as exact; ``"estimate"``: the corner
    noise and the robot's rotation and translation noise estimated from the data by variance
    components, reported in ``noise_estimate``; ``"auto"``: the exact and the estimated model both
    fitted, the one predicting held-out images better kept, systematic disagreement in ``warnings``,
    :mod:`.pose_noise`; with ``joint_offsets`` the poses from forward kinematics are taken as exact); pixel_sigma [px]: the corner noise per coordinate
    (default: from the per-image PnP residuals); variance_rounds: at most this many re-solves of the
    variance-component estimate; pnp: optional ``(T_camera_target (N, 4, 4) [mm], reasons (N,))`` of
    :func:`~robocal.handeye.pnp.solve_pnp` on these images with this camera and ``min_points``
    (NaN poses and a reason for images without one), instead of solving it here (cross-validation
    reuses the full set's).

    Raises :class:`HandEyeError` naming the problem for mismatched counts, fewer than 3 usable
    images, pure translations or rotations about one axis only, or a robot model whose forward
    kinematics do not reproduce the flange poses.
    """
    if method not in LINEAR_METHODS:
        raise HandEyeError(f"unknown hand-eye method {method!r}; expected one of {', '.join(LINEAR_METHODS)}")
    if isinstance(robot_pose_sigma, str) and robot_pose_sigma == "auto" and joint_offsets:
        # the robot's error is modelled by its joint offsets; per-image corrections would compete with them
        robot_pose_sigma = None
    if isinstance(robot_pose_sigma, str) and robot_pose_sigma == "auto":
        from .pose_noise import refine_auto

        return refine_auto(refine_hand_eye, T_base_flange, image_points, target_points, camera, setup=setup,
                           joints=joints, method=method, refine_intrinsics=refine_intrinsics, robot=robot,
                           joint_offsets=joint_offsets, loss=loss, min_points=min_points, end_effector=end_effector)
    F_all, uv_all, X = _check_inputs(T_base_flange, image_points, target_points, setup)
    N = len(F_all)
    if pnp is None:
        C_all, _, reasons = solve_pnp(camera, X, uv_all, min_points=min_points)
    else:
        C_all, reasons = np.asarray(pnp[0], dtype=float), list(pnp[1])
        if C_all.shape != (N, 4, 4) or len(reasons) != N:
            raise HandEyeError(f"pnp: expected ({N}, 4, 4) poses and {N} reasons, got {C_all.shape} and {len(reasons)}")
    good = np.all(np.isfinite(C_all), axis=(1, 2))
    skipped = {int(i): reasons[i] or "no pose of the target found in this image" for i in np.flatnonzero(~good)}
    if good.sum() < 3:
        detail = "; ".join(f"image {i}: {r}" for i, r in skipped.items())
        raise HandEyeError(f"hand-eye calibration needs at least 3 usable images, got {int(good.sum())} of {N}"
                           + (f" ({detail})" if detail else ""))
    F, C, uv = F_all[good], C_all[good], uv_all[good]
    linear = _linear_solutions(F, C, setup)
    cam_pose0, target_pose0 = linear[method]

    eye_in_hand = setup == "eye_in_hand"
    cam = _intrinsics_block(camera, refine_intrinsics)
    cam_block = FramesBlock("camera_pose", cam_pose0, group="base")
    target_block = FramesBlock("target_pose", target_pose0, group="targets")
    blocks = [cam, cam_block, target_block]
    geometry = None
    if joint_offsets:
        q, ee, geometry = _joint_offsets_block(robot, joints, end_effector, F_all)
        blocks.append(geometry)
        flange = dict(model=robot, q=q[good], geometry=geometry, end_effector=ee)
    else:
        flange = dict(flange_poses=F)
    base_blocks = list(blocks)
    estimate = isinstance(robot_pose_sigma, str)
    if estimate and robot_pose_sigma != "estimate":
        raise HandEyeError(f"robot_pose_sigma: expected (mm, deg), None, 'estimate' or 'auto', got "
                           f"{robot_pose_sigma!r}")
    pose_sigma = (0.05, 0.01) if estimate else robot_pose_sigma
    sigma = None
    if pose_sigma is not None:
        sigma = _pixel_sigma(uv, C, camera, X) if pixel_sigma is None else float(pixel_sigma)

    structured = [True]  # the flange corrections eliminated per image (Schur complement) until that fails

    def build(pose_sigma, sigma):
        """The problem (and its blocks) for these noise levels."""
        blocks, extra, kw = list(base_blocks), [], dict(flange)
        if pose_sigma is not None:
            corrections, prior = _flange_corrections(pose_sigma, np.flatnonzero(good))
            blocks.append(corrections)
            extra.append(prior)
            kw["corrections"] = corrections
            kw["compact_corrections"] = structured[0]
        residual = FlangeReprojectionResidual(cam, cam_block, target_block, uv, X, invert=eye_in_hand, sigma=sigma,
                                              **kw)
        return Problem(blocks, [residual, *extra], n_poses=len(uv)), blocks

    def run(problem, blocks, sigma, pose_sigma, state0=None, auto_identifiable=True):
        """``(result, problem, blocks)``: the corrections eliminated per image when there are any
        (:func:`~robocal.calib.schur.solve_schur`, the same steps as the dense solve), else dense."""
        f_scale = None
        if loss != "linear" and sigma is not None:
            # weighted rows are ~unit: an image's norm is ~sqrt(its rows); twice that marks a bad image
            labels = problem.labels[:, 0]
            f_scale = 2.0 * float(np.sqrt(np.median(np.bincount(labels[labels >= 0]))))
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", NotConvergedWarning)
            if pose_sigma is not None and structured[0]:
                try:
                    return (solve_schur(problem, blocks[-1], loss=loss, f_scale=f_scale, state0=state0,
                                        auto_identifiable=auto_identifiable, frames_last=True), problem, blocks)
                except StructureError:
                    structured[0] = False
                    problem, blocks = build(pose_sigma, sigma)
            return (solve(problem, loss=loss, f_scale=f_scale, state0=state0, auto_identifiable=auto_identifiable),
                    problem, blocks)

    problem, blocks = build(pose_sigma, sigma)
    result, problem, blocks = run(problem, blocks, sigma, pose_sigma)
    noise = None
    if estimate:  # variance components: pixels, robot rotation, robot translation
        # the identifiable set does not change with the weights: analysed once (the rounds stay cheap)
        full_rank = not result.identifiability.dropped
        for _ in range(variance_rounds):
            factors = _variance_factors(result, problem.residual_blocks[0].n_rows)
            if np.all(np.abs(factors - 1.0) < 0.05):
                break
            sigma, pose_sigma = sigma * factors[0], (pose_sigma[0] * factors[2], pose_sigma[1] * factors[1])
            problem, blocks = build(pose_sigma, sigma)
            result, problem, blocks = run(problem, blocks, sigma, pose_sigma, result.state,
                                          auto_identifiable=not full_rank)
        noise = {"pixel_sigma_px": float(sigma), "robot_pose_sigma": tuple(float(v) for v in pose_sigma),
                 "converged": bool(np.all(np.abs(factors - 1.0) < 0.05))}

    state = dict(zip([b.name for b in blocks], result.state))
    cam_pose, target_pose = state["camera_pose"][0], state["target_pose"][0]
    value = state["cam"]
    refined = Camera(*value[:4], tuple(value[4:]), camera.model, camera.image_size)
    if joint_offsets:  # the links at the solution, from the reported joints
        F_all = robot.kinematics_with(np.asarray(joints, dtype=float), state["joint_offsets"], T_world_base=np.eye(4),
                                      end_effectors=[flange["end_effector"]])[0][:, 0]
    res_px, res_mm = _back_projection(refined, cam_pose, target_pose, F_all, eye_in_hand, good, uv_all, X)
    rms, per_image = rms_px(res_px)
    rms_mm, per_image_mm = rms_px(res_mm)
    s_rot, s_tr = _pose_sigmas(result, "camera_pose", cam_pose)
    offsets = None
    if geometry is not None:
        offsets = state["joint_offsets"][geometry.index] - geometry.initial[geometry.index]
    used = np.flatnonzero(good)
    outliers = {int(used[o["pose"]]): f"rejected by the {loss} loss: " + o["reason"] for o in result.outliers}
    msg = _message(result, method, int(good.sum()), N, rms, rms_mm, outliers, loss)
    return HandEyeRefinement(
        setup=setup, camera_pose=cam_pose, camera_pose_frame="flange" if eye_in_hand else "base",
        target_pose=target_pose, target_pose_frame="base" if eye_in_hand else "flange", camera=refined,
        residuals_px=res_px, residuals_mm=res_mm, rms_px=rms, per_image_rms_px=per_image,
        sigma_rotation_deg=s_rot, sigma_translation_mm=s_tr, covariance=result.covariance,
        variable_names=tuple(result.names), identifiability=result.identifiability, linear=linear,
        joint_offsets_rad=offsets, converged=bool(result.converged), message=msg, T_camera_target=C_all,
        skipped=skipped, rms_mm=rms_mm, per_image_rms_mm=per_image_mm,
        joint_offset_names=() if geometry is None else tuple(geometry.names), outliers=outliers,
        noise_estimate=noise)


def _intrinsics_block(camera, refine_intrinsics) -> CameraIntrinsics:
    """The camera's block ``cam``: nothing free, everything (True) or the named parameters."""
    cam = CameraIntrinsics(camera.intrinsics, camera.distortion, model=camera.model, name="cam")
    if refine_intrinsics is True:
        return cam.with_free(True)
    if refine_intrinsics is False or refine_intrinsics is None:
        return cam.with_free(False)
    return cam.with_free([n if n.startswith("cam.") else f"cam.{n}" for n in refine_intrinsics])


def _joint_offsets_block(robot, joints, end_effector, F_all) -> tuple:
    """``(q (N, n), end-effector index, RobotGeometry of the joint offsets)``, after checking that the
    model's forward kinematics at the joints reproduce the flange poses (to 20 mm)."""
    if joints is None or robot is None:
        raise HandEyeError("joint_offsets=True needs the joints (N, n) [rad] and the robot model")
    q = np.asarray(joints, dtype=float)
    if q.shape[0] != len(F_all):
        raise HandEyeError(f"{q.shape[0]} joint rows but {len(F_all)} images: they must pair one to one")
    ee = robot.end_effector_index(end_effector)
    F_fk = robot.kinematics_with(q, T_world_base=np.eye(4), end_effectors=[ee])[0][:, 0]
    dev = np.linalg.norm(F_fk[:, :3, 3] - F_all[:, :3, 3], axis=1)
    if dev.max() > 20.0:
        i = int(np.argmax(dev))
        raise HandEyeError(f"the robot model's forward kinematics at the joints differ from T_base_flange by "
                           f"{dev[i]:.1f} mm at image {i}: wrong robot file, joints not in radians, or the "
                           "poses are not flange poses in the robot base")
    return q, ee, RobotGeometry(robot, joint_offset_names(robot), name="joint_offsets")


def _flange_corrections(robot_pose_sigma, images) -> tuple:
    """``(FramesBlock of one flange correction per used image, its PosePriorResidual)``; the prior's
    rows belong to their image, so a robust loss weighs a wrong robot reading with its image."""
    s_mm, s_deg = (float(v) for v in robot_pose_sigma)
    if not (s_mm > 0 and s_deg > 0):
        raise HandEyeError(f"robot_pose_sigma: expected positive (mm, deg), got {robot_pose_sigma!r}")
    n = len(images)
    block = FramesBlock("flange_error", np.tile(np.eye(4), (n, 1, 1)), group="corrections",
                        labels=[f"flange_error{i}" for i in images])
    prior = PosePriorResidual(block, np.tile([np.radians(s_deg)] * 3 + [s_mm] * 3, n), np.repeat(np.arange(n), 6))
    return block, prior


def _back_projection(camera, cam_pose, target_pose, F_all, eye_in_hand, good, uv_all, X) -> tuple:
    """``(residuals_px, residuals_mm)`` (N, P, 2) of every image with the flange poses as given:
    the target in the camera is ``C^-1 M_i T``; NaN for skipped images."""
    M = invert_transforms(F_all) if eye_in_hand else F_all
    T_ct = invert_transforms(cam_pose)[None] @ M @ target_pose[None]
    T_ct[~good] = np.nan
    p = np.einsum("nij,pj->npi", T_ct[:, :3, :3], X) + T_ct[:, None, :3, 3]
    res_px = uv_all - camera.project(p.reshape(-1, 3)).pixels.reshape(uv_all.shape)
    return res_px, target_plane_residuals(camera, T_ct, uv_all, X)


def _message(result, method, n_used, N, rms, rms_mm, outliers, loss) -> str:
    """One line: convergence, images, RMS, rejected images, what is not identifiable and why."""
    msg = (f"{'converged' if result.converged else 'NOT CONVERGED (' + result.reason + ')'} after "
           f"{result.iterations} iterations from the {method} start; {n_used} of {N} images, "
           f"RMS {rms:.3f} px, {rms_mm:.4f} mm on the target")
    if outliers:
        msg += f"; image(s) {', '.join(map(str, outliers))} rejected as outliers ({loss} loss)"
    if result.identifiability.dropped:
        msg += "; not identifiable from these poses (held at their start): " + "; ".join(
            f"{d['name']} ({d['why']})" for d in result.identifiability.dropped)
    return msg


def rotation_error_deg(T, T_ref) -> float:
    """The angle [deg] of ``R R_ref^T`` (for tests and studies)."""
    return float(np.degrees(np.linalg.norm(so3_log((T[:3, :3] @ T_ref[:3, :3].T)[None])[0])))
