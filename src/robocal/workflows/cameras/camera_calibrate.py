"""``robocal camera calibrate IMAGES_DIR --board ...``: intrinsics and distortion from images of a
board (issue 14 item 7). Detection (:mod:`robocal.io.detection`), then
:func:`robocal.handeye.camera_calibration.calibrate_camera`; outputs, all or nothing:

* ``camera.json`` (robocal-camera/1) and ``camera.yaml`` (ROS camera_info) of the calibrated camera;
* ``camera_calibration.json``: the summary (RMS, 1-sigma of every parameter, per-image rows with
  skip reasons, identifiability findings);
* ``report.html``: per-image RMS, residuals, back-projection overlays.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from ...calib.outputs import json_ready
from ...io.boards import parse_board
from ...io.camera_files import write_camera_json, write_camera_ros_yaml
from ...io.images import list_images
from ...report.camera_report import write_camera_report
from .camera_common import backprojection, detect_set, identifiability_lines, image_rows, overlay_figures
from ..convergence import Convergence
from ..outputs import check_output_folder, staged_outputs

__all__ = ["calibrate_camera_images", "CAMERA_OUTPUTS", "camera_summary"]

CAMERA_OUTPUTS = ["camera.json", "camera.yaml", "camera_calibration.json", "report.html"]


def _camera_parameters(camera) -> dict:
    names = ["fx", "fy", "cx", "cy"]
    names += (["k1", "k2", "p1", "p2", "k3", "k4", "k5", "k6"][:len(camera.distortion)] if camera.model == "brown"
              else ["kappa"])
    values = [camera.fx, camera.fy, camera.cx, camera.cy, *camera.distortion]
    return dict(zip(names, (float(v) for v in values)))


def camera_summary(camera, sigma: dict | None = None) -> dict:
    """The camera as JSON: model, parameters by name (px; distortion unitless), 1-sigma, image size."""
    params = _camera_parameters(camera)
    return {"model": camera.model, "parameters": params, "sigma": dict(sigma or {}),
            "parameter_units": {k: ("px" if k in ("fx", "fy", "cx", "cy") else "1") for k in params},
            "image_size": None if camera.image_size is None else [int(v) for v in camera.image_size],
            "units": "fx, fy, cx, cy in pixels (OpenCV pixel-centre convention); distortion coefficients "
                     "unitless, OpenCV order"}


#: --distortion counts as model names
COUNT_MODELS = {4: "k1-k2-p1-p2", 5: "k1-k3-p1-p2", 8: "rational"}


def calibrate_camera_images(images_dir, board: str, *, out_dir=None, model: str = "brown", n_distortion=5,
                            fix=(), overwrite: bool = False, progress=None, board_shape: bool = False,
                            allow_unconverged: bool = False, force: bool = False) -> dict:
    """Calibrate a camera from the images of ``images_dir`` (module docstring). Returns the summary
    dict (the JSON); writes the outputs when ``out_dir`` is given.

    n_distortion: 4, 5 or 8 Brown-Conrady coefficients, a model name of
    :data:`robocal.handeye.distortion_models.DISTORTION_MODELS`, or ``"auto"``: the model with the
    lowest held-out RMS (5-fold cross-validation over the images). ChArUco corners are taken as
    OpenCV's detector gives them or refined again by ``cornerSubPix``, whichever set the model fits
    with the lower RMS. board_shape: also estimate the board's sag along x and y [mm]
    (``board_sag_mm`` in the summary). The sanity gate (:func:`robocal.handeye.gate.camera_verdict`)
    puts ``status``/``reasons`` in the summary; a failed result writes no camera.json / camera.yaml
    unless ``force``, a fit that did not converge none unless ``allow_unconverged`` (``convergence``
    in the summary)."""
    from dataclasses import replace

    from ...handeye.camera_calibration import calibrate_camera
    from ...handeye.distortion_models import DISTORTION_MODELS, select_distortion_model, undetermined_terms
    from ...handeye.gate import camera_verdict

    b = parse_board(board)
    if out_dir is not None:
        check_output_folder(out_dir, CAMERA_OUTPUTS, {"the images": images_dir}, overwrite)
    detected = detect_set(list_images(images_dir), b, progress=progress)
    detected.require(3, "camera calibration")
    used = detected.used
    X = b.object_points()
    if model == "brown":
        name = COUNT_MODELS.get(n_distortion, n_distortion) if not isinstance(n_distortion, str) \
            else COUNT_MODELS.get(int(n_distortion), n_distortion) if n_distortion.isdigit() else n_distortion
        if name != "auto" and name not in DISTORTION_MODELS:
            raise ValueError(f"distortion model {n_distortion!r}: expected auto, 4, 5, 8 or one of "
                             f"{', '.join(DISTORTION_MODELS)}")
    else:
        name = "division"

    def run(m, uv):
        if m == "division":
            return calibrate_camera(uv, X, detected.image_size, model="division", fix=tuple(fix), min_points=b.min_points,
                                    board_shape=board_shape)
        n, held = DISTORTION_MODELS[m]
        return calibrate_camera(uv, X, detected.image_size, model="brown", n_distortion=n,
                                fix=tuple(fix) + tuple(h for h in held if h not in fix), min_points=b.min_points,
                                board_shape=board_shape)

    corners = "as detected"
    corner_rms = None
    if detected.refined_points is not None:
        m0 = "k1-k3-p1-p2" if name == "auto" else name
        plain = run(m0, detected.image_points[used])
        again = run(m0, detected.refined_points[used])
        corner_rms = {"as detected": float(plain.rms_px), "cornerSubPix": float(again.rms_px)}
        if again.rms_px < plain.rms_px:
            detected = replace(detected, image_points=detected.refined_points)
            corners = "cornerSubPix"
    selection = None
    if name == "auto":
        name, scores = select_distortion_model(run, detected.image_points[used], X, min_points=b.min_points)
        selection = {"held_out_rms_px": scores, "folds": min(5, int(used.sum())), "chosen": name}
    cal = run(name, detected.image_points[used])
    camera = cal.camera if cal.camera.image_size else _with_size(cal.camera, detected.image_size)
    params = _camera_parameters(camera)
    not_determined = undetermined_terms(params, cal.sigma)
    residuals = np.full(detected.image_points.shape, np.nan)
    residuals[used] = cal.residuals_px
    T = np.full((len(used), 4, 4), np.nan)
    T[used] = cal.T_camera_target
    solver_skips = {int(np.flatnonzero(used)[k]): r for k, r in (getattr(cal, "skipped", None) or {}).items()}
    rows = image_rows(detected, residuals, None, solver_skips)
    findings = identifiability_lines(cal.identifiability)
    if not_determined:  # the rank test passed, but the images do not pin these down
        findings = [ln for ln in findings if not ln.startswith("every estimated parameter")]
    for term, (v, sg) in not_determined.items():
        findings.append(f"{term}: not determined by these images ({v:+.4g} +- {sg:.3g}, the 1-sigma exceeds the "
                        f"value); choose a model without it (--distortion auto) or --fix {term}")
    summary = {
        "format": "robocal-camera-calibration/1", "board": b.to_dict(), "images_dir": str(images_dir),
        "camera": camera_summary(camera, {k: v for k, v in cal.sigma.items() if not k.startswith("sag_")}),
        "reprojection_rms_px": float(cal.rms_px),
        "n_images": len(rows), "n_images_used": sum(r["used"] for r in rows),
        "n_corners": int(np.count_nonzero(np.isfinite(residuals[..., 0]))),
        "converged": bool(cal.converged), "message": cal.message,
        "convergence": Convergence.of([("camera calibration", cal)],
                                      "more images with the board tilted and near the corners, or fewer distortion "
                                      "terms (--fix)").as_dict(),
        "identifiability": findings, "images": rows,
        "distortion_model": name, "distortion_selection": selection,
        "not_determined": {k: {"value": v, "sigma": sg} for k, (v, sg) in not_determined.items()},
        "corners": corners, "corner_set_rms_px": corner_rms,
        "board_sag_mm": None if cal.board_sag_mm is None else {
            "x": cal.board_sag_mm[0], "y": cal.board_sag_mm[1], "sigma_x": cal.sigma.get("sag_x"),
            "sigma_y": cal.sigma.get("sag_y")},
    }
    verdict = camera_verdict(float(cal.rms_px))
    summary["status"], summary["reasons"], summary["sanity_checks"] = verdict.status, list(verdict.reasons), \
        verdict.checks
    if out_dir is not None:
        projected, _ = backprojection(camera, T, X, detected.image_points)
        per_image = np.array([np.nan if r["rms_px"] is None else r["rms_px"] for r in rows])
        overlays = overlay_figures(detected, projected, per_image)
        with staged_outputs(out_dir, CAMERA_OUTPUTS, overwrite=overwrite) as stage:
            if (verdict.ok or force) and \
                    Convergence.from_dict(summary["convergence"]).may_write_model(allow_unconverged):
                write_camera_json(stage / "camera.json", camera)
                if camera.model == "brown":
                    write_camera_ros_yaml(stage / "camera.yaml", camera)
            (stage / "camera_calibration.json").write_text(json.dumps(json_ready(summary), indent=1) + "\n")
            write_camera_report(stage / "report.html", {**summary, "_residuals_px": residuals},
                                title=f"Camera calibration: {Path(images_dir).name}", overlays=overlays)
        summary["outputs"] = {n: str(Path(out_dir) / n) for n in CAMERA_OUTPUTS
                              if (Path(out_dir) / n).exists() and (verdict.ok or force or not n.startswith("camera."))}
    return summary


def _with_size(camera, size):
    from dataclasses import replace

    return replace(camera, image_size=tuple(int(v) for v in size))
