"""The HALCON paper's study in simulation (issue 14 item 6; METHODS.md section 3, "Hand-eye"):
accuracy of the hand-eye transform against the number of images and the camera model.

Set-up (:func:`robocal.sim.cameras.handeye_points.simulate_hand_eye`): eye-in-hand, 1280 x 1024 camera,
f = 1400 px, the true lens a full Brown-Conrady one (k1 -0.25, k2 0.12, p1 0.0012, p2 -0.0008,
k3 -0.03), an 11 x 8 board of 20 mm squares seen from 450-750 mm with tilts up to 35 deg,
0.3 px corner noise, 0.05 mm / 0.01 deg robot pose noise. For each number of images and each
camera *model used for the calibration* (none: pinhole; radial: k1, k2; brown: k1, k2, p1, p2,
k3; division: one kappa) and each seed, the camera is calibrated from the same images
(:func:`robocal.handeye.calibrate_camera`, HALCON's workflow: intrinsics first), then the hand-eye
transform is solved (linear, Tsai–Lenz, as the paper, on the PnP poses of that camera) and refined
(:func:`robocal.handeye.refine_hand_eye`, the model's intrinsics and distortion refined jointly).
Errors against the truth; medians over the seeds.

    python benchmarks/handeye_study.py [--seeds 8] [--png docs/handeye_study.png]

prints a Markdown table and writes the plot. Single-threaded BLAS (a shared machine); ~5 min.
"""

from __future__ import annotations

import argparse
import os
import sys
import time

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("MKL_NUM_THREADS", "1")

import numpy as np  # noqa: E402

from robocal.handeye import HandEyeError, calibrate_camera, refine_hand_eye  # noqa: E402
from robocal.handeye.refine import rotation_error_deg  # noqa: E402
from robocal.sim.cameras.handeye_points import CAMERA_MODELS, simulate_hand_eye  # noqa: E402

IMAGES = (3, 4, 5, 6, 8, 10, 15, 20, 30)
MODELS = {"none": ("brown", 5, ("k1", "k2", "p1", "p2", "k3")), "radial": ("brown", 5, ("p1", "p2", "k3")),
          "brown": ("brown", 5, ()), "division": ("division", 1, ())}


def one_run(seed: int, n: int, model: str) -> tuple:
    """(refined rot [deg], refined trans [mm], tsai rot, tsai trans, calibration RMS [px]) or NaNs."""
    sim = simulate_hand_eye(1000 + seed, n_images=n, camera=CAMERA_MODELS["brown"])
    kind, nd, fix = MODELS[model]
    try:
        cal = calibrate_camera(sim.image_points, sim.target_points, (1280, 1024), model=kind, n_distortion=nd, fix=fix)
        names = ("k1", "k2", "p1", "p2", "k3") if kind == "brown" else ("kappa",)
        free = ["fx", "fy", "cx", "cy"] + [d for d in names if d not in fix]
        res = refine_hand_eye(sim.T_base_flange, sim.image_points, sim.target_points, cal.camera,
                              refine_intrinsics=free)
    except HandEyeError:
        return (np.nan,) * 5
    tsai = res.linear["tsai"][0]
    t = sim.camera_pose
    return (rotation_error_deg(res.camera_pose, t), float(np.linalg.norm(res.camera_pose[:3, 3] - t[:3, 3])),
            rotation_error_deg(tsai, t), float(np.linalg.norm(tsai[:3, 3] - t[:3, 3])), cal.rms_px)


def study(seeds: int) -> dict:
    out = {}
    for model in MODELS:
        for n in IMAGES:
            runs = np.array([one_run(s, n, model) for s in range(seeds)])
            out[model, n] = np.nanmedian(runs, axis=0)
            print(f"  {model:9s} {n:3d} images: refined {out[model, n][0]:.4f} deg {out[model, n][1]:.3f} mm; "
                  f"tsai {out[model, n][2]:.4f} deg {out[model, n][3]:.3f} mm", file=sys.stderr)
    return out


def table(res: dict) -> str:
    head = "| images | " + " | ".join(f"{m} rot [deg] | {m} trans [mm]" for m in MODELS) + " |"
    sep = "|---:|" + "---:|---:|" * len(MODELS)
    rows = [head, sep]
    for n in IMAGES:
        rows.append(f"| {n} | " + " | ".join(f"{res[m, n][0]:.3f} | {res[m, n][1]:.2f}" for m in MODELS) + " |")
    rows.append("")
    rows.append("Linear (Tsai–Lenz) on the same calibrated cameras:")
    rows.append("")
    rows += [head, sep]
    for n in IMAGES:
        rows.append(f"| {n} | " + " | ".join(f"{res[m, n][2]:.3f} | {res[m, n][3]:.2f}" for m in MODELS) + " |")
    return "\n".join(rows)


def plot(res: dict, path: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(10, 4))
    for model, color in zip(MODELS, ("tab:red", "tab:orange", "tab:green", "tab:blue")):
        for k, ax in enumerate(axes):
            ax.plot(IMAGES, [res[model, n][k] for n in IMAGES], "o-", color=color, label=f"{model}, refined")
            ax.plot(IMAGES, [res[model, n][k + 2] for n in IMAGES], "x--", color=color, alpha=0.6,
                    label=f"{model}, Tsai-Lenz")
    for ax, what in zip(axes, ("rotation error [deg]", "translation error [mm]")):
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xticks(IMAGES)
        ax.set_xticklabels([str(n) for n in IMAGES])
        ax.set_xlabel("number of images")
        ax.set_ylabel(what)
        ax.grid(True, which="both", alpha=0.3)
    axes[0].legend(fontsize=7, ncol=2)
    fig.suptitle("Hand-eye accuracy vs images and camera model (simulation, median over seeds; true lens: full Brown)",
                 fontsize=9)
    fig.tight_layout()
    tmp = path + ".tmp.png"
    fig.savefig(tmp, dpi=110)
    os.replace(tmp, path)


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seeds", type=int, default=8)
    ap.add_argument("--png", default=os.path.join(os.path.dirname(__file__), "..", "docs", "handeye_study.png"))
    args = ap.parse_args(argv)
    t0 = time.perf_counter()
    res = study(args.seeds)
    print(table(res))
    plot(res, args.png)
    print(f"\n{args.seeds} seeds per cell, {time.perf_counter() - t0:.0f} s; plot: {args.png}")


if __name__ == "__main__":
    main()
