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

The verdict table (issue 34 item 1, ``--fair-only`` prints it alone): the refinement against its
fair peer, OpenCV ``solvePnP`` once per image, OpenCV's SHAH (``calibrateRobotWorldHandEye``) as
the start and ``scipy.optimize.least_squares(method="lm")`` over the 12 unknowns (camera and target
pose) on every corner through ``cv2.projectPoints`` (the configuration of
``handeye_fair_comparison.py``), timed interleaved with robocal's default ``refine_hand_eye``
(per-image flange corrections under the 0.05 mm / 0.01 deg prior) and ``robot_pose_sigma=None``
(``--exact-poses``: the same 12 unknowns), each from the same corners, at ``--images`` (30 and 100);
medians, the ratio of medians and the median of per-repeat ratios, and the camera pose difference
between robocal's exact-pose fit and the peer's (the same least-squares problem).
Run: ``python benchmarks/bench_handeye.py --fair-only [--images 30 100] [--repeat 7] [--auto]``
(``--auto`` adds ``robot_pose_sigma="auto"``, the command line's default: both noise models and a
5-fold cross-validation, about 12 fits).
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


def opencv_scipy_refinement(F, uv, X, camera):
    """The fair peer: ``T_flange_camera`` (4, 4) by OpenCV solvePnP per image, OpenCV SHAH and SciPy
    LM over the 12 unknowns (module docstring; eye-in-hand)."""
    from handeye_fair_comparison import _pnp, scipy_refinement

    K, D = camera.matrix, np.array(camera.distortion)
    C = _pnp(uv, X, K, D)
    B = invert_transforms(F)
    R_bw, t_bw, R_gc, t_gc = cv2.calibrateRobotWorldHandEye(list(C[:, :3, :3]), list(C[:, :3, 3]), list(B[:, :3, :3]),
                                                            list(B[:, :3, 3]), method=cv2.CALIB_ROBOT_WORLD_HAND_EYE_SHAH)
    cam0 = invert_transforms(_T(R_gc, t_gc)[None])[0]
    target0 = invert_transforms(_T(R_bw, t_bw)[None])[0]
    return scipy_refinement(F, uv, X, K, D, cam0, target0)


def fair(n_images: int, repeat: int, auto: bool = False, seed: int = 0) -> dict:
    """Interleaved timings of robocal (default, exact poses[, auto]) and the fair peer: medians [s],
    paired ratios robocal / peer and the exact fit's difference from the peer's."""
    import warnings

    sim = simulate_hand_eye(seed, n_images=n_images)
    F, uv, X, cam = sim.T_base_flange, sim.image_points, sim.target_points, sim.camera
    runs = {"default": lambda: refine_hand_eye(F, uv, X, cam),
            "exact": lambda: refine_hand_eye(F, uv, X, cam, robot_pose_sigma=None),
            "peer": lambda: opencv_scipy_refinement(F, uv, X, cam)}
    if auto:
        runs["auto"] = lambda: refine_hand_eye(F, uv, X, cam, robot_pose_sigma="auto")
    out = {}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for k, fn in runs.items():  # warm-up (imports, caches)
            out[k] = fn()
        times = {k: [] for k in runs}
        for _ in range(repeat):
            for k, fn in runs.items():
                t = time.perf_counter()
                fn()
                times[k].append(time.perf_counter() - t)
    peer = np.array(times["peer"])
    res = {"images": n_images, "median": {k: statistics.median(v) for k, v in times.items()},
           "paired": {k: float(np.median(np.array(v) / peer)) for k, v in times.items() if k != "peer"},
           "exact_vs_peer_mm": float(np.linalg.norm(out["exact"].camera_pose[:3, 3] - out["peer"][:3, 3])),
           "exact_vs_peer_deg": rotation_error_deg(out["exact"].camera_pose, out["peer"]),
           "iterations": {k: out[k].message.split(" iterations")[0].split()[-1] for k in runs if k != "peer"}}
    return res


def print_fair(rows) -> None:
    print("| images | robocal default (flange corrections, prior) | robocal exact poses (12 unknowns) | "
          "OpenCV solvePnP + SHAH + SciPy LM (12 unknowns) | default / peer (paired) | exact / peer (paired) | "
          "exact vs peer camera pose |" + (" robocal auto (CLI default) / peer |" if "auto" in rows[0]["median"] else ""))
    print("|---:|---:|---:|---:|---:|---:|---:|" + ("---:|" if "auto" in rows[0]["median"] else ""))
    for r in rows:
        m, p = r["median"], r["paired"]
        line = (f"| {r['images']} | {m['default'] * 1e3:.1f} ms | {m['exact'] * 1e3:.1f} ms | {m['peer'] * 1e3:.1f} ms | "
                f"x{m['default'] / m['peer']:.2f} (x{p['default']:.2f}) | x{m['exact'] / m['peer']:.2f} "
                f"(x{p['exact']:.2f}) | {r['exact_vs_peer_mm']:.1e} mm / {r['exact_vs_peer_deg']:.1e} deg |")
        if "auto" in m:
            line += f" {m['auto'] * 1e3:.0f} ms, x{m['auto'] / m['peer']:.1f} (x{p['auto']:.1f}) |"
        print(line)


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--runs", type=int, default=7)
    ap.add_argument("--fair-only", action="store_true", help="only the verdict table against the fair peer")
    ap.add_argument("--images", type=int, nargs="+", default=[30, 100], help="image counts of the verdict table")
    ap.add_argument("--repeat", type=int, default=7, help="interleaved repeats of the verdict table")
    ap.add_argument("--auto", action="store_true", help="add robot_pose_sigma='auto' (the CLI default) to the table")
    args = ap.parse_args(argv)
    if machine_info:
        print("\n".join(machine_info([f"opencv      {cv2.__version__}"])))
    print(f"load average at start: {os.getloadavg()[0]:.1f}\n")
    rows = [fair(n, args.repeat, args.auto) for n in args.images]
    print_fair(rows)
    print(f"\n{args.repeat} interleaved repeats, medians; paired = median of per-repeat ratios; load average at the "
          f"end {os.getloadavg()[0]:.1f}\n")
    if args.fair_only:
        return
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
