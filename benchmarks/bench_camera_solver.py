"""Camera calibration solver against ``cv2.calibrateCamera`` on the same corners (issue 34 item 1).

``robocal.handeye.calibrate_camera`` (closed-form start, per-image PnP, Levenberg-Marquardt with the
per-image poses eliminated by a Schur complement, covariance, identifiability) against OpenCV's
``calibrateCamera`` (its default criteria; start, LM and its own per-view errors) on the same
simulated detections: the simulator's camera (1280 x 1024, Brown 5 coefficients), an 11 x 8
board, 0.3 px corner noise, N images. Interleaved repeats in one process; medians, the ratio of
medians and the median of per-repeat ratios; the RMS of both and the largest difference of an
intrinsic / distortion value in units of robocal's reported 1-sigma.

A second table: batched PnP, ``robocal.handeye.solve_pnp`` (homography start, LM per image, all
images at once) against ``cv2.solvePnP`` (ITERATIVE) called once per image, the true camera.

Run: ``python benchmarks/bench_camera_solver.py [--images 30 60 100] [--repeat 7]``.
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "NUMBA_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_var] = "1"

import argparse  # noqa: E402
import time  # noqa: E402

import cv2  # noqa: E402
import numpy as np  # noqa: E402

from robocal.handeye import calibrate_camera, solve_pnp  # noqa: E402
from robocal.sim.cameras.handeye_points import simulate_hand_eye  # noqa: E402

NAMES = ("fx", "fy", "cx", "cy", "k1", "k2", "p1", "p2", "k3")


def _opencv_inputs(sim):
    ok = np.all(np.isfinite(sim.image_points), axis=2)
    obj = [sim.target_points[m].astype(np.float32) for m in ok]
    img = [u[m].astype(np.float32) for u, m in zip(sim.image_points, ok)]
    return obj, img


def run(n_images: int, repeat: int, seed: int = 11):
    sim = simulate_hand_eye(seed, n_images=n_images, pose_noise_mm=0.0, pose_noise_deg=0.0)
    size = (1280, 1024)
    obj, img = _opencv_inputs(sim)
    calibrate_camera(sim.image_points, sim.target_points, size)  # warm-up (imports, caches)
    cv2.calibrateCamera(obj, img, size, None, None)
    t_rc, t_cv = [], []
    for _ in range(repeat):
        t0 = time.perf_counter()
        res = calibrate_camera(sim.image_points, sim.target_points, size)
        t1 = time.perf_counter()
        rms, K, dist, _, _ = cv2.calibrateCamera(obj, img, size, None, None)
        t2 = time.perf_counter()
        t_rc.append(t1 - t0)
        t_cv.append(t2 - t1)
    ours = dict(zip(NAMES, (*res.camera.intrinsics, *res.camera.distortion)))
    theirs = dict(zip(NAMES, (K[0, 0], K[1, 1], K[0, 2], K[1, 2], *dist.ravel()[:5])))
    dz = max(abs(ours[k] - theirs[k]) / res.sigma[k] for k in NAMES)
    t_rc, t_cv = np.array(t_rc), np.array(t_cv)
    return dict(n=n_images, robocal=float(np.median(t_rc)), opencv=float(np.median(t_cv)),
                ratio=float(np.median(t_rc) / np.median(t_cv)), paired=float(np.median(t_rc / t_cv)),
                rms=res.rms_px, rms_cv=float(rms), dz=dz, iterations=res.message.split(" iterations")[0])


def run_pnp(n_images: int, repeat: int, seed: int = 11):
    sim = simulate_hand_eye(seed, n_images=n_images, pose_noise_mm=0.0, pose_noise_deg=0.0)
    cam, X, uv = sim.camera, sim.target_points, sim.image_points
    obj, img = _opencv_inputs(sim)
    K, D = cam.matrix, np.asarray(cam.distortion, dtype=float)

    def cv():
        return [cv2.solvePnP(o, i, K, D, flags=cv2.SOLVEPNP_ITERATIVE) for o, i in zip(obj, img)]

    solve_pnp(cam, X, uv)
    cv()
    t_rc, t_cv = [], []
    for _ in range(repeat):
        t0 = time.perf_counter()
        T, _, _ = solve_pnp(cam, X, uv)
        t1 = time.perf_counter()
        out = cv()
        t2 = time.perf_counter()
        t_rc.append(t1 - t0)
        t_cv.append(t2 - t1)
    dt = max(float(np.linalg.norm(T[k, :3, 3] - o[2].ravel())) for k, o in enumerate(out))
    t_rc, t_cv = np.array(t_rc), np.array(t_cv)
    return dict(n=n_images, robocal=float(np.median(t_rc)), opencv=float(np.median(t_cv)),
                ratio=float(np.median(t_rc) / np.median(t_cv)), paired=float(np.median(t_rc / t_cv)), dt=dt)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--images", type=int, nargs="+", default=[30, 60, 100])
    ap.add_argument("--repeat", type=int, default=7)
    a = ap.parse_args()
    print("| images | robocal `calibrate_camera` [s] | OpenCV `calibrateCamera` [s] | robocal / OpenCV (paired) "
          "| robocal ms / image | RMS robocal / OpenCV [px] | max abs(difference) / sigma |")
    print("|---:|---:|---:|---:|---:|---:|---:|")
    for n in a.images:
        r = run(n, a.repeat)
        print(f"| {r['n']} | {r['robocal']:.3f} | {r['opencv']:.3f} | x{r['ratio']:.2f} (x{r['paired']:.2f}) | "
              f"{1e3 * r['robocal'] / n:.2f} | {r['rms']:.4f} / {r['rms_cv']:.4f} | {r['dz']:.2e} |", flush=True)
    print("\n| images | robocal `solve_pnp` (batched) [ms] | OpenCV `solvePnP` x images [ms] | robocal / OpenCV (paired) "
          "| largest translation difference [mm] |")
    print("|---:|---:|---:|---:|---:|")
    for n in a.images:
        r = run_pnp(n, a.repeat)
        print(f"| {r['n']} | {1e3 * r['robocal']:.2f} | {1e3 * r['opencv']:.2f} | x{r['ratio']:.2f} (x{r['paired']:.2f}) | "
              f"{r['dt']:.2e} |", flush=True)
    print(f"\n(load average {os.getloadavg()[0]:.1f}; {a.repeat} interleaved repeats, medians)")


if __name__ == "__main__":
    main()
