"""Fleet calibration on Dask against a plain serial loop (issue 19).

Run from the repository root (robocal installed with the fleet extra)::

    python benchmarks/bench_fleet.py                 # 200 robots x 100 poses, 3 repeats
    python benchmarks/bench_fleet.py --robots 50 --repeat 2 --workers 2

In one run, on the same simulated fleet (seeded tracker campaigns of UR10, KUKA KR150 R3100 and
ABB IRB140 robots, each with its own hidden true parameters):

* **serial loop**: ``run_calibration(model, csv, out, report=False)`` for every robot, one after
  the other in this process (what a user would script without robocal fleet);
* **fleet on a local cluster**: :func:`robocal.workflows.fleet.calibrate.run_fleet_calibration` with a
  ``distributed.LocalCluster`` of ``--workers`` single-threaded worker processes (the default of
  ``robocal fleet calibrate``), no reports, no history (as the loop), into a fresh folder each
  repeat; the cluster is started once beforehand (its start-up is printed separately);
* **plain processes** (the machine's ceiling, no Dask): ``--workers`` processes started with
  ``multiprocessing`` (spawn), each running the serial loop over its share of the robots, timed
  from the moment all are ready; on a shared VM whose two vCPUs are not two free cores this is
  what any pool can reach, so the fleet is read against it as well as against the ideal;
* **per-task overhead**: (a) the round trip of an empty task (1,000 no-op tasks through the same
  client, wall time / 1,000 x workers), (b) in the fleet run, wall x workers minus the summed
  in-task time, per robot;
* the CPU time of the script's own process during the fleet runs (client and scheduler: they
  share the cores with the workers), per robot and per task (by default one long task per worker
  that takes robots one by one; ``--robots-per-task N`` for fixed groups of N, one task each);
* an estimate for 1,000 robots from the measured per-robot time and overhead.

Every figure is the median of the repeats (serial and fleet interleaved, so load changes affect both).
BLAS and numba are held to one thread per process.
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "NUMBA_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_var] = "1"

import argparse  # noqa: E402
import shutil  # noqa: E402
import statistics  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _machine import machine_info  # noqa: E402

MODELS = ("ur10", "kuka_kr150_r3100", "abb_irb140")


def make_fleet(d: Path, n_robots: int, n_poses: int) -> Path:
    from robocal.workflows.calibration.simulate import simulate_tracker

    lines = ["[options]", "holdout = 0.2", "seed = 0", ""]
    for i in range(n_robots):
        model = MODELS[i % len(MODELS)]
        simulate_tracker(model, d / f"r{i:04d}.csv", n_poses=n_poses, noise_mm=0.02, seed=i)
        lines += ["[[robot]]", f'id = "r{i:04d}"', f'model = "{model}"', f'measurements = "r{i:04d}.csv"', ""]
    p = d / "fleet.toml"
    p.write_text("\n".join(lines))
    return p


def serial_loop(fleet_file: Path, out: Path, limit: int | None = None) -> float:
    from robocal.io.fleet_file import read_fleet
    from robocal.workflows.calibration.calibrate import run_calibration

    t0 = time.perf_counter()
    for e in read_fleet(fleet_file).entries[:limit]:
        run_calibration(e.model, e.measurements, out / e.id, report=False, **e.options)
    return time.perf_counter() - t0


def fleet_run(client, fleet_file: Path, out: Path, per_task=None):
    """Wall time, summed in-task time and this (client + scheduler) process's CPU time of one run."""
    from robocal.workflows.fleet.calibrate import run_fleet_calibration

    t0, c0 = time.perf_counter(), time.process_time()
    r = run_fleet_calibration(fleet_file, out, client=client, report=False, per_task=per_task)
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    rows = r["summary"]["robots"]
    assert all(row["status"] == "ok" for row in rows), [row for row in rows if row["status"] != "ok"][:2]
    return wall, sum(row["seconds"] for row in rows), cpu


def _share(fleet_file, out, k, workers, barrier, spans):
    """One plain process of the ceiling row: warm up on its share (as each fleet worker is warmed by the
    fleet's warm-up run: the kernel policy loads compiled code only once a process's work has paid
    for it, so a three-robot warm-up left the numba load inside the timed loop), wait for the others,
    then the loop over its share."""
    from robocal.io.fleet_file import read_fleet
    from robocal.workflows.calibration.calibrate import run_calibration

    entries = read_fleet(fleet_file).entries[k::workers]
    for e in entries:
        run_calibration(e.model, e.measurements, Path(out) / f"warm{k}" / e.id, report=False, **e.options)
    barrier.wait(timeout=600)
    t0 = time.perf_counter()
    for e in entries:
        run_calibration(e.model, e.measurements, Path(out) / e.id, report=False, **e.options)
    spans.put((t0, time.perf_counter()))


def plain_processes(fleet_file: Path, out: Path, workers: int) -> float:
    """Wall time of ``workers`` plain processes sharing the fleet, from their common start (after
    start-up and warm-up) to the last one's end."""
    import multiprocessing

    ctx = multiprocessing.get_context("spawn")
    barrier, spans = ctx.Barrier(workers), ctx.Queue()
    procs = [ctx.Process(target=_share, args=(fleet_file, out, k, workers, barrier, spans)) for k in range(workers)]
    for p in procs:
        p.start()
    got = [spans.get(timeout=3600) for _ in procs]
    for p in procs:
        p.join()
    return max(t1 for _, t1 in got) - min(t0 for t0, _ in got)


def _noop(x):
    return x


def empty_task_overhead(client, n: int = 1000) -> float:
    from distributed import wait

    wait(client.map(_noop, range(50), pure=False))
    t0 = time.perf_counter()
    futs = client.map(_noop, range(n), pure=False)
    wait(futs)
    return (time.perf_counter() - t0) / n


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--robots", type=int, default=200)
    ap.add_argument("--poses", type=int, default=100)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--workers", type=int, default=None, help="local cluster size (default: usable CPUs)")
    ap.add_argument("--robots-per-task", type=int, default=None,
                    help="robots per Dask task in fixed groups (default: robocal fleet calibrate's: each worker "
                         "takes robots one by one)")
    args = ap.parse_args()
    from robocal.workflows.fleet.cluster import default_workers, fleet_client

    workers = args.workers or default_workers()
    for line in machine_info([f"fleet       {args.robots} robots x {args.poses} poses, {workers} workers, "
                              f"{args.repeat} repeats"]):
        print(line)
    tmp = Path(tempfile.mkdtemp(prefix="bench-fleet-"))
    try:
        t0 = time.perf_counter()
        fleet_file = make_fleet(tmp, args.robots, args.poses)
        print(f"simulated the fleet's campaigns in {time.perf_counter() - t0:.1f} s")
        serial_loop(fleet_file, tmp / "warm")  # the whole fleet once, as the fleet and the plain processes are warmed
        t0 = time.perf_counter()
        # the cluster robocal fleet calibrate starts (single-threaded workers, no worker profiler)
        with fleet_client(workers=workers) as client:
            client.run(lambda: __import__("robocal.workflows.calibration.calibrate"))
            start = time.perf_counter() - t0
            fleet_run(client, fleet_file, tmp / "fleet-warm", args.robots_per_task)  # kernels from cache
            serial, fleet, busy, plain, client_cpu = [], [], [], [], []
            for k in range(args.repeat):
                serial.append(serial_loop(fleet_file, tmp / f"serial{k}"))
                w, b, c = fleet_run(client, fleet_file, tmp / f"fleet{k}", args.robots_per_task)
                fleet.append(w)
                busy.append(b)
                client_cpu.append(c)
                plain.append(plain_processes(fleet_file, tmp / f"plain{k}", workers))
                print(f"  repeat {k + 1}: serial {serial[-1]:.2f} s, fleet {w:.2f} s, "
                      f"plain processes {plain[-1]:.2f} s")
            empty = statistics.median(empty_task_overhead(client) for _ in range(3))
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    s, f, b = statistics.median(serial), statistics.median(fleet), statistics.median(busy)
    pp = statistics.median(plain)
    n = args.robots
    per_robot = s / n
    per_task_overhead = (f * workers - b) / n
    print()
    print(f"{'':<44}{'median [s]':>12}{'per robot [ms]':>16}")
    print(f"{'serial loop (run_calibration, no report)':<44}{s:>12.2f}{1e3 * per_robot:>16.1f}")
    print(f"{f'fleet, local cluster ({workers} worker processes)':<44}{f:>12.2f}{1e3 * f / n:>16.1f}")
    print(f"{f'{workers} plain processes (no Dask; the ceiling)':<44}{pp:>12.2f}{1e3 * pp / n:>16.1f}")
    print(f"ratio serial / fleet: {s / f:.2f}x   (ideal {workers}x; plain processes reach {s / pp:.2f}x: "
          f"the fleet gets {100 * pp / f:.1f} % of that; per repeat "
          f"{', '.join(f'{100 * b / a:.0f}' for a, b in zip(fleet, plain))} %, their median "
          f"{statistics.median(100 * b / a for a, b in zip(fleet, plain)):.1f} %)")
    print(f"local cluster start-up (not in the fleet time): {start:.1f} s")
    print(f"per-task overhead: empty task {1e3 * empty * workers:.2f} ms of a worker; in the fleet run "
          f"{1e3 * per_task_overhead:.1f} ms per robot (wall x workers - time inside the tasks) = "
          f"{100 * per_task_overhead / (per_task_overhead + b / n):.1f} % of a task")
    from robocal.workflows.fleet.calibrate import task_groups

    if args.robots_per_task:
        n_tasks = len(task_groups(range(n), args.robots_per_task))
        how = f"fixed groups of {args.robots_per_task} robots"
    else:
        n_tasks, how = workers, "one long task per worker, robots taken one by one"
    cc = statistics.median(client_cpu)
    print(f"client process (client + scheduler) CPU in the fleet run: {cc:.2f} s = {1e3 * cc / n:.2f} ms per robot, "
          f"{1e3 * cc / n_tasks:.2f} ms per task ({n_tasks} tasks: {how})")
    est = 1000 * (b / n + per_task_overhead) / workers
    print(f"estimate for 1,000 robots x {args.poses} poses: {est:.0f} s on {workers} workers here; "
          f"{1000 * (b / n + per_task_overhead) / 32:.0f} s on 32 such workers (4 machines x 8 cores), "
          f"plus cluster start-up")


if __name__ == "__main__":
    main()
