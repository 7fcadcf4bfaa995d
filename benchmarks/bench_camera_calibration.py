"""Camera calibration side by side with OpenCV (issue 30 item 2): `robocal camera calibrate`'s
pipeline (``calibrate_camera_images``: detection, corner set, calibration) against OpenCV end to end
on the same image files, on

* rendered images with known truth (:class:`robocal.sim.cameras.camera_render.BoardRenderer`: the
  simulator's 1280 x 1024 camera, fx = fy = 1600 px, k1 -0.12, k2 0.09, p1 4e-4, p2 -3e-4; blur,
  lighting, sensor noise; 15 views per seed): the error of every parameter against the truth, not
  only the RMS;
* the ROS-Industrial real images (../shared/datasets/ros_industrial_handeye): the RMS.

Both fit OpenCV's 5-coefficient model (the truth's). OpenCV pipelines: checkerboard
``findChessboardCorners`` + ``cornerSubPix`` (11 x 11) and ``findChessboardCornersSB`` (ACCURACY);
ChArUco ``CharucoDetector`` with and without ``cornerSubPix`` (11 x 11); circle grid
``findCirclesGrid``; then ``calibrateCamera``. Run: ``python benchmarks/bench_camera_calibration.py
[--seeds 3]`` (prints a Markdown table; docs/handeye.md cites it).
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "NUMBA_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_var] = "1"

import argparse  # noqa: E402
import tempfile  # noqa: E402
from pathlib import Path  # noqa: E402

import cv2  # noqa: E402
import numpy as np  # noqa: E402

from robocal.io.boards import board_image, parse_board  # noqa: E402
from robocal.io.datasets import datasets_root  # noqa: E402
from robocal.io.detection import _blob_detector  # noqa: E402
from robocal.io.ros_calibration import read_cal_data  # noqa: E402
from robocal.sim.cameras.camera_cell import simulate_hand_eye_poses  # noqa: E402
from robocal.sim.cameras.camera_render import BoardRenderer  # noqa: E402
from robocal.workflows.cameras.camera_calibrate import calibrate_camera_images  # noqa: E402
from robocal.workflows.cameras.camera_simulate import _texel_mm  # noqa: E402

CRIT = (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_MAX_ITER, 50, 1e-4)
NAMES = ("fx", "fy", "cx", "cy", "k1", "k2", "p1", "p2")


def _render(spec, seed, folder):
    board = parse_board(spec)
    X = board.object_points()
    cell = simulate_hand_eye_poses(X, setup="eye_in_hand", n_images=15, front_z=board.front_z, seed=seed)
    texture, affine = board_image(board, _texel_mm(board))
    renderer = BoardRenderer(cell.camera, texture, affine)
    rng = np.random.default_rng(seed)
    for k, T in enumerate(cell.T_camera_target):
        cv2.imwrite(str(folder / f"{k:02d}.png"), renderer.render(T, rng))
    return board, cell.camera


def _truth_vector(camera):
    return np.array([camera.fx, camera.fy, camera.cx, camera.cy, *camera.distortion[:4]])


def _opencv(board, paths, variant):
    """(rms, parameter vector (8,)) of OpenCV end to end, or None if it finds too few boards."""
    obj, img, size = [], [], None
    for p in paths:
        gray = cv2.imread(str(p), cv2.IMREAD_GRAYSCALE)
        size = gray.shape[::-1]
        if board.kind == "checkerboard":
            pattern = (board.cols, board.rows)
            if variant == "SB":
                found, c = cv2.findChessboardCornersSB(gray, pattern, flags=cv2.CALIB_CB_NORMALIZE_IMAGE
                                                       | cv2.CALIB_CB_EXHAUSTIVE | cv2.CALIB_CB_ACCURACY)
            else:
                found, c = cv2.findChessboardCorners(gray, pattern, flags=cv2.CALIB_CB_ADAPTIVE_THRESH
                                                     | cv2.CALIB_CB_NORMALIZE_IMAGE)
                if found:
                    c = cv2.cornerSubPix(gray, c, (5, 5), (-1, -1), CRIT)
            if not found:
                continue
            Xg = np.zeros((board.cols * board.rows, 3), np.float32)
            Xg[:, :2] = np.mgrid[0:board.cols, 0:board.rows].T.reshape(-1, 2) * board.pitch_mm
            obj.append(Xg)
            img.append(c.reshape(-1, 2).astype(np.float32))
        elif board.kind == "charuco":
            dictionary = cv2.aruco.getPredefinedDictionary(getattr(cv2.aruco, board.dictionary))
            cb = cv2.aruco.CharucoBoard((board.cols, board.rows), board.pitch_mm, board.marker_mm, dictionary)
            corners, ids, _, _ = cv2.aruco.CharucoDetector(cb).detectBoard(gray)
            if ids is None or len(ids) < 6:
                continue
            c = corners.astype(np.float32)
            if variant == "cornerSubPix":
                c = cv2.cornerSubPix(gray, c, (5, 5), (-1, -1), CRIT)
            obj.append(cb.getChessboardCorners()[ids.ravel()].astype(np.float32))
            img.append(c.reshape(-1, 2))
        else:
            return None
    if len(obj) < 3:
        return None
    rms, K, D, _, _ = cv2.calibrateCamera(obj, img, size, None, None)
    return rms, np.array([K[0, 0], K[1, 1], K[0, 2], K[1, 2], *D.ravel()[:4]]), len(obj)


def _robocal(folder, spec, distortion="5"):
    s = calibrate_camera_images(folder, spec, n_distortion=distortion)
    p = s["camera"]["parameters"]
    return s["reprojection_rms_px"], np.array([p[n] for n in NAMES]), s["n_images_used"], s


def rendered(seeds):
    rows = []
    for spec, variants in (("checkerboard:9x6:25mm", ("classic + cornerSubPix", "SB")),
                           ("charuco:9x7:30mm:22mm:DICT_5X5_100", ("CharucoDetector", "cornerSubPix"))):
        errs = {"robocal": []}
        rms = {"robocal": []}
        for v in variants:
            errs[v], rms[v] = [], []
        for seed in seeds:
            with tempfile.TemporaryDirectory() as tmp:
                folder = Path(tmp)
                board, truth = _render(spec, seed, folder)
                t = _truth_vector(truth)
                r, p, _, _ = _robocal(folder, spec)
                errs["robocal"].append(np.abs(p - t))
                rms["robocal"].append(r)
                paths = sorted(folder.glob("*.png"))
                for v in variants:
                    out = _opencv(board, paths, v)
                    if out is not None:
                        errs[v].append(np.abs(out[1] - t))
                        rms[v].append(out[0])
        for k in errs:
            e = np.mean(errs[k], axis=0)
            rows.append((spec.split(":")[0], k, np.mean(rms[k]), *e))
    print(f"\nRendered images, {len(seeds)} seeds x 15 views, mean absolute parameter error against the truth "
          "(5-coefficient model for both):\n")
    print("| board | pipeline | RMS [px] | fx [px] | fy [px] | cx [px] | cy [px] | k1 | k2 | p1 | p2 |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for b, k, r, *e in rows:
        who = "**robocal**" if k == "robocal" else f"OpenCV {k}"
        print(f"| {b} | {who} | {r:.4f} | " + " | ".join(f"{v:.3f}" if i < 4 else f"{v:.2e}" for i, v in enumerate(e))
              + " |")


def real():
    root = datasets_root() / "ros_industrial_handeye" / "raw"
    if not root.is_dir():
        print(f"\n(real images absent: {root})")
        return
    print("\nROS-Industrial real images, RMS [px] (5 coefficients unless named):\n")
    print("| set | robocal 5 | robocal auto (model, held-out RMS) | OpenCV | OpenCV + cornerSubPix |")
    print("|---|---|---|---|---|")
    for name, spec in (("test_set_charuco", "charuco:5x7:36.195mm:18.256mm:DICT_6X6_250"),
                       ("test_set_10x10", "circles:10x10:25.4mm:modified")):
        folder = root / name / "images"
        r5 = _robocal(folder, spec)[0]
        ra, _, _, s = _robocal(folder, spec, "auto")
        held = s["distortion_selection"]["held_out_rms_px"][s["distortion_model"]]
        data = read_cal_data(root / name / "cal_data.yaml")
        b = data.board
        if b.kind == "charuco":
            cv = _opencv(b, data.image_paths, "CharucoDetector")[0]
            cvs = f"{_opencv(b, data.image_paths, 'cornerSubPix')[0]:.4f}"
        else:
            obj, img = [], []
            for p in data.image_paths:
                gray = cv2.imread(str(p), cv2.IMREAD_GRAYSCALE)
                size = gray.shape[::-1]
                found, c = cv2.findCirclesGrid(gray, b.grid, flags=cv2.CALIB_CB_SYMMETRIC_GRID
                                               | cv2.CALIB_CB_CLUSTERING, blobDetector=_blob_detector(data.blob_settings))
                X = np.zeros((b.grid[0] * b.grid[1], 3), np.float32)
                X[:, :2] = np.mgrid[0:b.grid[0], 0:b.grid[1]].T.reshape(-1, 2) * b.pitch_mm
                obj.append(X)
                img.append(c.reshape(-1, 2))
            cv = cv2.calibrateCamera(obj, img, size, None, None)[0]
            cvs = "-"
        print(f"| {name} | {r5:.4f} | {ra:.4f} ({s['distortion_model']}, {held:.4f}) | {cv:.4f} | {cvs} |")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=3)
    a = ap.parse_args()
    rendered(list(range(a.seeds)))
    real()


if __name__ == "__main__":
    main()
