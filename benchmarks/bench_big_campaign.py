"""Memory and output size of ``robocal calibrate`` on a big campaign (issue 34 item 4).

Simulates a UR10 laser-tracker campaign of N poses (default 100 000) with ``LaserTracker.campaign``
(uniform poses within the joint limits, no cell: ``robocal simulate tracker`` gives up after 200 000
draws in its default cell), then runs in fresh child processes, interleaved:

* the data alone: ``read_measurements`` of the file (the floor any tool that loads the data pays);
* ``robocal calibrate`` (with and without the report), its peak resident memory (``ru_maxrss``).

Prints both peaks, the memory per pose above the data (target <= 1 KiB), the marginal memory per pose
(against the same command on a small campaign, which holds the fixed part: the libraries calibrate
loads, ~100 MiB), the wall time and the size
of every file written (result.json must not grow with N; per-point errors go to residuals.csv).
Run: ``python benchmarks/bench_big_campaign.py [--poses 100000] [--repeat 2] [--before SRC] [--numpy-kernels]``; ``--before SRC``
adds the same calibrate rows run from the sources in SRC (``PYTHONPATH=SRC``: the code before a change),
interleaved, for before/after figures from one run. A script, not a test.
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

BIN = Path(sys.executable).parent
CHILD_READ = ("import resource, sys\nfrom robocal.io import read_measurements\nfrom robocal.robots import load_robot\n"
              "m = read_measurements(sys.argv[1], robot=load_robot('ur10'))\n"
              "print(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss)\n")
CHILD_SIM = ("import sys\nimport numpy as np\nfrom robocal.robots import load_robot\nfrom robocal.sim import LaserTracker, "
             "VirtualRobot\nnom = load_robot('ur10')\nrngs = [np.random.default_rng(s) for s in (1, 2, 3)]\n"
             "robot = VirtualRobot.perturbed(nom, rngs[0], joint_noise_deg=0.0)\n"
             "tracker = LaserTracker.placed(rngs[1], 1, sigma_mm=0.02)\n"
             "tracker.campaign(robot, int(sys.argv[1]), rngs[2], measurements_path=sys.argv[2], cell=None)\n")
CHILD_CAL = ("import resource, sys\nfrom robocal.cli.main import main\n"
             "try:\n    main(sys.argv[1:], standalone_mode=False)\n"
             "finally:\n    print(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss, file=sys.stderr)\n")


def _child(code, args, env) -> tuple[float, float, str]:
    t = time.perf_counter()
    p = subprocess.run([sys.executable, "-c", code, *args], env=env, capture_output=True, text=True, check=True)
    wall = time.perf_counter() - t
    text = p.stdout if "getrusage" in code and "stderr" not in code else p.stderr
    return int(text.strip().splitlines()[-1]) / 1024.0, wall, p.stdout


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--poses", type=int, default=100_000)
    ap.add_argument("--repeat", type=int, default=2)
    ap.add_argument("--small", type=int, default=2000,
                    help="pose count of a small campaign whose peak gives the fixed part (loaded libraries)")
    ap.add_argument("--before", metavar="SRC", help="also run the calibrate rows from these sources (PYTHONPATH)")
    ap.add_argument("--numpy-kernels", action="store_true",
                    help="also run the calibrate rows with ROBOCAL_KERNELS=numpy (no numba: the memory-lean mode)")
    a = ap.parse_args()
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1")
    with tempfile.TemporaryDirectory(prefix="robocal-big-") as tmp:
        work = Path(tmp)
        data = work / "m.csv"
        # the data: ``robocal simulate tracker`` draws feasible poses in a default cell and gives up after 200 000
        # draws (~2.5 % of a UR10's draws are feasible there), so a big campaign is drawn without a cell: uniform
        # poses within the joint limits (what the memory of calibrate depends on is the pose count, not the poses)
        subprocess.run([sys.executable, "-c", CHILD_SIM, str(a.poses), str(data)], env=env, check=True,
                       capture_output=True)
        small = work / "small.csv"
        subprocess.run([sys.executable, "-c", CHILD_SIM, str(a.small), str(small)], env=env, check=True,
                       capture_output=True)
        small_label = f"robocal calibrate --no-report, {a.small} poses"
        print(f"UR10, {a.poses} poses, file {data.stat().st_size / 1e6:.1f} MB; load avg {os.getloadavg()[0]:.2f} at start; "
              f"{a.repeat} interleaved repeats, median")
        variants = [("", env)] + ([("before: ", dict(env, PYTHONPATH=a.before))] if a.before else [])
        if a.numpy_kernels:
            variants.append(("ROBOCAL_KERNELS=numpy: ", dict(env, ROBOCAL_KERNELS="numpy")))
        rows = {"read the data (read_measurements)": ([], [])}
        for prefix, _ in variants:
            for label in ("robocal calibrate --no-report", "robocal calibrate (with report)", small_label):
                rows[prefix + label] = ([], [])
        for v, (_, venv) in enumerate(variants):  # kernels compiled into the cache first: warm runs are measured
            _child(CHILD_CAL, ["calibrate", "ur10", str(small), "--out", str(work / f"warmup{v}"), "--no-report"], venv)
        for r in range(a.repeat):
            rss, wall, _ = _child(CHILD_READ, [str(data)], env)
            rows["read the data (read_measurements)"][0].append(rss)
            rows["read the data (read_measurements)"][1].append(wall)
            for v, (prefix, venv) in enumerate(variants):
                for label, extra in (("robocal calibrate --no-report", ["--no-report"]),
                                     ("robocal calibrate (with report)", [])):
                    out = work / f"out{r}{len(extra)}{v}"
                    rss, wall, _ = _child(CHILD_CAL, ["calibrate", "ur10", str(data), "--out", str(out), *extra], venv)
                    rows[prefix + label][0].append(rss)
                    rows[prefix + label][1].append(wall)
                rss, wall, _ = _child(CHILD_CAL, ["calibrate", "ur10", str(small), "--out", str(work / f"small{r}{v}"),
                                                  "--no-report"], venv)
                rows[prefix + small_label][0].append(rss)
                rows[prefix + small_label][1].append(wall)
        floor = statistics.median(rows["read the data (read_measurements)"][0])
        print(f"{'':64s}{'peak MiB':>10s}{'wall s':>9s}{'above data':>12s}{'per pose':>11s}   target")
        for label, (rss, wall) in rows.items():
            m = statistics.median(rss)
            if label.startswith("read"):
                print(f"{label:64s}{m:10.1f}{statistics.median(wall):9.2f}")
                continue
            if label.endswith(small_label):
                print(f"{label:64s}{m:10.1f}{statistics.median(wall):9.2f}{m - floor:10.1f} M   (fixed part: the "
                      "libraries calibrate loads, numba/LLVM and scipy, and its working set at a small N)")
                continue
            per = (m - floor) * 1024.0 / a.poses
            print(f"{label:64s}{m:10.1f}{statistics.median(wall):9.2f}{m - floor:10.1f} M{per:9.2f} KiB   "
                  f"{'ok  ' if per <= 1.0 else 'MISS'} <= 1 KiB per pose above the data")
        for prefix, _ in variants:
            big = statistics.median(rows[prefix + "robocal calibrate --no-report"][0])
            little = statistics.median(rows[prefix + small_label][0])
            slope = (big - little) * 1024.0 / (a.poses - a.small)
            print(f"{prefix}marginal memory per pose (calibrate --no-report, {a.small} -> {a.poses} poses): {slope:.2f} "
                  f"KiB   {'ok  ' if slope <= 1.0 else 'MISS'} <= 1 KiB per pose (the fixed part not counted)")
        print(f"load avg at end {os.getloadavg()[0]:.2f}")
        out = work / "out000"
        print("files written by calibrate (with report):")
        for f in sorted(out.iterdir()):
            print(f"  {f.name:28s}{f.stat().st_size / 1e6:10.3f} MB")


if __name__ == "__main__":
    main()
