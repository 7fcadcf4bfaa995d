"""``robocal self-calibrate``: joint offsets from a robot's own camera images (issue 15).

Inputs: the robot file, an image folder, a ``robocal-joint-log/1`` joint log and a
``robocal-frames/1`` frames file (:mod:`robocal.io.joint_log_files`), a board spec, the end
effector(s) that may hold the board (several: each image is assigned to the nearest one,
:func:`robocal.handeye.self_calibration.assign_carriers`), the camera (a camera file, else
calibrated on the same images). Steps, no manual ones:

1. every image listed in the frames file gets its joints by time stamp (``tolerance`` [s],
   ``nearest`` or ``interpolate``); unmatched images are reported with the reason;
2. the board is detected in the matched images; images without the full board, unreadable ones and
   images of another size than the first are skipped, each with its reason;
3. :func:`robocal.handeye.self_calibration.solve_self_calibration` over all chains at once;
4. outputs (all or nothing): ``robot.toml`` (the calibrated robot file), ``self_calibration.json``
   and ``report.html`` (back-projection overlays, per-image RMS).

Bad input raises ``ValueError`` naming the file and what was expected: a log that matches no image,
a board never fully visible, a frames file naming images that are not in the folder.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from ...calib.outputs import json_ready
from ...handeye import HandEyeError
from ...handeye.gate import self_calibration_verdict
from ...io.boards import parse_board
from ...io.camera_files import read_camera
from ...io.capture_times import match_capture_times
from ...io.detection import detect_board
from ...io.images import read_image_gray
from ...io.joint_log_files import read_frames, read_joint_log_file
from ...robots import load_robot
from ...robots.writer import save_robot
from .camera_common import DetectedSet, identifiability_lines, overlay_figures
from ..convergence import Convergence
from ..outputs import check_output_folder, staged_outputs
from .self_calibration_gate import clock_reasons, estimate_joint_noise

__all__ = ["self_calibrate", "SELF_CALIBRATION_OUTPUTS"]

SELF_CALIBRATION_OUTPUTS = ["robot.toml", "self_calibration.json", "report.html"]


def _detect(paths, board, progress):
    """(image_points (N, P, 2), reasons (N,), image size) with per-image reasons."""
    P = board.n_points
    uv = np.full((len(paths), P, 2), np.nan)
    reasons, size = [None] * len(paths), None
    for i, p in enumerate(paths):
        if p is None:
            continue
        try:
            img = read_image_gray(p)
        except (OSError, ValueError) as exc:
            reasons[i] = f"unreadable image: {exc}"
            continue
        h, w = img.shape[:2]
        if size is None:
            size = (w, h)
        if (w, h) != size:
            reasons[i] = f"image is {w}x{h} px, the first image is {size[0]}x{size[1]} px (one camera, one size)"
        else:
            det = detect_board(img, board, name=p.name, min_points=P)
            if det.skip_reason is not None:
                reasons[i] = "board not fully visible: " + det.skip_reason
            else:
                uv[i] = det.image_points
        if progress is not None:
            progress(i + 1, len(paths), f"{p.name}: " + (reasons[i] or f"{P} corners"))
    return uv, reasons, size


def self_calibrate(robot, *, images, joints, frames, board: str, camera_end_effector: str, board_on,
                   camera_file=None, tolerance: float = 0.05, match: str = "nearest", link_parameters=(),
                   refine_intrinsics: bool = False, joint_noise_deg: float | None = None, out_dir=None,
                   overwrite: bool = False, progress=None, allow_unconverged: bool = False,
                   force: bool = False) -> dict:
    """Run the pipeline (module docstring); returns the JSON summary (``convergence``: of the camera
    and self-calibration fits; robot.toml is not written when one did not converge, unless
    ``allow_unconverged``).

    robot: shipped name or robot file; images: folder; joints: the joint log; frames: the frames
    file; board: board spec; camera_end_effector: the end effector carrying the camera;
    board_on: the end effector holding the board (``"world"`` for a fixed board), or a sequence of
    them (each image is assigned to the nearest); tolerance [s]; match: ``nearest`` | ``interpolate``; progress(i, n, text) per image.

    Sanity gate (:func:`robocal.handeye.gate.self_calibration_verdict`, with the clock diagnosis of
    :mod:`.self_calibration_gate`): ``status``/``reasons``/``sanity_checks`` in the summary; a
    failed or non-converged result writes no ``robot.toml`` unless ``force``. joint_noise_deg
    ``None`` (default): the joint-reading noise is estimated (:func:`.self_calibration_gate.estimate_joint_noise`).
    """
    from ...handeye.camera_calibration import calibrate_camera
    from ...handeye.self_calibration import assign_carriers, solve_self_calibration

    model = load_robot(robot)
    b = parse_board(board)
    if out_dir is not None:
        check_output_folder(out_dir, SELF_CALIBRATION_OUTPUTS, {"ROBOT": robot, "--images": images, "--joints": joints,
                                                                "--frames": frames, "--camera": camera_file}, overwrite)
    carriers = [board_on] if isinstance(board_on, str) else list(board_on)
    if not carriers:
        raise ValueError("say which end effector holds the board (--board-on; 'world' for a fixed board)")
    fr = read_frames(frames)
    names, t_img = list(fr.images), np.asarray(fr.times, dtype=float)
    folder = Path(images)
    if not folder.is_dir():
        raise ValueError(f"{folder}: not an image folder")
    missing = [n for n in names if not (folder / n).is_file()]
    if missing:
        raise ValueError(f"{frames}: {len(missing)} listed image(s) not in {folder}: {', '.join(missing[:5])}")
    log = read_joint_log_file(joints, robot=model)
    t_log, q_log = log.times, log.joints
    q, dt, reasons = match_capture_times(t_img, t_log, q_log, tolerance=tolerance, mode=match)
    matched = [r is None for r in reasons]
    if not any(matched):
        raise ValueError(f"{joints}: no joint reading within {tolerance:g} s of any capture time in {frames} "
                         f"(images {t_img.min():.3f}..{t_img.max():.3f} s, log {t_log.min():.3f}..{t_log.max():.3f} s): "
                         "different clocks or the wrong log?")
    paths = [folder / n if ok else None for n, ok in zip(names, matched)]
    uv, det_reasons, size = _detect(paths, b, progress)
    reasons = [r or d for r, d in zip(reasons, det_reasons)]
    used = np.array([r is None for r in reasons])
    if not used.any():
        raise ValueError(f"{folder}: the board {b.spec} is not fully visible in any matched image "
                         f"({sum(matched)} matched of {len(names)})")
    X = b.object_points()
    camera_source = "given"
    fits = []
    if camera_file is not None:
        camera = read_camera(camera_file)
    else:
        intrinsics = calibrate_camera(uv[used], X, size, min_points=b.min_points)
        camera = intrinsics.camera
        camera_source = "calibrated on the same images"
        fits.append(("camera intrinsics", intrinsics))
    on = [carriers[0]] * len(names)
    if len(carriers) > 1:
        idx = np.flatnonzero(used)
        assigned, _, why = assign_carriers(model, q[idx], uv[idx], X, camera, carriers,
                                           camera_end_effector=camera_end_effector, min_points=b.min_points)
        for k, i in enumerate(idx):
            on[i], reasons[i] = (assigned[k], None) if assigned[k] else (None, why[k])
        used = np.array([r is None for r in reasons])
        if used.sum() < 3:
            why = "; ".join(f"{names[i]}: {reasons[i]}" for i in idx[:3])
            raise ValueError(f"only {int(used.sum())} of {len(idx)} images could be given to a board carrier "
                             f"({', '.join(carriers)}) at their joint readings ({why}): likely the images are paired "
                             f"with the wrong joint readings (a camera clock offset, permuted frame times in {frames}, "
                             "a joint log of another run) or the wrong --board-on")
    idx = np.flatnonzero(used)
    def solve_with(noise):
        return solve_self_calibration(model, q[idx], uv[idx], X, camera, [on[i] for i in idx],
                                      camera_end_effector=camera_end_effector, link_parameters=link_parameters,
                                      refine_intrinsics=refine_intrinsics, min_points=b.min_points,
                                      joint_noise_deg=noise)

    noise_source = "given"
    if joint_noise_deg is None:
        joint_noise_deg, res, noise_source = estimate_joint_noise(solve_with)
    else:
        res = solve_with(joint_noise_deg)
    convergence = Convergence.of(fits + [("self-calibration", res)],
                                 "better joint offsets to start from, more images or fewer --link-parameter")
    res_px = np.full_like(uv, np.nan)
    res_px[idx] = res.residuals_px
    for k, r in res.skipped.items():
        reasons[idx[k]] = r
    rows = []
    for i, n in enumerate(names):
        r = res_px[i]
        ok = np.isfinite(r[:, 0])
        rows.append({"name": n, "time_s": float(t_img[i]), "board_on": on[i], "used": reasons[i] is None,
                     "skip_reason": reasons[i], "match_dt_s": None if not matched[i] else float(dt[i]),
                     "n_points": int(np.isfinite(uv[i, :, 0]).sum()),
                     "rms_px": float(np.sqrt(np.mean(np.sum(r[ok] ** 2, 1)))) if ok.any() else None})
    summary = {
        "format": "robocal-self-calibration/1", "robot": model.name, "board": b.to_dict(),
        "camera_end_effector": camera_end_effector, "match": {"mode": match, "tolerance_s": tolerance},
        "camera": {"fx": res.camera.fx, "fy": res.camera.fy, "cx": res.camera.cx, "cy": res.camera.cy,
                   "distortion": list(res.camera.distortion), "model": res.camera.model, "source": camera_source},
        "joint_offsets": [{"name": n, "value": float(v), "sigma": float(s),
                           "unit": model.params.units[model.params.names.index(n)]}
                          for n, v, s in zip(res.joint_offset_names, res.joint_offsets, res.joint_offset_sigma)],
        "joint_report": res.joint_report,
        "camera_mount": {"matrix": res.camera_mount.tolist(), "frame": camera_end_effector},
        "boards": {c: {"matrix": T.tolist(), "frame": c} for c, T in res.boards.items()},
        "reprojection_rms_px": res.rms_px, "pixel_sigma_px": res.pixel_sigma,
        "variance_factor": res.variance_factor, "joint_noise_deg": joint_noise_deg,
        "joint_noise_source": noise_source,
        "n_images": len(names), "n_images_used": int(used.sum() - len(res.skipped)),
        "converged": res.converged, "message": res.message, "convergence": convergence.as_dict(),
        "identifiability": identifiability_lines(res.identifiability), "images": rows,
        "units": "mm, rad (joint offsets in the robot file's parameter units: rad or mm)",
    }
    rad = [j for j in summary["joint_offsets"] if j["unit"] == "rad" and j["sigma"] is not None]
    verdict = self_calibration_verdict(variance_factor=res.variance_factor, pixel_sigma_px=res.pixel_sigma,
                                       rms_px=res.rms_px, joint_noise_deg=joint_noise_deg,
                                       joint_noise_estimated=noise_source.startswith("estimated"),
                                       offsets_deg={j["name"]: float(np.degrees(j["value"])) for j in rad})
    checks, reasons_gate = dict(verdict.checks), list(verdict.reasons)
    if not verdict.ok:
        used_now = [i for i in idx if reasons[i] is None]
        try:  # the diagnosis never hides the verdict
            extra, more = clock_reasons(model=model, t_img=t_img, t_log=t_log, q_log=q_log, idx=used_now,
                                        image_points=uv, target_points=X, camera=camera,
                                        carriers=[on[i] for i in used_now], camera_end_effector=camera_end_effector,
                                        tolerance=tolerance, match=match, min_points=b.min_points)
        except (ValueError, HandEyeError, KeyError) as exc:
            extra, more = [], {"pairing_diagnosis": {"passed": None, "error": str(exc)}}
        reasons_gate += extra
        checks.update(more)
    summary["status"] = "ok" if verdict.ok else "failed"
    summary["reasons"], summary["sanity_checks"] = reasons_gate, checks
    write_robot = (verdict.ok or force) and convergence.may_write_model(allow_unconverged)
    if out_dir is not None:
        detected = DetectedSet(paths=tuple(folder / n for n in names), names=tuple(names), image_points=uv,
                               image_size=size, skip_reasons=tuple(reasons), board=b)
        per_image = np.array([np.nan if r["rms_px"] is None else r["rms_px"] for r in rows])
        overlays = overlay_figures(detected, uv - res_px, per_image)
        from ...report.camera_report import write_camera_report

        with staged_outputs(out_dir, SELF_CALIBRATION_OUTPUTS, overwrite=overwrite) as stage:
            if write_robot:
                save_robot(res.model, stage / "robot.toml", comment=f"self-calibrated from {len(idx)} images"
                           + ("" if verdict.ok and res.converged else "; FAILED its gates or did not converge, "
                              "written because of --force / --allow-unconverged"))
            elif not convergence.may_write_model(allow_unconverged):
                summary["notes"] = [convergence.skipped_note("robot.toml")]
            (stage / "self_calibration.json").write_text(json.dumps(json_ready(summary), indent=1) + "\n")
            write_camera_report(stage / "report.html", {**summary, "_residuals_px": res_px},
                                title=f"Camera self-calibration ({model.name})", overlays=overlays)
        summary["outputs"] = {n: str(Path(out_dir) / n) for n in SELF_CALIBRATION_OUTPUTS
                              if n != "robot.toml" or write_robot}
    return json_ready(summary)
