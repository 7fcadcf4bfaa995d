"""Camera self-calibration pipeline speed (issue 15): 80 images (40 per arm), detection + solve.

Data: the DLR Justin tree (head camera, a 7x4 checkerboard in each hand, offsets on head and arms
up to 3 deg), 80 images rendered by :class:`robocal.sim.cameras.camera_render.BoardRenderer` at 640x480,
a 20 Hz joint log and a frames file on another clock (:mod:`robocal.sim.cameras.self_calibration_views`). Rows (one
process, one BLAS thread, median of ``--runs``):

* the whole pipeline ``workflows.self_calibration.self_calibrate`` (read files, match time stamps,
  detect, solve, no outputs written);
* detection alone (``io.detection.detect_board`` on the 80 images, OpenCV's corner finder inside);
* the solve alone (``handeye.self_calibration.solve_self_calibration`` on the detected corners);
* for scale, OpenCV ``calibrateCamera`` on the same corners (intrinsics only, no kinematics).

With ``--nao`` the data are nao-model's simulated NAO run instead (``sim.self_calibration``: 40 views
per hand + 8 partial ones, 1280x960, 0.05 deg joint-reading noise, rendered), the pipeline with
``--board-on left_hand,right_hand`` (automatic hand assignment) and joint corrections.

Run: ``python benchmarks/bench_self_calibration.py [--runs 3] [--nao]``.
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "NUMBA_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_var] = "1"

import argparse  # noqa: E402
import statistics  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import cv2  # noqa: E402
import numpy as np  # noqa: E402

from robocal.camera import Camera  # noqa: E402
from robocal.handeye.refine import joint_offset_names  # noqa: E402
from robocal.handeye.self_calibration import solve_self_calibration  # noqa: E402
from robocal.io.boards import board_image, parse_board  # noqa: E402
from robocal.io.camera_files import write_camera_json  # noqa: E402
from robocal.io.joint_log_files import write_frames, write_joint_log  # noqa: E402
from robocal.io.detection import detect_board  # noqa: E402
from robocal.io.images import read_image_gray, write_png  # noqa: E402
from robocal.robots import load_robot  # noqa: E402
from robocal.sim.cameras.self_calibration import capture_schedule  # noqa: E402
from robocal.sim.cameras.self_calibration_views import ViewLimits, camera_board_poses, visible_configurations  # noqa: E402
from robocal.sim.cameras.camera_render import BoardRenderer  # noqa: E402
from robocal.transforms import so3_exp, transforms_from  # noqa: E402
from robocal.workflows.cameras.self_calibration import self_calibrate  # noqa: E402

BOARD = "checkerboard:7x4:25mm"
CAM = Camera(800.0, 800.0, 319.5, 239.5, (-0.1, 0.05, 0.0, 0.0, 0.0), "brown", (640, 480))
HANDS = {"left": transforms_from(so3_exp(np.array([0.1, -0.2, 0.3])), np.array([10.0, 20.0, 120.0])),
         "right": transforms_from(so3_exp(np.array([-0.2, 0.1, 2.0])), np.array([-15.0, 5.0, 110.0]))}


def make_set(root: Path, n_per_arm: int = 40, seed: int = 0):
    m = load_robot("dlr_justin19")
    rng = np.random.default_rng(seed)
    truth = m.params.values.copy()
    for n in joint_offset_names(m):
        if m.links[int(n[5:]) - 1].name.startswith(("head", "left", "right")):
            truth[m.params.names.index(n)] += np.radians(rng.uniform(-3, 3))
    true_model = m.with_params(truth)
    b = parse_board(BOARD)
    renderer = BoardRenderer(CAM, *board_image(b, 1.0))
    q, on, T = [], [], []
    for c in HANDS:
        qc = visible_configurations(true_model, CAM, b.object_points(), camera_end_effector="head",
                                    T_ee_camera=np.eye(4), carrier=c, T_carrier_board=HANDS[c], n=n_per_arm, rng=rng,
                                    q_center=np.zeros(19), q_spread=np.pi, front_z=b.front_z, pitch_mm=b.pitch_mm,
                                    limits=ViewLimits(margin_px=30.0, depth_mm=(50.0, np.inf), max_tilt_deg=55.0))
        q.append(qc)
        on += [c] * n_per_arm
        T.append(camera_board_poses(true_model, qc, "head", np.eye(4), c, HANDS[c]))
    q, T = np.concatenate(q), np.concatenate(T)
    (root / "images").mkdir()
    names = [f"frame_{i:03d}.png" for i in range(len(q))]
    for n, Ti in zip(names, T):
        write_png(root / "images" / n, renderer.render(Ti, rng))
    t_img, t_log, pose = capture_schedule(len(q), rng)
    write_joint_log(root / "joints.csv", t_log, np.where(pose[:, None] >= 0, q[np.clip(pose, 0, None)], 0.0),
                          m.controller_joints)
    write_frames(root / "frames.csv", names, t_img)
    write_camera_json(root / "camera.json", CAM)
    return m, q, on, names


def timed(fn, runs):
    fn()
    t = []
    for _ in range(runs):
        t0 = time.perf_counter()
        fn()
        t.append(time.perf_counter() - t0)
    return statistics.median(t)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--nao", action="store_true", help="nao-model's simulated NAO run instead of Justin")
    args = ap.parse_args()
    if args.nao:
        return main_nao(args.runs)
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        m, q, on, names = make_set(root)
        b = parse_board(BOARD)
        X = b.object_points()
        paths = [root / "images" / n for n in names]

        def detect():
            return np.array([detect_board(read_image_gray(p), b).image_points for p in paths])

        uv = detect()
        rows = [
            ("pipeline: match + detect + solve", lambda: self_calibrate(
                "dlr_justin19", images=root / "images", joints=root / "joints.csv", frames=root / "frames.csv",
                board=BOARD, camera_end_effector="head", board_on=["left", "right"], camera_file=root / "camera.json")),
            ("detection alone (80 images)", detect),
            ("solve alone (all chains, 80 images)", lambda: solve_self_calibration(
                m, q, uv, X, CAM, on, camera_end_effector="head")),
            ("OpenCV calibrateCamera, same corners", lambda: cv2.calibrateCamera(
                [X.astype(np.float32)] * len(uv), [u.astype(np.float32) for u in uv], CAM.image_size, None, None)),
        ]
        times = {name: timed(fn, args.runs) for name, fn in rows}
    ref = times["OpenCV calibrateCamera, same corners"]
    print(f"{'row':40s} {'median s':>9s} {'/ OpenCV calibrateCamera':>25s}")
    for name, t in times.items():
        print(f"{name:40s} {t:9.3f} {t / ref:25.2f}")


def main_nao(runs):
    from robocal.sim.cameras.self_calibration import simulate_self_calibration

    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        run = simulate_self_calibration("nao_h25", n_images_per_chain=40, seed=0, out_dir=root)
        b = run.board
        paths = [root / "images" / n for n in run.images]

        def pipeline():
            return self_calibrate("nao_h25", images=root / "images", joints=root / "joint_log.csv",
                                  frames=root / "frames.csv", board=b.spec, camera_end_effector="camera_top",
                                  board_on=["left_hand", "right_hand"], camera_file=root / "camera.json",
                                  joint_noise_deg=0.05)

        s = pipeline()
        print(f"NAO: {s['n_images']} images, {s['n_images_used']} used, RMS {s['reprojection_rms_px']:.3f} px, "
              f"{s['message'][:120]}")
        times = {
            "pipeline: match + detect + assign + solve": timed(pipeline, runs),
            "detection alone": timed(lambda: [detect_board(read_image_gray(p), b) for p in paths], runs),
        }
        uv = np.array([detect_board(read_image_gray(p), b).image_points for p in paths])
        full = np.all(np.isfinite(uv[..., 0]), axis=1)
        X = b.object_points()
        times["OpenCV calibrateCamera, same corners"] = timed(lambda: cv2.calibrateCamera(
            [X.astype(np.float32)] * int(full.sum()), [u.astype(np.float32) for u in uv[full]], run.camera.image_size,
            None, None), runs)
    ref = times["OpenCV calibrateCamera, same corners"]
    print(f"{'row':45s} {'median s':>9s} {'/ OpenCV calibrateCamera':>25s}")
    for name, t in times.items():
        print(f"{name:45s} {t:9.3f} {t / ref:25.2f}")


if __name__ == "__main__":
    main()
