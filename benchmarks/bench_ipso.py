"""IPSO speed: 2000 generations x 20 particles x 32 poses, 24 parameters (the IPSO paper's run,
220 s in MATLAB), median of 5 runs; target <= 1 s and >= 10x faster than pyswarms.

Objective: (7) on the ER10L-C10 simulation (``robocal.workflows.calibration.ipso_study.er10l_experiment``,
seed 0, degree-scale joint noise), 24 identifiable MDH parameters, box ±0.01 rad / ±0.5 mm.
Rows (all in one process, one thread):

* robocal ``run_pso`` + ``SwarmObjective`` -- the whole swarm per generation in one compiled call
  that returns objective (7) per particle (FK, residuals and rotation angles fused; what
  ``solve_swarm`` runs);
* pyswarms ``GlobalBestPSO`` (w = K = 0.7298, c1 = c2 = K * 2.05: Clerc's constriction written in
  inertia form, the same update) on the same objective computed per particle through the
  problem's own residuals (``objective_at``: one ``Problem.evaluate`` per particle, as one would
  hand a library objective without robocal's batched path);
* pyswarms on robocal's batched objective: the fair peer (same objective, only the swarm loop
  differs); its ratio is printed first.

Rows are timed interleaved (one run of each in turn).

If pyswarms is missing, a plain numpy swarm of the same algorithm with a per-particle loop
replaces the pyswarms rows. Run: ``python benchmarks/bench_ipso.py [--runs 5] [--generations 2000]``.
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "NUMBA_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_var] = "1"

import argparse  # noqa: E402
import logging  # noqa: E402
import statistics  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402

from robocal.calib.swarm import SwarmObjective, constriction_factor, objective_at, run_pso, search_box  # noqa: E402
from robocal.workflows.calibration.ipso_study import er10l_experiment  # noqa: E402

try:
    from _machine import machine_info  # noqa: E402
except ImportError:  # run from elsewhere
    machine_info = None


def per_particle(problem):
    """Objective (7) one particle at a time (a Python loop over particles)."""
    start = problem.initial_state()

    def f(X):
        return np.array([objective_at(problem, problem.retract(start, x)) for x in X])

    return f


def plain_numpy_pso(fun, lo, up, particles, generations, seed):
    """The same constriction swarm, textbook style: one objective call per particle."""
    rng = np.random.default_rng(seed)
    K = constriction_factor()
    x = lo + rng.random((particles, lo.size)) * (up - lo)
    v = (rng.random((particles, lo.size)) - 0.5) * (up - lo)
    f = np.array([fun(xi[None])[0] for xi in x])
    pb, pf = x.copy(), f.copy()
    g = pb[np.argmin(pf)].copy()
    for _ in range(generations):
        r1, r2 = rng.random(x.shape), rng.random(x.shape)
        v = np.clip(K * (v + 2.05 * r1 * (pb - x) + 2.05 * r2 * (g - x)), lo - up, up - lo)
        x = np.clip(x + v, lo, up)
        f = np.array([fun(xi[None])[0] for xi in x])
        better = f < pf
        pb[better], pf[better] = x[better], f[better]
        g = pb[np.argmin(pf)].copy()
    return float(pf.min())


def pyswarms_run(fun, lo, up, particles, generations, seed):
    import pyswarms as ps

    logging.getLogger("pyswarms").setLevel(logging.ERROR)
    K = constriction_factor()
    np.random.seed(seed)
    opt = ps.single.GlobalBestPSO(n_particles=particles, dimensions=lo.size, bounds=(lo, up),
                                  options={"w": K, "c1": K * 2.05, "c2": K * 2.05})
    cost, _ = opt.optimize(fun, iters=generations, verbose=False)
    return float(cost)


FAIR = "pyswarms GlobalBestPSO on robocal's batched objective"


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=5)
    ap.add_argument("--generations", type=int, default=2000)
    ap.add_argument("--particles", type=int, default=20)
    ap.add_argument("--fair-only", action="store_true", help="skip the per-particle pyswarms row (~15 s a run)")
    a = ap.parse_args(argv)
    if machine_info is not None:
        print("\n".join(machine_info()))
    prob = er10l_experiment(0, "deg").problem
    obj = SwarmObjective(prob)
    lo, up = search_box(prob.units, 0.01, 0.5)
    P, G = a.particles, a.generations
    run_pso(obj, lo, up, particles=P, generations=2, seed=0)  # compile / load the kernel
    print(f"problem: {len(prob.names)} parameters, {prob.n_poses} poses; {G} generations x {P} particles; "
          f"median of {a.runs} runs")
    rows = [("robocal run_pso + batched SwarmObjective",
             lambda r: run_pso(obj, lo, up, particles=P, generations=G, seed=r).best_f)]
    slow = per_particle(prob)
    try:
        import pyswarms  # noqa: F401

        rows.append((FAIR, lambda r: pyswarms_run(obj, lo, up, P, G, r)))
        if not a.fair_only:
            rows.append(("pyswarms GlobalBestPSO, objective per particle (Problem.evaluate)",
                         lambda r: pyswarms_run(slow, lo, up, P, G, r)))
    except ImportError:
        rows.append(("plain numpy swarm, objective per particle (pyswarms not installed)",
                     lambda r: plain_numpy_pso(slow, lo, up, P, G, r)))
    # interleaved: one run of each row in turn, so a change of the machine's load hits every row alike
    times = {name: [] for name, _ in rows}
    best = {}
    for r in range(a.runs):
        for name, fn in rows:
            t0 = time.perf_counter()
            best[name] = fn(r)
            times[name].append(time.perf_counter() - t0)
    base = statistics.median(times[rows[0][0]])
    if FAIR in times:
        paired = [p / q for p, q in zip(times[FAIR], times[rows[0][0]])]
        t_fair = statistics.median(times[FAIR])
        print(f"\nfair peer first: pyswarms on robocal's batched objective {t_fair:.3f} s, robocal {base:.3f} s: "
              f"pyswarms / robocal x{t_fair / base:.2f} (paired per run: median x{statistics.median(paired):.2f}, "
              f"range x{min(paired):.2f}-x{max(paired):.2f}); "
              f"{'robocal ahead' if t_fair / base > 1.05 else 'no lead' if t_fair / base >= 0.95 else 'pyswarms ahead'}")
    print("\n| implementation | median [s] | best [s] | best f [mm^2] | time / robocal |\n|---|---|---|---|---|")
    for name, _ in rows:
        t = statistics.median(times[name])
        print(f"| {name} | {t:.3f} | {min(times[name]):.3f} | {best[name]:.4g} | {t / base:.2f} |")


if __name__ == "__main__":
    main()
