"""Production schedules of the thermal simulator (METHODS.md 4): cycles of work at a motor load,
a short measurement phase and optional idle gaps; :func:`standard_schedules` gives the three
runs of the thesis-like experiment. Times in s, loads relative (0..1).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from ..robot import as_rng

__all__ = ["PRODUCTION_LOAD", "MEASUREMENT_LOAD", "ProductionSchedule", "standard_schedules"]

# joint motor loads in a production cycle (relative, heaviest in joints 2-4) and in the measurement phase
PRODUCTION_LOAD = np.array([0.6, 1.0, 0.9, 0.8, 0.5, 0.5])
MEASUREMENT_LOAD = 0.3


@dataclass(frozen=True)
class ProductionSchedule:
    """Production cycles of one run (times in s from the start of the run).

    Cycle c: production work from ``start_s[c]`` for ``work_s[c]`` at relative load ``load[c]``
    (0..1, times :data:`PRODUCTION_LOAD` per joint), then the measurement phase of
    ``measure_s`` at load :data:`MEASUREMENT_LOAD`, then ``idle_s[c]`` of idle (load 0: cooling).
    The measurement instant of cycle c is the middle of its measurement phase
    (:attr:`measurement_times_s`). ``duty`` (n, 6), optional: per cycle and joint, a factor on
    the production load (the program run in that cycle; :meth:`with_programs`); default all 1.
    """

    work_s: np.ndarray
    load: np.ndarray
    idle_s: np.ndarray
    measure_s: float = 40.0
    name: str = ""
    duty: np.ndarray | None = None

    def __post_init__(self):
        w = np.asarray(self.work_s, float)
        ld = np.asarray(self.load, float)
        idle = np.asarray(self.idle_s, float)
        if not (w.ndim == 1 and w.shape == ld.shape == idle.shape and len(w)):
            raise ValueError("ProductionSchedule: work_s, load, idle_s must be 1-D of the same length >= 1")
        if np.any(w < 0) or np.any(idle < 0) or np.any((ld < 0) | (ld > 1)) or self.measure_s < 0:
            raise ValueError("ProductionSchedule: durations must be >= 0 and loads in [0, 1]")
        for k, v in (("work_s", w), ("load", ld), ("idle_s", idle)):
            v.setflags(write=False)
            object.__setattr__(self, k, v)
        if self.duty is not None:
            d = np.array(self.duty, float)
            if d.shape != (len(w), len(PRODUCTION_LOAD)) or np.any(d < 0) or not np.all(np.isfinite(d)):
                raise ValueError(f"ProductionSchedule: duty must be ({len(w)}, {len(PRODUCTION_LOAD)}), finite, >= 0")
            d.setflags(write=False)
            object.__setattr__(self, "duty", d)

    @property
    def n_cycles(self) -> int:
        return len(self.work_s)

    @property
    def start_s(self) -> np.ndarray:
        """Start time of every cycle (n,) [s]."""
        length = self.work_s + self.measure_s + self.idle_s
        return np.concatenate([[0.0], np.cumsum(length)[:-1]])

    @property
    def measurement_times_s(self) -> np.ndarray:
        """The measurement instant of every cycle (n,) [s]."""
        return self.start_s + self.work_s + 0.5 * self.measure_s

    @property
    def duration_s(self) -> float:
        return float(np.sum(self.work_s + self.measure_s + self.idle_s))

    def segments(self):
        """Piecewise-constant load: ``(t_start (S,), duration (S,), relative load (S, 6))``."""
        n = self.n_cycles
        dur = np.stack([self.work_s, np.full(n, self.measure_s), self.idle_s], axis=1).reshape(-1)
        work = self.load[:, None] * PRODUCTION_LOAD
        if self.duty is not None:
            work = np.minimum(work * self.duty, 1.0)
        loads = np.stack([work, np.full((n, 6), MEASUREMENT_LOAD),
                          np.zeros((n, 6))], axis=1).reshape(-1, 6)
        t0 = np.concatenate([[0.0], np.cumsum(dur)[:-1]])
        return t0, dur, loads

    def with_programs(self, rng, n_programs: int = 3, spread: float = 0.3) -> "ProductionSchedule":
        """A copy in which every cycle runs one of ``n_programs`` programs, each with a per-joint
        duty factor uniform in ``1 +- spread`` (drawn from ``rng``, seed or Generator); the
        program of each cycle is drawn uniformly."""
        rng = as_rng(rng)
        programs = rng.uniform(1.0 - spread, 1.0 + spread, (int(n_programs), len(PRODUCTION_LOAD)))
        pick = rng.integers(0, int(n_programs), self.n_cycles)
        return replace(self, duty=programs[pick])

    @classmethod
    def generate(cls, rng, n_cycles: int = 90, *, cycle_s: float = 180.0, jitter_s: float = 10.0,
                 measure_s: float = 40.0, load_range=(0.8, 1.0), gap_probability: float = 0.05,
                 gap_mean_s: float = 240.0, breaks=None, name: str = "") -> "ProductionSchedule":
        """A random schedule: cycles of ``cycle_s`` +- ``jitter_s`` (work + measurement), loads
        uniform in ``load_range``, after each cycle an idle gap with probability
        ``gap_probability`` (exponential, mean ``gap_mean_s``), and fixed ``breaks``
        ``{cycle index: idle seconds}`` (e.g. a 45-min stop after cycle 40). ``rng``: seed or Generator."""
        rng = as_rng(rng)
        work = cycle_s - measure_s + rng.uniform(-jitter_s, jitter_s, n_cycles)
        load = rng.uniform(*load_range, n_cycles)
        idle = np.where(rng.random(n_cycles) < gap_probability, rng.exponential(gap_mean_s, n_cycles), 0.0)
        for c, s in (breaks or {}).items():
            idle[int(c)] += float(s)
        return cls(np.maximum(work, 0.0), np.clip(load, 0, 1), idle, measure_s, name)


def standard_schedules(seed: int = 7, n_cycles: int = 90) -> list:
    """Three different runs of ~3-min cycles (the thesis-like experiment):

    1. screening run: steady production, loads 0.85-1.0, rare short gaps;
    2. evaluation run: loads 0.7-1.0, more gaps and a 45-min stop after 45 % of the cycles (the
       robot cools down and heats up again);
    3. evaluation run: faster cycles (160 s) at loads 0.9-1.0, a 30-min stop after 70 % of the
       cycles.
    """
    rng = as_rng(seed)
    s = rng.integers(0, 2**31, 3)
    return [
        ProductionSchedule.generate(int(s[0]), n_cycles, load_range=(0.85, 1.0), gap_probability=0.03, name="run 1"),
        ProductionSchedule.generate(int(s[1]), n_cycles, load_range=(0.7, 1.0), gap_probability=0.1,
                                    breaks={int(0.45 * n_cycles): 2700.0}, name="run 2"),
        ProductionSchedule.generate(int(s[2]), n_cycles, cycle_s=160.0, load_range=(0.9, 1.0), gap_probability=0.05,
                                    breaks={int(0.7 * n_cycles): 1800.0}, name="run 3"),
    ]

