"""GA-RBF learned IK seed (issue 17), measured against the exact solvers.

Run from the repository root (robocal installed with the ``ik-net`` extra for DEAP)::

    python benchmarks/bench_ik_seed.py            # 20 000 samples, GA 10 x 5 (a few minutes)
    python benchmarks/bench_ik_seed.py --quick    # 5 000 samples, GA 6 x 2

For the ABB IRB140 (the thesis's robot, closed form exists) and a "calibrated" IRB140 with Hayati beta
tilts and length errors (no closed form): train a network (seeded), then on held-out poses of the
trained branch report the network's raw joint / position / rotation error (median, p95, max), the
domain check's pass rate on those poses and on poses that need J1 = 175 deg (outside the branch), the
query time for 10 000 poses, and batched damped least squares (tol 1e-6 mm, 1e-9 rad, 100 iterations)
from four starts: the network, the middle of the joint ranges ("nominal"), all zeros, and the
closed-form solution of branch 0 (exact for the IRB140; of the beta-free nominal shape, then refined,
for the tilted model). Then the same for the UR10, which has no closed form in robocal at all: its
branch is a joint box (elbow J3 and wrist J5 on one side, J1 within +-90 deg), and the fixed starts are
compared with the middle of that box. Times are medians of several repeats; one thread.
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "NUMBA_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_var] = "1"
# Kernel speed is measured: the compiled kernels from the first call (not numpy until the work pays).
os.environ.setdefault("ROBOCAL_KERNELS", "compiled")

import argparse  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402
from _machine import machine_info  # noqa: E402  (benchmarks/_machine.py)

from robocal.kinematics import ik_analytic, ik_numeric  # noqa: E402
from robocal.kinematics.convert import dh_with_beta  # noqa: E402
from robocal.kinematics.ik_net import (  # noqa: E402
    joint_box_branch,
    on_branch,
    reference_model,
    sample_branch,
    train_ik_network,
)
from robocal.kinematics.ik_net.network import pose_error_stats  # noqa: E402
from robocal.robots import load_robot  # noqa: E402


def tilted_irb140():
    return dh_with_beta(load_robot("abb_irb140")).with_params(
        beta2=np.radians(0.3), beta3=np.radians(-0.2), beta5=np.radians(0.15), a2=360.4, d4=379.7)


def median_time(fn, repeats):
    times = []
    for _ in range(repeats):
        t = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t)
    return float(np.median(times)), out


def ik_row(label, model, T, q_true, q0, repeats, branch, ref):
    dt, r = median_time(lambda: ik_numeric(model, T, q0), repeats)
    ok = r.converged
    same = ok & on_branch(ref, r.q, branch)
    return (f"| {label} | {100 * ok.mean():.1f} | {100 * same.mean():.1f} | {np.median(r.iterations):.0f} | "
            f"{np.percentile(r.iterations, 95):.0f} | {1000 * dt:.0f} |")


def run(name, model, n_samples, population, generations, n_test, repeats, seed, branch=None):
    print(f"\n### {name}\n")
    t = time.perf_counter()
    net = train_ik_network(model, n_samples, seed, population=population, generations=generations, branch=branch)
    train_s = time.perf_counter() - t
    br = net.branch
    ref = None if br.index < 0 else reference_model(model)
    q = sample_branch(ref, br, n_test, np.random.default_rng(seed + 1000))
    T = model.fk(q)
    st = pose_error_stats(model, net.predict_joints(T), q, T)
    s = net.structure
    h = net.stats["ga_history"]
    print(f"training: {n_samples} FK samples, GA population {population} x {generations} generations: "
          f"{train_s:.1f} s; chosen K = {s.n_centres}, width {s.width_factor:.2f}, lam {s.reg:.1e}, "
          f"position weight {s.position_weight:.2f}; held-out poses: {n_test}")
    print(f"GA: validation RMS joint error {np.degrees(h[0]['best_rms_rad']):.2f} deg (best of generation 0, "
          f"which includes the untuned default) -> {np.degrees(h[-1]['best_rms_rad']):.2f} deg after "
          f"{len(h) - 1} generations; {h[-1]['evaluations']} structures evaluated\n")
    print("| network raw error | median | p95 | max |\n|---|---|---|---|")
    for key, label in (("joint_deg", "joint (worst joint) [deg]"), ("position_mm", "position [mm]"),
                       ("rotation_deg", "rotation [deg]")):
        v = st[key]
        print(f"| {label} | {v['median']:.2f} | {v['p95']:.2f} | {v['max']:.2f} |")
    pred = net.seed(model, T)
    q_back = q.copy()
    q_back[:, 0] = np.radians(175.0)
    back = net.seed(model, model.fk(q_back))
    print(f"\ndomain check: {100 * pred.in_domain.mean():.1f} % of held-out branch poses pass "
          f"({', '.join(f'{k} {v}' for k, v in zip(*np.unique(pred.status, return_counts=True)))}); "
          f"{100 * back.in_domain.mean():.1f} % of poses needing J1 = 175 deg pass")
    T10 = model.fk(sample_branch(ref, br, 10000, np.random.default_rng(seed + 2000)))
    t_raw, _ = median_time(lambda: net.predict_joints(T10), repeats)
    t_chk, _ = median_time(lambda: net.seed(model, T10), repeats)
    text = f"query 10 000 poses: network {1000 * t_raw:.0f} ms raw, {1000 * t_chk:.0f} ms with the domain check"
    if ref is not None:
        t_cf, _ = median_time(lambda: ik_analytic(ref, T10), repeats)
        text += (f"; closed form (8 branches{'' if ref is model else ', nominal shape'}) {1000 * t_cf:.0f} ms "
                 f"(network / closed form {t_raw / t_cf:.1f}x)")
    print(text + "\n")
    print(f"| IK start ({n_test} poses) | converged [%] | on trained branch [%] | median iterations | "
          "p95 iterations | time [ms] |\n|---|---|---|---|---|---|")
    print(ik_row("GA-RBF network seed", model, T, q, pred.q, repeats, br, ref))
    print(ik_row("nominal: middle of the joint ranges", model, T, q, model.limits.mean(axis=1), repeats, br, ref))
    print(ik_row("zero joints", model, T, q, np.zeros(6), repeats, br, ref))
    if ref is None:
        print(ik_row("middle of the branch's joint box", model, T, q, br.box.mean(axis=1), repeats, br, ref))
        print("| closed form | (none for this robot) | | | | |")
        return
    dt, (q_all, valid) = median_time(lambda: ik_analytic(ref, T), repeats)
    q_cf = np.where(valid[:, :1], q_all[:, 0], 0.0)
    if ref is model:
        r = ik_numeric(model, T, q_cf, max_iterations=0)
        print(f"| closed form, branch 0 (exact, no iterations) | {100 * r.converged.mean():.1f} | "
              f"{100 * (r.converged & on_branch(ref, q_cf, br)).mean():.1f} | 0 | 0 | {1000 * dt:.0f} |")
    else:
        print(ik_row(f"closed form of the nominal shape, branch 0 ({1000 * dt:.0f} ms), refined", model, T, q, q_cf,
                     repeats, br, ref))


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--seed", type=int, default=1)
    a = ap.parse_args()
    n, pop, gens, n_test, rep = (5000, 6, 2, 1000, 3) if a.quick else (20000, 10, 5, 2000, 5)
    print("\n".join(machine_info([f"settings    samples {n}, GA {pop} x {gens}, seed {a.seed}, one thread"])))
    run("ABB IRB140 (nominal, closed form exists)", load_robot("abb_irb140"), n, pop, gens, n_test, rep, a.seed)
    run("ABB IRB140 with beta tilts (beta2 0.3, beta3 -0.2, beta5 0.15 deg; a2 +0.4, d4 -0.3 mm; no closed form)",
        tilted_irb140(), n, pop, gens, n_test, rep, a.seed)
    ur10 = load_robot("ur10")
    box = {"J1": (-90, 90), "J2": (-170, -10), "J3": (10, 150), "J5": (10, 150)}
    run("UR10 (offset wrist: no closed form in robocal; branch = joint box J1 -90..90, J2 -170..-10, J3 10..150, "
        "J5 10..150 deg, others -150..150)", ur10, n, pop, gens, n_test, rep, a.seed,
        branch=joint_box_branch(ur10, {k: np.radians(v) for k, v in box.items()}))


if __name__ == "__main__":
    main()
