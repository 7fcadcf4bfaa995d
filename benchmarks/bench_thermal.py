"""Thermal compensation speed benchmark (issue 5 acceptance).

Run from the repository root (robocal installed in the environment)::

    python benchmarks/bench_thermal.py             # 7 repeats
    python benchmarks/bench_thermal.py --repeat 15
    python benchmarks/bench_thermal.py --experiment 20            # + table 5-2 over 20 seeds, timed

Times, on one thread, with the simulated thesis-like cell (KR150 R3100, DH + beta):

* **full screening**: :func:`robocal.thermal.screening.screen_parameters`, 24 -> 8 parameters on
  90 cycles x 20 sphere poses and 34 monitored points (the problem -- coefficient matrices, the
  sphere differences and the monitored residuals -- is built once beforehand and timed separately).
  Target <= 2 s.
* **online cycle**: :func:`robocal.thermal.online_cycle` -- identify the 8 screened deltas from 6
  sphere poses and correct a 50-point taught program by iterative IK. Target <= 5 ms median.
* **the experiment** (``--experiment N``): :func:`robocal.workflows.thermal.seeds.run_thermal_seeds`
  on the realistic preset, N seeds of 90 cycles, once (wall clock per seed, with ``--resamples``
  bootstrap resamples of the screening run), and its table. This is where the multi-seed
  figures of docs/thermal.md come from; the unit tests run a 20-cycle version.

Every figure is the median (and the minimum) of the repeats; short calls are looped so a repeat
takes ~0.2 s. The numba kernels are compiled / loaded from cache before anything is timed.
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "NUMBA_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS",
             "VECLIB_MAXIMUM_THREADS", "NUMEXPR_NUM_THREADS"):
    os.environ[_var] = "1"

import argparse  # noqa: E402
import platform  # noqa: E402
import time  # noqa: E402
import timeit  # noqa: E402

import numpy as np  # noqa: E402

from robocal.sim.thermal.simulator import ThermalCell, standard_schedules  # noqa: E402
from robocal.thermal.screening import screen_parameters, select_online_poses  # noqa: E402
from robocal.workflows.thermal.runs import screening_problem  # noqa: E402


def _time(fn, repeat: int, target_s: float = 0.2):
    """(median, min) seconds per call over ``repeat`` repeats, each looped to ~target_s."""
    fn()
    t0 = time.perf_counter()
    fn()
    once = time.perf_counter() - t0
    number = max(1, int(target_s / max(once, 1e-9)))
    per = np.array(timeit.repeat(fn, number=number, repeat=repeat)) / number
    return float(np.median(per)), float(per.min())


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=7)
    ap.add_argument("--seed", type=int, default=2024)
    ap.add_argument("--experiment", type=int, default=0, metavar="N", help="also run table 5-2 over N seeds")
    ap.add_argument("--resamples", type=int, default=0, help="bootstrap resamples per seed in --experiment")
    ap.add_argument("--preset", default="realistic", choices=("ideal", "realistic"))
    args = ap.parse_args(argv)

    print(f"python {platform.python_version()}, numpy {np.__version__}, {platform.machine()}, one thread")
    cell = ThermalCell.standard(args.seed)
    run = cell.simulate(standard_schedules(7)[0], 1)
    t0 = time.perf_counter()
    prob = screening_problem(cell, run)
    t_build = time.perf_counter() - t0
    print(f"screening problem: {prob.n_cycles} cycles x {prob.n_poses} sphere poses, {prob.n_directions} monitored "
          f"directions, {len(prob.names)} candidates (built in {t_build * 1e3:.1f} ms)")

    rows = []
    result = screen_parameters(prob)
    med, best = _time(lambda: screen_parameters(prob), args.repeat)
    rows.append(("full screening 24 -> 8 (90 x 20)", med, best, 2.0))
    med, best = _time(lambda: screening_problem(cell, run), args.repeat)
    rows.append(("  building the screening problem", med, best, None))
    print(f"selected: {', '.join(result.selected)} (lambda {result.lam:.2f} % on the screening run)")

    try:
        from robocal.thermal import online_cycle
    except ImportError:                                       # pragma: no cover - the other module is missing
        online_cycle = None
    if online_cycle is None:
        rows.append(("online cycle (6 poses, 8 deltas, 50 points)", float("nan"), float("nan"), 5e-3))
    else:
        subset = result.selected
        idx = select_online_poses(prob, subset, 6)
        q6, P6, Pc6 = run.q_sphere[idx], run.sphere[60, idx], run.sphere_cold[idx]
        rng = np.random.default_rng(5)
        q_prog = np.vstack([cell.q_monitor, cell.q_monitor[:16] + rng.normal(0, 0.02, (16, 6))])   # 50 points
        model = cell.model
        oc = online_cycle(model, cell.T_sensor_base, cell.P_e, q6, P6, subset, q_prog, P_cold=Pc6)
        print(f"online cycle check: {oc.compensation.summary()}")
        med, best = _time(lambda: online_cycle(model, cell.T_sensor_base, cell.P_e, q6, P6, subset, q_prog, P_cold=Pc6),
                          args.repeat)
        rows.append(("online cycle (6 poses, 8 deltas, 50 points)", med, best, 5e-3))

    print()
    print(f"{'what':<46} {'median':>11} {'best':>11} {'target':>9}  ")
    for name, med, best, target in rows:
        mark = "" if target is None else ("ok" if med <= target else "MISS")
        tg = "" if target is None else f"{target * 1e3:.0f} ms"
        print(f"{name:<46} {med * 1e3:>8.2f} ms {best * 1e3:>8.2f} ms {tg:>9}  {mark}")
    if args.experiment > 0:
        _experiment(args.experiment, args.resamples, args.preset)


def _experiment(n: int, resamples: int, preset: str) -> None:
    """Table 5-2 over ``n`` seeds, timed once (it is minutes, not milliseconds)."""
    from robocal.workflows.thermal.seeds import format_seeds_table, run_thermal_seeds

    t0 = time.perf_counter()
    res = run_thermal_seeds(preset=preset, seeds=n, resamples=resamples)
    dt = time.perf_counter() - t0
    print()
    print(format_seeds_table(res))
    print(f"experiment: {n} seeds x 3 runs x 90 cycles ({preset}, {resamples} resamples): {dt:.1f} s, "
          f"{dt / n:.2f} s per seed")


if __name__ == "__main__":
    main()
