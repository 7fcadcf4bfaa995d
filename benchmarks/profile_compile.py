"""Where a cold start's compile time goes (issue 12): numba's compile events, timed per function.

Runs one ``robocal`` command in this process with a fresh numba cache and prints the total time
and the compile time of each function numba compiled (nested compiles are inside their caller's
time). Usage::

    NUMBA_CACHE_DIR=$(mktemp -d) python benchmarks/profile_compile.py calibrate abb_irb140 M.csv --out OUT --no-report

A script, not a test. Without a fresh ``NUMBA_CACHE_DIR`` the kernels load from the cache and
nothing compiles.
"""

from __future__ import annotations

import collections
import sys
import time

from numba.core import event


class _CompileTimes(event.Listener):
    def __init__(self):
        self.started, self.seconds, self.count = {}, collections.defaultdict(float), collections.Counter()

    def on_start(self, ev):
        self.started[id(ev.data["dispatcher"])] = time.perf_counter()

    def on_end(self, ev):
        d = ev.data["dispatcher"]
        name = d.py_func.__qualname__
        self.seconds[name] += time.perf_counter() - self.started.pop(id(d), time.perf_counter())
        self.count[name] += 1


def main(argv) -> None:
    times = _CompileTimes()
    event.register("numba:compile", times)
    t0 = time.perf_counter()
    from robocal.cli.main import main as robocal_main

    try:
        robocal_main(argv, standalone_mode=False)
    except SystemExit:
        pass
    total = time.perf_counter() - t0
    print(f"\ntotal {total:.2f} s; compile time per function (nested compiles included in their caller):")
    for name, sec in sorted(times.seconds.items(), key=lambda kv: -kv[1])[:15]:
        print(f"  {name:48s} {sec:6.2f} s  x{times.count[name]}")


if __name__ == "__main__":
    main(sys.argv[1:])
