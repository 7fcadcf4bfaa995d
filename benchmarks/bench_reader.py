"""Measurement-file reader on a large input (issue 9 acceptance).

Run from the repository root (robocal installed in the environment)::

    python benchmarks/bench_reader.py              # 1.2 M rows (about 150 MB of text)
    python benchmarks/bench_reader.py --rows 200000

Writes a ``robocal-measurements/1`` file of a UR10 (pose, six joints in degrees, x, y, z in mm,
full float precision as ``robocal simulate`` writes) into a temporary folder, then reads it with
:func:`robocal.io.measurements.read_measurements` (the robot model given, as ``robocal calibrate``
does) in a fresh child process, and reports the wall time and the child's peak resident memory
(``ru_maxrss``, which includes the interpreter and numpy, about 60 MB). Targets: under 10 s and
under 500 MB.
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _machine import machine_info  # noqa: E402

TARGET_S, TARGET_MB = 10.0, 500.0

_CHILD = """
import sys, time, resource
from robocal.io.measurements import read_measurements
from robocal.robots import load_robot
model = load_robot("ur10")
t0 = time.perf_counter()
m = read_measurements(sys.argv[1], robot=model)
dt = time.perf_counter() - t0
print(m.n_poses, dt, resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0)
"""


def write_file(path: Path, n_rows: int, seed: int = 0) -> float:
    """A UR10 measurement file of ``n_rows`` random rows; returns its size [MB]."""
    rng = np.random.default_rng(seed)
    with open(path, "w") as fh:
        fh.write("# format: robocal-measurements/1\n# robot: ur10\n# length_unit: mm\n# angle_unit: deg\n"
                 "# instrument: benchmark\npose,J1,J2,J3,J4,J5,J6,x,y,z\n")
        chunk = 100_000
        for start in range(0, n_rows, chunk):
            n = min(chunk, n_rows - start)
            q = rng.uniform(-180, 180, (n, 6))
            p = rng.uniform(-1500, 1500, (n, 3)) + [2000.0, 0.0, 500.0]
            block = np.column_stack([np.arange(start + 1, start + n + 1), q, p])
            np.savetxt(fh, block, fmt=["%d"] + ["%.17g"] * 9, delimiter=",")
    return path.stat().st_size / 1e6


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rows", type=int, default=1_200_000)
    args = ap.parse_args()
    print("\n".join(machine_info()))
    with tempfile.TemporaryDirectory() as d:
        path = Path(d) / "large.csv"
        t0 = time.perf_counter()
        size = write_file(path, args.rows)
        print(f"wrote {args.rows:,} rows, {size:.0f} MB in {time.perf_counter() - t0:.1f} s")
        t0 = time.perf_counter()
        out = subprocess.run([sys.executable, "-c", _CHILD, str(path)], capture_output=True, text=True, check=True)
        wall = time.perf_counter() - t0
    n, read_s, peak_mb = out.stdout.split()
    read_s, peak_mb = float(read_s), float(peak_mb)
    print(f"read_measurements: {int(n):,} poses in {read_s:.2f} s ({wall:.2f} s with interpreter start), "
          f"peak RSS {peak_mb:.0f} MB  [{'ok' if read_s < TARGET_S else 'MISS'} < {TARGET_S:g} s, "
          f"{'ok' if peak_mb < TARGET_MB else 'MISS'} < {TARGET_MB:g} MB]")


if __name__ == "__main__":
    main()
