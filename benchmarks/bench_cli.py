"""Wall time of whole ``robocal`` commands, as a user waits for them (issue 12).

Each command is a fresh process; the rows are timed interleaved (one run of each row in turn per
repeat) so that a change in the shared machine's load affects every row alike, and each row is
given as its median and as a ratio to ``python -c "import numpy"`` measured in the same repeats.

* warm: numba's compiled kernels in the cache (the usual case after the first run).
* cold: a fresh, empty numba cache directory for every run (``NUMBA_CACHE_DIR``), as on the first
  run after installing; only the commands that use kernels differ from warm.

Usage: ``python benchmarks/bench_cli.py [--repeat 5] [--cold-repeat 2] [--quick] [--before SRC]``;
``--before SRC`` adds, interleaved, each command that uses kernels run from the sources in SRC (the
code before a change, e.g. ``git archive`` of the old commit: ``PYTHONPATH=SRC``), for before/after
ratios from one run.
It is a script, not a test: nothing fails on a slow machine.
"""

from __future__ import annotations

import argparse
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

BIN = Path(sys.executable).parent
ROBOCAL = str(BIN / "robocal")


def _run(cmd, env, cwd) -> float:
    t = time.perf_counter()
    subprocess.run(cmd, env=env, cwd=cwd, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return time.perf_counter() - t


def _rows(work: Path, before: str | None = None) -> list:
    data = str(work / "m100.csv")
    rows = [
        ("python -c 'import numpy'", [sys.executable, "-c", "import numpy"], False),
        ("robocal --help", [ROBOCAL, "--help"], False),
        ("robocal robots", [ROBOCAL, "robots"], False),
        ("robocal fk ur10 (one pose)", [ROBOCAL, "fk", "ur10", "--deg", "10", "-20", "30", "0", "45", "0"], True),
        ("robocal calibrate 100 poses --no-report",
         [ROBOCAL, "calibrate", "abb_irb140", data, "--out", str(work / "a"), "--overwrite", "--no-report"], True),
        ("robocal calibrate 100 poses (with report)",
         [ROBOCAL, "calibrate", "abb_irb140", data, "--out", str(work / "b"), "--overwrite"], True),
    ]
    rows = [(label, cmd, kernels, None) for label, cmd, kernels in rows]
    if before:
        rows += [(f"  before: {label}", cmd, True, before) for label, cmd, kernels, _ in rows if kernels]
    return rows


def _measure(rows, repeat: int, cold: bool, work: Path) -> dict:
    times = {label: [] for label, _, _, _ in rows}
    for _ in range(repeat):
        for label, cmd, kernels, src in rows:
            env = dict(os.environ)
            if src:
                env["PYTHONPATH"] = src
            cache = None
            if cold and kernels:
                cache = tempfile.mkdtemp(prefix="robocal-numba-cold-")
                env["NUMBA_CACHE_DIR"] = cache
            elif kernels:
                env["NUMBA_CACHE_DIR"] = str(work / ("numba-warm-before" if src else "numba-warm"))
            try:
                times[label].append(_run(cmd, env, work))
            finally:
                if cache:
                    shutil.rmtree(cache, ignore_errors=True)
    return times


#: Issue 34 item 2 targets: (warm?, label) -> ("x numpy" limit, seconds limit)
TARGETS = {(False, "robocal fk ur10 (one pose)"): (3.0, None),
           (True, "robocal calibrate 100 poses --no-report"): (None, 2.0)}


def _print(title: str, times: dict, cold: bool = False) -> None:
    base = statistics.median(next(iter(times.values())))
    print(f"\n{title}")
    print(f"{'command':<46}{'median s':>10}{'best s':>9}{'x numpy':>9}   runs   target")
    for label, ts in times.items():
        med = statistics.median(ts)
        x_max, s_max = TARGETS.get((cold, label), (None, None))
        mark = ""
        if x_max is not None:
            mark = f"{'ok  ' if med / base <= x_max else 'MISS'} <= {x_max:g}x import numpy"
        elif s_max is not None:
            mark = f"{'ok  ' if med <= s_max else 'MISS'} <= {s_max:g} s"
        print(f"{label:<46}{med:10.3f}{min(ts):9.3f}{med / base:9.1f}   {len(ts):4d}   {mark}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=5, help="warm runs per row (median)")
    ap.add_argument("--cold-repeat", type=int, default=2, help="cold runs per row (0: skip)")
    ap.add_argument("--quick", action="store_true", help="3 warm runs, 1 cold")
    ap.add_argument("--before", metavar="SRC", help="also run the kernel commands from these sources (PYTHONPATH)")
    args = ap.parse_args()
    if args.quick:
        args.repeat, args.cold_repeat = 3, 1
    with tempfile.TemporaryDirectory(prefix="robocal-bench-cli-") as tmp:
        work = Path(tmp)
        subprocess.run([ROBOCAL, "simulate", "tracker", "abb_irb140", "--poses", "100", "--out", "m100.csv"],
                       cwd=work, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        rows = _rows(work, args.before)
        print(f"robocal CLI wall time; python {sys.version.split()[0]}; load avg {os.getloadavg()[0]:.2f} "
              f"{os.getloadavg()[1]:.2f} (1/5 min) at start; {os.cpu_count()} CPUs")
        _measure([r for r in rows if r[2]], 1, False, work)  # fill the warm caches
        _print(f"warm (kernels cached), {args.repeat} runs per row, interleaved", _measure(rows, args.repeat, False, work))
        if args.cold_repeat:
            cold_rows = [r for r in rows if r[2] or r[0].startswith("python")]
            _print(f"cold (fresh numba cache every run), {args.cold_repeat} runs per row, interleaved",
                   _measure(cold_rows, args.cold_repeat, True, work), cold=True)
        print(f"load avg at end {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
