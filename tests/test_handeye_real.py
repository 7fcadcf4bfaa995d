"""Issue 14 real-data acceptance: the ROS-Industrial sets (../shared/datasets/ros_industrial_handeye,
read in place; skipped with the reason when absent), end to end through `robocal handeye solve
cal_data.yaml` from the raw images and pose files: the eye-to-hand ChArUco set and the eye-in-hand
modified circle grid. Detections are captured from the command's own run (one detection per set)
for the checks of ids/order and for OpenCV's linear methods side by side. Figures: docs/datasets.md."""

from __future__ import annotations

import json
import tempfile

import cv2
import numpy as np
import pytest
from click.testing import CliRunner

import robocal.workflows.cameras.handeye_solve as handeye_solve
from robocal.cli.main import main
from robocal.handeye import refine_hand_eye
from robocal.handeye.camera_calibration import calibrate_camera
from robocal.io.datasets import datasets_root
from robocal.io.ros_calibration import read_cal_data

ROS = datasets_root() / "ros_industrial_handeye" / "raw"
pytestmark = pytest.mark.skipif(not ROS.is_dir(), reason=f"real data folder {ROS} absent (tests read "
                                                         "../shared/datasets relative to the repository root)")
# the source library's reprojection RMS per corner (norm of the 2-vector) on these images, measured by
# running industrial_calibration fe62b7c (OpenCV 4.6, Ceres 2.1) on them: twice its printed "final
# cost per observation" (1.20829 and 1.14589; docs/datasets.md). Its ChArUco figure is over the 14
# images its detection can use (it finds 4 and 6 corners in 2.png and 15.png and drops both).
SOURCE_RMS_PX = {"test_set_charuco": 2.41658, "test_set_10x10": 2.29178}
SOURCE_CHARUCO_IMAGES = [f"{i}.png" for i in range(16) if i not in (2, 15)]


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    """`robocal handeye solve <set>/cal_data.yaml --exact-poses --out DIR` per set, with the detections."""
    out = {}
    captured = {}
    original = handeye_solve.detect_set

    def spy(*args, **kwargs):
        captured["set"] = original(*args, **kwargs)
        return captured["set"]

    handeye_solve.detect_set = spy
    try:
        for name in ("test_set_charuco", "test_set_10x10"):
            folder = tmp_path_factory.mktemp(name)
            r = CliRunner().invoke(main, ["handeye", "solve", str(ROS / name / "cal_data.yaml"), "--exact-poses",
                                          "--out", str(folder), "--json"])
            assert r.exit_code == 0, r.output
            summary = json.loads((folder / "handeye.json").read_text())
            out[name] = (summary, captured.pop("set"), folder)
    finally:
        handeye_solve.detect_set = original
    return out


def test_charuco_eye_to_hand_end_to_end(runs):
    s, det, folder = runs["test_set_charuco"]
    assert s["setup"] == "eye_to_hand" and s["camera_pose"]["frame"] == "base"
    # with the ArUco markers re-searched from the board layout every image is usable (2.png: 24 corners,
    # 4 without the re-search); the source uses 14 images, 274 corners
    assert s["n_images_used"] == 16 and s["n_corners"] == 382 and s["converged"]
    assert all(r["n_points"] >= 22 for r in s["images"])
    # fixed (given) intrinsics without distortion, flange poses exact, as the source: 2.62 px per corner
    # over all 16 images (15.png, which the source cannot use, fits worst: 3.9 px)
    assert 2.55 < s["reprojection_rms_px"] < 2.7
    assert abs(s["backprojection_rms_px"] - s["reprojection_rms_px"]) < 1e-6  # exact poses: the same chain
    # the solution sits near the layout's own initial guess of the camera (about 1.28 m from the base)
    guess = read_cal_data(ROS / "test_set_charuco" / "cal_data.yaml").camera_guess
    assert np.linalg.norm(np.array(s["camera_pose"]["position_mm"]) - guess[:3, 3]) < 15.0
    # the linear solutions scatter by millimetres to tens of millimetres and all back-project worse
    lin = s["linear"]
    assert max(d["difference_position_mm"] for d in lin.values()) > 5.0
    assert min(d["reprojection_rms_px"] for d in lin.values()) > s["reprojection_rms_px"] + 1.0
    report = (folder / "report.html").read_text()
    assert report.count('aria-label="back-projection"') >= 4 and 'aria-label="RMS per image"' in report
    assert report.count("data:image/png;base64") >= 4 and "2.png" in report
    yaml_text = (folder / "handeye.yaml").read_text()
    assert "parent_frame: base_link" in yaml_text and "child_frame: camera" in yaml_text


def test_circle_grid_eye_in_hand_end_to_end(runs):
    s, det, _ = runs["test_set_10x10"]
    assert s["setup"] == "eye_in_hand" and s["camera_pose"]["frame"] == "flange"
    assert s["n_images_used"] == 15 and s["n_corners"] == 1500 and s["converged"]
    # the same 1500 dots as the source (centres within 0.03 px median): the same RMS to 0.0005 px
    assert abs(s["reprojection_rms_px"] - SOURCE_RMS_PX["test_set_10x10"]) < 0.002
    lin = s["linear"]
    assert max(d["difference_position_mm"] for d in lin.values()) > 20.0  # tens of mm


def test_detections_real_ids_and_orientation(runs):
    """ChArUco ids in OpenCV's order (per-image PnP with the given intrinsics fits to ~1 px, no
    0.5 px offset against cornerSubPix); the modified grid's origin is its large dot."""
    _, det, _ = runs["test_set_charuco"]
    K = np.array([[1352.02747, 0, 789.67065], [0, 1356.14287, 627.2995], [0, 0, 1]])
    X = det.board.object_points()
    for i in np.flatnonzero(det.used):
        uv = det.image_points[i]
        ok = np.isfinite(uv[:, 0])
        _, r, t = cv2.solvePnP(X[ok], uv[ok], K, None)
        fit = cv2.projectPoints(X[ok], r, t, K, None)[0].reshape(-1, 2)
        assert np.sqrt(np.mean(np.sum((fit - uv[ok]) ** 2, 1))) < 1.1
        img = cv2.imread(str(det.paths[i]), cv2.IMREAD_GRAYSCALE)
        sp = cv2.cornerSubPix(img, uv[ok].astype(np.float32).reshape(-1, 1, 2), (5, 5), (-1, -1),
                              (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_MAX_ITER, 50, 1e-3)).reshape(-1, 2)
        assert np.all(np.abs((sp - uv[ok]).mean(axis=0)) < 0.12)
    _, det, _ = runs["test_set_10x10"]
    params = cv2.SimpleBlobDetector_Params()
    params.minArea, params.maxArea, params.minDistBetweenBlobs = 25, 5000, 5
    blobs = cv2.SimpleBlobDetector_create(params)
    for i in range(len(det.paths)):
        kp = blobs.detect(cv2.imread(str(det.paths[i]), cv2.IMREAD_GRAYSCALE))
        big = np.array(kp[int(np.argmax([k.size for k in kp]))].pt)
        assert np.linalg.norm(det.image_points[i, 90] - big) < 1.0, det.names[i]


def test_charuco_on_the_source_images_at_or_below_the_source(runs):
    """On the 14 images the source uses, with the given intrinsics and exact poses as the source,
    robocal's fit over its corners (334, the source 274) is at or below the source's 2.4166 px."""
    s, det, _ = runs["test_set_charuco"]
    data = read_cal_data(ROS / "test_set_charuco" / "cal_data.yaml")
    keep = np.isin(det.names, SOURCE_CHARUCO_IMAGES) & det.used
    assert keep.sum() == 14
    res = refine_hand_eye(data.T_base_flange[keep], det.image_points[keep], det.board.object_points(),
                          data.camera, setup=data.setup, robot_pose_sigma=None)
    n = int(np.isfinite(det.image_points[keep][..., 0]).sum())
    print("charuco, source's 14 images:", n, "corners", round(res.rms_px, 4), "px")
    assert res.converged and n == 334
    assert res.rms_px <= SOURCE_RMS_PX["test_set_charuco"]


def test_charuco_marker_refinement_recovers_corners():
    """2.png: the first ArUco pass finds 6 markers (4 corners); the layout-guided re-search finds all
    17 markers and all 24 corners, which fit one PnP pose with the given intrinsics to < 1 px."""
    from robocal.io.detection import detect_board, read_image_gray

    data = read_cal_data(ROS / "test_set_charuco" / "cal_data.yaml")
    gray = read_image_gray(ROS / "test_set_charuco" / "images" / "2.png")
    b = data.board
    plain = cv2.aruco.CharucoDetector(cv2.aruco.CharucoBoard(
        (b.cols, b.rows), b.pitch_mm, b.marker_mm, cv2.aruco.getPredefinedDictionary(cv2.aruco.DICT_6X6_250)))
    ids = plain.detectBoard(gray)[1]
    assert ids is not None and len(ids) == 4
    det = detect_board(gray, b)
    assert det.used and det.n_found == 24
    K = np.array([[1352.02747, 0, 789.67065], [0, 1356.14287, 627.2995], [0, 0, 1]])
    X = b.object_points()
    _, r, t = cv2.solvePnP(X, det.image_points, K, None)
    fit = cv2.projectPoints(X, r, t, K, None)[0].reshape(-1, 2)
    assert np.sqrt(np.mean(np.sum((fit - det.image_points) ** 2, 1))) < 1.0


def test_charuco_too_few_corners_rejected_with_reason():
    """Real pixels with most of the board hidden (8.png outside the box x 937-1188, y 719-981 painted
    flat grey): the 4 corners left are reported and the image is rejected with the reason."""
    from robocal.io.detection import detect_board, read_image_gray

    data = read_cal_data(ROS / "test_set_charuco" / "cal_data.yaml")
    gray = read_image_gray(ROS / "test_set_charuco" / "images" / "8.png")
    hidden = np.full_like(gray, int(np.median(gray)))
    hidden[719:981, 937:1188] = gray[719:981, 937:1188]
    det = detect_board(hidden, data.board, name="8.png")
    assert not det.used and det.n_found == 4
    assert det.skip_reason == "too few points: 4 of 24 found, need 6"


def _opencv_linear(F, uv, X, camera, setup):
    from test_handeye_images import opencv_solutions  # the same OpenCV pipeline as the rendered-image test

    return opencv_solutions(F, uv, X, camera, setup)


@pytest.mark.parametrize("name", ["test_set_charuco", "test_set_10x10"])
def test_opencv_linear_methods_scatter_and_refinement_is_needed(runs, name):
    s, det, _ = runs[name]
    data = read_cal_data(ROS / name / "cal_data.yaml")
    used = det.used
    from dataclasses import replace

    camera = replace(data.camera, image_size=det.image_size)
    X = det.board.object_points()
    solutions = _opencv_linear(data.T_base_flange[used], det.image_points[used], X, camera, data.setup)
    refined = np.array(s["camera_pose"]["position_mm"])
    distances = {k: float(np.linalg.norm(T[:3, 3] - refined)) for k, T in solutions.items()}
    print(name, {k: round(v, 1) for k, v in distances.items()})
    assert max(distances.values()) > 10.0  # OpenCV's linear answers scatter by tens of millimetres
    # with the intrinsics refined too, both sets go below the source's RMS
    res = refine_hand_eye(data.T_base_flange[used], det.image_points[used], X, camera, setup=data.setup,
                          refine_intrinsics=True, robot_pose_sigma=None)
    assert res.converged and res.rms_px < SOURCE_RMS_PX[name] * 0.75
    # two steps, as `camera calibrate` then `handeye solve --camera`: below the source's RMS too
    cal = calibrate_camera(det.image_points[used], X, det.image_size, min_points=det.board.min_points)
    two_step = refine_hand_eye(data.T_base_flange[used], det.image_points[used], X, cal.camera, setup=data.setup,
                               robot_pose_sigma=None)
    assert two_step.rms_px < SOURCE_RMS_PX[name] * 0.8, two_step.rms_px


@pytest.fixture(scope="module")
def default_runs():
    """`robocal handeye solve <set>/cal_data.yaml --json` with every option at its default."""
    out = {}
    for name in ("test_set_charuco", "test_set_10x10"):
        with tempfile.TemporaryDirectory() as he:  # --out is required; the tests read the printed result
            r = CliRunner().invoke(main, ["handeye", "solve", str(ROS / name / "cal_data.yaml"), "--json", "--out", he])
        assert r.exit_code == 0, r.output
        out[name] = json.loads(r.stdout[r.stdout.index("{"):])
    return out


def _pose(d):
    return np.array(d["matrix"], dtype=float)


def test_the_default_command_lands_at_the_source_library(runs, default_runs):
    """Issue 30 acceptance: the DEFAULT command (robot_pose_sigma "auto") lands within 1 mm / 0.1 deg
    of the source library's camera on the circle grid and 2 mm / 0.2 deg on ChArUco, its RMS within
    2 % of the exact-pose fit. The source's circle-grid camera equals robocal's exact-pose fit to
    0.00 mm (same 1500 dots); its ChArUco camera is robocal's exact-pose fit on the source's 14
    images to 0.18 mm / 0.04 deg (docs/datasets.md), used here as the source's."""
    from robocal.handeye.refine import rotation_error_deg

    circ, exact_circ = default_runs["test_set_10x10"], runs["test_set_10x10"][0]
    d_mm = np.linalg.norm(np.subtract(circ["camera_pose"]["position_mm"], exact_circ["camera_pose"]["position_mm"]))
    d_deg = rotation_error_deg(_pose(circ["camera_pose"]), _pose(exact_circ["camera_pose"]))
    assert d_mm < 1.0 and d_deg < 0.1, (d_mm, d_deg)
    assert circ["reprojection_rms_px"] <= 1.02 * SOURCE_RMS_PX["test_set_10x10"]
    sigma = circ["robot_pose_sigma"]
    # the estimated robot noise absorbs the chain's misfit and predicts held-out images ~4x worse
    assert sigma["mode"] == "auto" and sigma["choice"] == "exact"
    assert sigma["cv_rms_px"]["estimated"] > 2 * sigma["cv_rms_px"]["exact"]

    s, det, _ = runs["test_set_charuco"]
    data = read_cal_data(ROS / "test_set_charuco" / "cal_data.yaml")
    keep = np.isin(det.names, SOURCE_CHARUCO_IMAGES) & det.used
    source_like = refine_hand_eye(data.T_base_flange[keep], det.image_points[keep], det.board.object_points(),
                                  data.camera, setup=data.setup, robot_pose_sigma=None)
    ch = default_runs["test_set_charuco"]
    d_mm = np.linalg.norm(np.subtract(ch["camera_pose"]["position_mm"], source_like.camera_pose[:3, 3]))
    d_deg = rotation_error_deg(_pose(ch["camera_pose"]), source_like.camera_pose)
    assert d_mm < 2.0 and d_deg < 0.2, (d_mm, d_deg)  # measured 1.4 mm / 0.11 deg
    assert ch["reprojection_rms_px"] <= 1.02 * s["reprojection_rms_px"]


def test_a_systematic_misfit_is_a_warning_naming_both_fits(tmp_path):
    """Circle grid (nominal Kinect intrinsics: the rigid chain misses by 2.3 px where one PnP pose
    per image fits to 0.3 px): the exact and the estimated-noise fits disagree beyond their sigma,
    and the command says so on one `Warning:` line naming both and the remedies."""
    r = CliRunner().invoke(main, ["handeye", "solve", str(ROS / "test_set_10x10" / "cal_data.yaml"),
                                  "--out", str(tmp_path / "he")])
    assert r.exit_code == 0, r.output
    warnings = [ln for ln in r.stderr.splitlines() if ln.startswith("Warning:")]
    assert len(warnings) == 1
    assert "exact-pose fit" in warnings[0] and "estimated" in warnings[0] and "joint offsets" in warnings[0]
    assert "flange poses: taken as exact (auto" in r.stdout


def test_robot_pose_sigma_option_values(tmp_path):
    """--robot-pose-sigma takes auto, estimate or MM,DEG; anything else is a usage error naming it."""
    args = ["handeye", "solve", str(ROS / "test_set_charuco" / "cal_data.yaml"), "--out", str(tmp_path / "he")]
    r = CliRunner().invoke(main, [*args, "--robot-pose-sigma", "0.5"])
    assert r.exit_code == 2 and "--robot-pose-sigma" in r.output and "MM,DEG" in r.output
    r = CliRunner().invoke(main, [*args, "--robot-pose-sigma", "estimate", "--exact-poses"])
    assert r.exit_code == 2 and "exclude each other" in r.output
    r = CliRunner().invoke(main, [*args, "--robot-pose-sigma", "estimate", "--json"])
    # asked for explicitly on this set, the estimated pose noise back-projects through the reported
    # poses at 7.3 px, beyond the gate (10 x the per-image PnP RMS): exit 3 with that reason -- the
    # default (auto) keeps the exact-pose fit here for the same reason (held-out 3.4 vs 7.9 px)
    assert r.exit_code == 3, r.output
    s = json.loads(r.stdout[r.stdout.index("{"):])
    assert not s["sanity_checks"]["reprojection_vs_corner_noise"]["passed"]
    assert s["robot_pose_sigma"]["mode"] == "estimate"
    assert s["robot_pose_sigma"]["robot_pose_sigma"][0] > 0


def test_refined_distortion_terms_the_images_do_not_determine_are_named(tmp_path):
    """Issue 25 item 6 (camera part): `handeye solve --refine-intrinsics` on the ChArUco set refines
    five distortion terms; k3 comes out -0.17 +- 0.19 and is named as not determined, not reported
    as identifiable; every refined intrinsic has its 1-sigma and unit."""
    r = CliRunner().invoke(main, ["handeye", "solve", str(ROS / "test_set_charuco" / "cal_data.yaml"),
                                  "--refine-intrinsics", "--exact-poses", "--json", "--out", str(tmp_path / "he")])
    assert r.exit_code == 0, r.output
    s = json.loads(r.stdout[r.stdout.index("{"):])
    assert "k3" in s["not_determined"]
    assert any(line.startswith("k3: not determined") for line in s["identifiability"])
    assert not any(line.startswith("every estimated") for line in s["identifiability"])
    cam = s["camera"]
    assert set(cam["sigma"]) >= {"fx", "fy", "cx", "cy", "k1", "k2", "p1", "p2", "k3"}
    assert cam["parameter_units"]["fx"] == "px"
