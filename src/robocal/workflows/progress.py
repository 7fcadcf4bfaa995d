"""Progress for long steps: a solver's iteration callback that reports at most once a second."""

from __future__ import annotations

import time

__all__ = ["solver_progress"]


def solver_progress(step, i: int, total: int, interval_s: float = 1.0):
    """A ``progress(iteration, cost)`` callback for :func:`robocal.calib.solve` that calls
    ``step(i, total, "... iteration k, cost c")`` at most every ``interval_s`` seconds, so a
    solve that takes longer than a second shows it is alive."""
    last = [time.monotonic()]

    def report(iteration, cost):
        now = time.monotonic()
        if now - last[0] >= interval_s:
            last[0] = now
            step(i, total, f"  ... iteration {iteration}, cost {float(cost):.6g}")

    return report
