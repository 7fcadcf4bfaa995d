"""Where a cold start's compile time goes (issue 12): numba's compile events, timed per function.

Runs one ``robocal`` command in this process with a fresh numba cache and prints the total time
and the compile time of each function numba compiled (nested compiles are inside their caller's
time), as wall time and as this process's CPU time (the CPU figure holds on a loaded machine, where the
wall time swings by 2-3x). The kernels run in numpy until the work pays for a compile
(:mod:`robocal.kinematics._backend`): the listed compiles are those a command's work pays for. Usage::

    NUMBA_CACHE_DIR=$(mktemp -d) python benchmarks/profile_compile.py calibrate abb_irb140 M.csv --out OUT --no-report

A script, not a test. Without a fresh ``NUMBA_CACHE_DIR`` the kernels load from the cache and
nothing compiles.
"""

from __future__ import annotations

import collections
import os
import sys
import time

from numba.core import event


class _CompileTimes(event.Listener):
    def __init__(self):
        self.started, self.seconds, self.count = {}, collections.defaultdict(float), collections.Counter()
        self.cpu = collections.defaultdict(float)
        self.depth = 0
        self.total_wall = self.total_cpu = 0.0

    def on_start(self, ev):
        self.started[id(ev.data["dispatcher"])] = (time.perf_counter(), time.process_time())
        self.depth += 1

    def on_end(self, ev):
        d = ev.data["dispatcher"]
        name = d.py_func.__qualname__
        wall, cpu = self.started.pop(id(d), (time.perf_counter(), time.process_time()))
        wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
        self.seconds[name] += wall
        self.cpu[name] += cpu
        self.count[name] += 1
        self.depth -= 1
        if self.depth == 0:  # outermost compiles only: the nested ones are inside them
            self.total_wall += wall
            self.total_cpu += cpu


def main(argv) -> None:
    times = _CompileTimes()
    event.register("numba:compile", times)
    t0, c0 = time.perf_counter(), time.process_time()
    from robocal.cli.main import main as robocal_main

    try:
        robocal_main(argv, standalone_mode=False)
    except SystemExit:
        pass
    total = time.perf_counter() - t0
    cpu = time.process_time() - c0
    print(f"\ntotal {total:.2f} s wall, {cpu:.2f} s CPU; compilation {times.total_wall:.2f} s wall, "
          f"{times.total_cpu:.2f} s CPU; load average {os.getloadavg()[0]:.1f}")
    print("compile time per function (nested compiles included in their caller):")
    for name, sec in sorted(times.seconds.items(), key=lambda kv: -kv[1])[:15]:
        print(f"  {name:48s} {sec:6.2f} s wall {times.cpu[name]:6.2f} s CPU  x{times.count[name]}")


if __name__ == "__main__":
    main(sys.argv[1:])
