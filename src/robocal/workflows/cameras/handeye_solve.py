"""``robocal handeye solve``: the hand-eye transform from images and flange poses (issue 14 item 7).

Inputs (the command line: ``robocal handeye solve [ROBOT] DATA``, docs/cli.md), either
* ``IMAGES_DIR --poses POSES.csv --board SPEC``: a flange-pose CSV in a named convention paired
  by name with the images (:mod:`robocal.io.image_poses`), or
* ``ROBOT IMAGES_DIR --joints JOINTS.csv --board SPEC``: the flange poses from the robot's joints, or
* ``path/to/cal_data.yaml``: the ROS-Industrial layout (:mod:`robocal.io.ros_calibration`: board,
  intrinsics, set-up from ``static_camera``).

The camera comes from ``--camera FILE``, else the layout's intrinsics, else a calibration on the
same images (:func:`robocal.handeye.camera_calibration.calibrate_camera`). The board is detected in
every image; :func:`robocal.handeye.refine.refine_hand_eye` starts from a linear solution
(``--method``) and refines over all corners. Outputs, all or nothing:

* ``handeye.json``: ``camera_pose {frame, position_mm, rotation_vector_deg, quaternion_xyzw,
  matrix, sigma_*}``, ``target_pose``, ``reprojection_rms_px`` (the solver's), ``backprojection_rms_px``
  (the target projected through the *reported* flange poses, no per-image corrections), per-image
  rows with skip reasons, identifiability findings, the linear solutions side by side;
* ``handeye.yaml``: the camera pose as a ROS transform (metres, quaternion x, y, z, w);
* ``report.html``: back-projection overlays, per-image RMS, residuals.
"""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

import numpy as np

from ...calib.outputs import json_ready
from ...handeye import HandEyeError
from ...io.boards import parse_board
from ...io.camera_files import read_camera
from ...io.image_poses import pair_images_with_labels, pair_images_with_poses
from ...io.programs.joint_table import read_joint_program
from ...io.ros_calibration import read_cal_data
from ...report.camera_report import write_camera_report
from ...robots import load_robot
from ...transforms import rotation_angle
from .camera_calibrate import camera_summary
from .camera_common import (
    POSE_CONVENTION,
    backprojection,
    detect_set,
    identifiability_lines,
    image_rows,
    overlay_figures,
    pose_dict,
    ros_transform_yaml,
)
from ..convergence import Convergence
from .handeye_gate import chain_T_camera_target, handeye_gate, pairing_causes
from ..outputs import check_output_folder, staged_outputs

__all__ = ["solve_handeye", "HANDEYE_OUTPUTS", "chain_T_camera_target"]

HANDEYE_OUTPUTS = ["handeye.json", "handeye.yaml", "report.html"]
SETUPS = ("eye_in_hand", "eye_to_hand")


def _rms(residuals) -> float:
    r = residuals.reshape(-1, 2)
    r = r[np.isfinite(r).all(axis=1)]
    return float(np.sqrt(np.mean(np.sum(r ** 2, axis=1)))) if len(r) else float("nan")


def _intrinsics_sigma(result) -> tuple:
    """({short name: 1-sigma} of the refined intrinsics, {term: (value, sigma)} of the distortion
    terms whose 1-sigma exceeds their magnitude); empty when the intrinsics were held."""
    from ...handeye.distortion_models import undetermined_terms

    names = list(getattr(result, "variable_names", ()) or ())
    cov = getattr(result, "covariance", None)
    sigma = {}
    for i, n in enumerate(names):
        if n.startswith("cam.") and cov is not None and np.isfinite(cov[i, i]):
            sigma[n.split(".", 1)[1]] = float(np.sqrt(cov[i, i]))
    if not sigma:
        return {}, {}
    return sigma, undetermined_terms(camera_summary(result.camera)["parameters"], sigma)


def _sigma_json(robot_pose_sigma, noise):
    """How the flange poses were treated, for the JSON."""
    if robot_pose_sigma is None:
        return "exact flange poses"
    if robot_pose_sigma == "default":
        return "refine_hand_eye default"
    if isinstance(robot_pose_sigma, str):
        out = {"mode": robot_pose_sigma}
        for k, v in (noise or {}).items():
            if k != "other_camera_pose":
                out[k] = v
        return out
    return {"mm": robot_pose_sigma[0], "deg": robot_pose_sigma[1]}


def _sigma_text(robot_pose_sigma, noise) -> str:
    """One line: how the flange poses were treated and why."""
    if robot_pose_sigma is None:
        return "taken as exact (--exact-poses)"
    if robot_pose_sigma == "default":
        return "refine_hand_eye's default prior"
    if isinstance(robot_pose_sigma, tuple):
        return f"corrected per image under a {robot_pose_sigma[0]:g} mm / {robot_pose_sigma[1]:g} deg prior"
    noise = noise or {}
    est = noise.get("estimated", noise)
    level = ""
    if est.get("robot_pose_sigma") is not None:
        level = (f"noise estimated from the data {est['robot_pose_sigma'][0]:.3g} mm / {est['robot_pose_sigma'][1]:.3g}"
                 f" deg, corners {est['pixel_sigma_px']:.3g} px")
    if robot_pose_sigma == "estimate":
        return "corrected per image, " + level
    cv = noise.get("cv_rms_px", {})
    choice = noise.get("choice")
    how = "taken as exact" if choice == "exact" else "corrected per image"
    if noise.get("reason"):
        return f"{how} (auto: {noise['reason']})"
    if not np.isfinite(cv.get("exact", float("nan"))):
        return f"{how} (auto: too few images to cross-validate the noise model)"
    return (f"{how} (auto: held-out RMS {cv.get('exact', float('nan')):.3f} px exact vs "
            f"{cv.get('estimated', float('nan')):.3f} px with the {level})")


def _inputs(cal_data, poses, images, board, setup, camera_file, joints_file=None, robot=None, length_unit=None):
    """(paths, labels, T_base_flange, board, blob_settings, camera or None, setup, source, homography
    threshold, joints or None, robot model or None)."""
    if cal_data is not None:
        if poses is not None or images is not None or joints_file is not None:
            raise ValueError("give either cal_data.yaml or --poses/--joints with the images' folder, not both")
        d = read_cal_data(cal_data)
        b = parse_board(board) if board else d.board
        if setup is not None and setup != d.setup:
            raise ValueError(f"{d.path}: static_camera says {d.setup}, but {setup} was asked for; drop the option "
                             "or fix the file")
        cam = read_camera(camera_file) if camera_file else d.camera
        return (d.image_paths, d.labels, d.T_base_flange, b, d.blob_settings, cam, d.setup, str(d.path),
                d.homography_threshold, None, None)
    if (poses is None) == (joints_file is None) or images is None or board is None:
        raise ValueError("need --poses POSES.csv or ROBOT and --joints JOINTS.csv, with the images' folder and "
                         "--board SPEC (or a cal_data.yaml)")
    b = parse_board(board)
    cam = read_camera(camera_file) if camera_file else None
    setup = setup or "eye_in_hand"
    if poses is not None:
        pairs = pair_images_with_poses(images, poses, length_unit)
        return (pairs.image_paths, pairs.labels, pairs.T_base_flange, b, None, cam, setup, f"{poses} + {images}",
                None, None, None)
    if robot is None:
        raise ValueError("--joints needs ROBOT (a shipped robot name or a robot file)")
    model = load_robot(robot)
    program = read_joint_program(joints_file, model)
    paths, idx = pair_images_with_labels(images, program.names, joints_file)
    q = program.joints[idx]
    F = model.kinematics_with(q, T_world_base=np.eye(4), end_effectors=[0])[0][:, 0]
    return (paths, tuple(program.names[i] for i in idx), F, b, None, cam, setup, f"{joints_file} ({model.name}) + "
            f"{images}", None, q, model)


def solve_handeye(*, cal_data=None, poses=None, images=None, board: str | None = None, setup: str | None = None,
                  method: str = "shah", camera_file=None, refine_intrinsics: bool = False,
                  robot_pose_sigma="auto", homography_threshold=None, joints=None, robot=None,
                  joint_offsets: bool = False, loss: str = "linear", out_dir=None, overwrite: bool = False, progress=None,
                  allow_unconverged: bool = False, force: bool = False, length_unit: str | None = None) -> dict:
    """Solve and (with ``out_dir``) write the outputs (module docstring). Returns the JSON dict.

    robot_pose_sigma: ``(mm, deg)`` the robot's pose error per axis for the errors-in-variables
    refinement, ``None`` to take the flange poses as exact (as ROS-Industrial's calibration does),
    ``"estimate"`` (variance components) or ``"auto"`` (the exact or the estimated model, whichever
    predicts held-out images better; :mod:`robocal.handeye.pose_noise`), ``"default"`` for
    :func:`~robocal.handeye.refine.refine_hand_eye`'s default prior.
    homography_threshold [px]: skip images whose detections one homography cannot explain
    (default: the cal_data.yaml value, else no check). joints: a ``robocal-program/1`` joint table
    (point names = image names) and robot (shipped name or robot file) instead of ``poses``: the
    flange poses are the robot file's forward kinematics; ``joint_offsets`` also estimates the
    robot's joint zero offsets. loss: ``"linear"``, or ``"huber"`` / ``"cauchy"`` to reject whole
    images that do not fit (listed per image as ``outlier``). The sanity gate
    (:mod:`.handeye_gate`) puts ``status`` and ``reasons`` into the summary; a failed result writes
    no ``handeye.yaml`` unless ``force``. A fit that did not converge (camera or hand-eye;
    ``convergence`` in the JSON) writes no handeye.yaml unless ``allow_unconverged``. length_unit: "m" | "mm" of a 4 x 4
    matrix pose file (:mod:`robocal.io.matrix_poses`) that does not declare it."""
    from ...handeye.camera_calibration import calibrate_camera
    from ...handeye.refine import refine_hand_eye

    if setup is not None and setup not in SETUPS:
        raise ValueError(f"setup must be one of {', '.join(SETUPS)}, got {setup!r}")
    paths, labels, F, b, blobs, camera, setup, source, file_threshold, q, model = _inputs(
        cal_data, poses, images, board, setup, camera_file, joints, robot, length_unit)
    if joint_offsets and q is None:
        raise ValueError("--joint-offsets needs ROBOT and --joints JOINTS.csv")
    threshold = file_threshold if homography_threshold is None else homography_threshold
    if out_dir is not None:
        check_output_folder(out_dir, HANDEYE_OUTPUTS, {"the cal_data.yaml": cal_data, "--poses": poses,
                                                       "the images": images, "--joints": joints, "ROBOT": robot,
                                                       "--camera": camera_file}, overwrite)
    detected = detect_set(paths, b, blob_settings=blobs, homography_threshold=threshold, progress=progress)
    detected.require(3, "hand-eye calibration")
    used = detected.used
    X = b.object_points()
    uv = detected.image_points[used]
    camera_source = "given"
    fits = []
    camera_given = camera is not None
    if camera is None:
        cal = calibrate_camera(uv, X, detected.image_size, min_points=b.min_points)
        camera, camera_source = cal.camera, "calibrated on the same images"
        fits.append(("camera intrinsics", cal))
    if camera.image_size is None:
        camera = replace(camera, image_size=tuple(int(v) for v in detected.image_size))
    elif tuple(camera.image_size) != tuple(detected.image_size):
        raise ValueError(f"the camera is for {camera.image_size[0]}x{camera.image_size[1]} px images, the images are "
                         f"{detected.image_size[0]}x{detected.image_size[1]} px")
    extra = {} if robot_pose_sigma == "default" else {"robot_pose_sigma": robot_pose_sigma}
    if q is not None:
        extra.update(joints=q[used], robot=model, joint_offsets=bool(joint_offsets))
    idx_used = np.flatnonzero(used)
    try:
        result = refine_hand_eye(F[used], uv, X, camera, setup=setup, method=method,
                                 refine_intrinsics=refine_intrinsics, min_points=b.min_points, loss=loss, **extra)
    except np.linalg.LinAlgError as exc:  # diverged on data that describe no single camera: say why
        causes = pairing_causes(camera=camera, T_base_flange=F, used=used, image_points=detected.image_points,
                                target_points=X, setup=setup, names=detected.names, labels=labels,
                                poses_file=poses if cal_data is None and joints is None else None,
                                camera_given=camera_given, image_size=detected.image_size, min_points=b.min_points)
        raise HandEyeError(f"the hand-eye refinement diverged ({exc}): the flange poses and the images do not "
                           "describe one camera on one robot" + ("; " + "; ".join(causes) if causes else "")) from None
    outliers = {int(idx_used[k]): r for k, r in (getattr(result, "outliers", None) or {}).items()}
    solver_skips = {int(idx_used[k]): r for k, r in (getattr(result, "skipped", None) or {}).items()}
    N = len(used)
    res_px = np.full(detected.image_points.shape, np.nan)
    res_px[used] = result.residuals_px
    res_mm = np.full(detected.image_points.shape, np.nan)
    res_mm[used] = result.residuals_mm
    T_ct = chain_T_camera_target(setup, result.camera_pose, result.target_pose, F)
    projected, back = backprojection(result.camera, T_ct, X, detected.image_points)
    back[~used] = np.nan
    for i in solver_skips:
        back[i] = np.nan
        res_px[i] = np.nan
        res_mm[i] = np.nan
    rows = image_rows(detected, res_px, res_mm, solver_skips)
    for i, r in enumerate(rows):
        r["label"] = labels[i]
        r["backprojection_rms_px"] = None if not r["used"] else _rms(back[i])
        r["outlier"] = outliers.get(i)
    linear = {}
    for m, (cam_pose, target_pose) in result.linear.items():
        _, lin_back = backprojection(result.camera, chain_T_camera_target(setup, cam_pose, target_pose, F), X,
                                     detected.image_points)
        lin_back[[not r["used"] for r in rows]] = np.nan
        d = pose_dict(cam_pose, result.camera_pose_frame)
        d["difference_position_mm"] = float(np.linalg.norm(cam_pose[:3, 3] - result.camera_pose[:3, 3]))
        d["difference_rotation_deg"] = float(np.degrees(rotation_angle(cam_pose[:3, :3].T @ result.camera_pose[:3, :3])))
        d["reprojection_rms_px"] = _rms(lin_back)
        linear[m] = d
    cam_sigma, not_determined = _intrinsics_sigma(result)
    findings = identifiability_lines(result.identifiability)
    if not_determined:
        findings = [ln for ln in findings if not ln.startswith("every estimated parameter")]
        findings += [f"{k}: not determined by these images ({v:+.4g} +- {sg:.3g}, the 1-sigma exceeds the value)"
                     for k, (v, sg) in not_determined.items()]
    summary = {
        "format": "robocal-handeye/1", "setup": setup, "source": source, "board": b.to_dict(), "method": method,
        "loss": loss,
        "robot_pose_sigma": _sigma_json(robot_pose_sigma, result.noise_estimate),
        "robot_pose_sigma_text": _sigma_text(robot_pose_sigma, result.noise_estimate),
        "warnings": list(getattr(result, "warnings", ()) or ()),
        "homography_threshold_px": threshold,
        "convention": POSE_CONVENTION,
        "camera_pose": pose_dict(result.camera_pose, result.camera_pose_frame, result.sigma_translation_mm,
                                 result.sigma_rotation_deg),
        "target_pose": pose_dict(result.target_pose, result.target_pose_frame),
        "reprojection_rms_px": float(result.rms_px),
        "backprojection_rms_px": _rms(back),
        "reprojection_rms_mm": float(getattr(result, "rms_mm", float("nan"))),
        "n_images": N, "n_images_used": sum(r["used"] for r in rows),
        "n_corners": int(np.count_nonzero(np.isfinite(back[..., 0]))),
        "camera": {**camera_summary(result.camera, cam_sigma), "source": camera_source,
                   "refined": bool(refine_intrinsics)},
        "not_determined": {k: {"value": v, "sigma": sg} for k, (v, sg) in not_determined.items()},
        "converged": bool(result.converged), "message": result.message,
        "convergence": Convergence.of(fits + [("hand-eye refinement", result)],
                                      "another --method to start from, --loss huber against bad images, or more "
                                      "images with larger rotations between them").as_dict(),
        "identifiability": findings,
        "linear": linear, "images": rows,
    }
    verdict = handeye_gate(camera=camera, result=result, T_base_flange=F, used=used,
                           image_points=detected.image_points, target_points=X, setup=setup, method=method,
                           names=detected.names, labels=labels,
                           back_rms_px=_rms(np.delete(back, list(outliers), axis=0)),
                           per_image_back_px=[float("nan") if i in outliers else _rms(back[i])
                                              for i in np.flatnonzero(used)], exclude=tuple(outliers),
                           poses_file=poses if cal_data is None and joints is None else None,
                           camera_given=camera_given, image_size=detected.image_size, min_points=b.min_points)
    summary["status"], summary["reasons"], summary["sanity_checks"] = verdict.status, list(verdict.reasons), \
        verdict.checks
    if joint_offsets and getattr(result, "joint_offsets_rad", None) is not None:
        names = getattr(result, "joint_offset_names", ()) or [f"joint{k + 1}" for k in range(len(result.joint_offsets_rad))]
        summary["joint_offsets_deg"] = {n: float(np.degrees(v)) for n, v in zip(names, result.joint_offsets_rad)}
    if out_dir is not None:
        per_image = np.array([np.nan if r["backprojection_rms_px"] is None else r["backprojection_rms_px"] for r in rows])
        overlays = overlay_figures(detected, projected, per_image)
        parent, child = ("tool0", "camera") if setup == "eye_in_hand" else ("base_link", "camera")
        with staged_outputs(out_dir, HANDEYE_OUTPUTS, overwrite=overwrite) as stage:
            (stage / "handeye.json").write_text(json.dumps(json_ready(summary), indent=1) + "\n")
            write_yaml = (verdict.ok or force) and \
                Convergence.from_dict(summary["convergence"]).may_write_model(allow_unconverged)
            if write_yaml:
                (stage / "handeye.yaml").write_text(ros_transform_yaml(
                    result.camera_pose, parent, child,
                    f"robocal hand-eye ({setup}): the camera's optical frame in the robot's "
                    f"{result.camera_pose_frame} frame\nreprojection RMS {result.rms_px:.3f} px"
                    + ("" if verdict.ok else "\nFAILED the sanity gates; written because of --force")))
            write_camera_report(stage / "report.html", {**summary, "_residuals_px": back},
                                title=f"Hand-eye calibration ({setup})", overlays=overlays)
        summary["outputs"] = {n: str(Path(out_dir) / n) for n in HANDEYE_OUTPUTS if (Path(out_dir) / n).exists()}
    return json_ready(summary)
