"""Hand-eye refinement speed (issue 14): 30 images x 88 corners, median of several runs, side by
side with OpenCV's linear methods on the same data in the same run.

Data: :func:`robocal.sim.cameras.handeye_points.simulate_hand_eye` (seed 0, eye-in-hand, 30 images of an
11 x 8 board, 0.3 px corner noise, 0.05 mm / 0.01 deg robot pose noise). Rows (one process, one
BLAS thread):

* robocal ``refine_hand_eye`` end to end: per-image PnP (own, batched LM), the four linear
  solvers, then the core's LM over all 2 x 30 x 88 corner residuals with the errors-in-variables
  flange corrections (6 x 30 extra unknowns with their prior), covariance and identifiability;
* the same with ``robot_pose_sigma=None`` (no flange corrections: 12 unknowns);
* robocal ``solve_pnp`` alone (30 images) and OpenCV ``solvePnP`` x 30 (ITERATIVE), for scale;
* OpenCV ``calibrateHandEye`` (TSAI, PARK, HORAUD, ANDREFF, DANIILIDIS) and
  ``calibrateRobotWorldHandEye`` (SHAH, LI) on the PnP poses: linear only, no refinement.

Ratios are robocal time / OpenCV time (how many times slower the full refinement is than a
linear solve). Run: ``python benchmarks/bench_handeye.py [--runs 7]``.
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "NUMBA_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_var] = "1"

import argparse  # noqa: E402
import statistics  # noqa: E402
import time  # noqa: E402

import cv2  # noqa: E402
import numpy as np  # noqa: E402

from robocal.handeye import refine_hand_eye, solve_pnp  # noqa: E402
from robocal.handeye.refine import rotation_error_deg  # noqa: E402
from robocal.sim.cameras.handeye_points import simulate_hand_eye  # noqa: E402
from robocal.transforms import invert_transforms  # noqa: E402

try:
    from _machine import machine_info  # noqa: E402
except ImportError:  # run from elsewhere
    machine_info = None

HAND_EYE = {"TSAI": cv2.CALIB_HAND_EYE_TSAI, "PARK": cv2.CALIB_HAND_EYE_PARK, "HORAUD": cv2.CALIB_HAND_EYE_HORAUD,
            "ANDREFF": cv2.CALIB_HAND_EYE_ANDREFF, "DANIILIDIS": cv2.CALIB_HAND_EYE_DANIILIDIS}
ROBOT_WORLD = {"SHAH": cv2.CALIB_ROBOT_WORLD_HAND_EYE_SHAH, "LI": cv2.CALIB_ROBOT_WORLD_HAND_EYE_LI}


def timed(fn, runs):
    fn()  # warm-up (imports, caches)
    times = []
    for _ in range(runs):
        t = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t)
    return statistics.median(times), out


def _T(R, t):
    T = np.eye(4)
    T[:3, :3], T[:3, 3] = R, np.ravel(t)
    return T


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--runs", type=int, default=7)
    args = ap.parse_args(argv)
    if machine_info:
        print("\n".join(machine_info([f"opencv      {cv2.__version__}"])))
    sim = simulate_hand_eye(0, n_images=30)
    F, uv, X, cam, truth = sim.T_base_flange, sim.image_points, sim.target_points, sim.camera, sim.camera_pose
    print(f"data        {uv.shape[0]} images x {uv.shape[1]} corners ({int(np.isfinite(uv[..., 0]).sum())} detected)")
    rows = []
    t_full, res = timed(lambda: refine_hand_eye(F, uv, X, cam), args.runs)
    rows.append(("robocal refine_hand_eye (PnP + linear + EIV refinement)", t_full, res.camera_pose))
    t_plain, res0 = timed(lambda: refine_hand_eye(F, uv, X, cam, robot_pose_sigma=None), args.runs)
    rows.append(("robocal refine_hand_eye, robot_pose_sigma=None", t_plain, res0.camera_pose))
    t_pnp, (C, _, _) = timed(lambda: solve_pnp(cam, X, uv), args.runs)
    rows.append(("robocal solve_pnp (30 images, batched)", t_pnp, None))
    dist = np.array(cam.distortion)

    def cv_pnp():
        return [cv2.solvePnP(X, u, cam.matrix, dist, flags=cv2.SOLVEPNP_ITERATIVE) for u in uv]

    t_cvpnp, _ = timed(cv_pnp, args.runs)
    rows.append(("OpenCV solvePnP x 30 (ITERATIVE)", t_cvpnp, None))
    G = invert_transforms(F)
    cv_times = {}
    for k, m in HAND_EYE.items():
        t, (R, tv) = timed(lambda m=m: cv2.calibrateHandEye(list(F[:, :3, :3]), list(F[:, :3, 3]), list(C[:, :3, :3]),
                                                           list(C[:, :3, 3]), method=m), args.runs)
        cv_times[k] = t
        rows.append((f"OpenCV calibrateHandEye {k}", t, _T(R, tv)))
    for k, m in ROBOT_WORLD.items():
        t, out = timed(lambda m=m: cv2.calibrateRobotWorldHandEye(list(C[:, :3, :3]), list(C[:, :3, 3]),
                                                                  list(G[:, :3, :3]), list(G[:, :3, 3]), method=m),
                       args.runs)
        cv_times[k] = t
        rows.append((f"OpenCV calibrateRobotWorldHandEye {k}", t, invert_transforms(_T(out[2], out[3])[None])[0]))
    print(f"runs        {args.runs} (median)\n")
    print("| method | median time [ms] | robocal full / this | rotation error [deg] | translation error [mm] |")
    print("|---|---:|---:|---:|---:|")
    for name, t, T in rows:
        err = ("", "") if T is None else (f"{rotation_error_deg(T, truth):.4f}",
                                          f"{np.linalg.norm(T[:3, 3] - truth[:3, 3]):.3f}")
        print(f"| {name} | {t * 1e3:.2f} | {t_full / t:.1f} | {err[0]} | {err[1]} |")
    print(f"\nslowest OpenCV linear method: {max(cv_times.values()) * 1e3:.2f} ms; robocal full refinement is "
          f"{t_full / max(cv_times.values()):.0f}x its time and {t_full / min(cv_times.values()):.0f}x the fastest")


if __name__ == "__main__":
    main()
