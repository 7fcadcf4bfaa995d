"""How stable is a screened parameter set? Selection frequencies over resampled cycles (issue 11).

The greedy screening (:func:`robocal.thermal.screening.screen_parameters`) returns one set from
one run; noise, outliers and effects outside the model can swap parameters that explain the
drift almost equally well. :func:`screening_stability` repeats the screening on ``B`` bootstrap
resamples of the run's cycles -- ``C`` cycles drawn with replacement and kept in time order, so
the heating trend the stationarity test looks for survives -- and reports how often each
candidate is selected. :attr:`StabilityReport.selected` is the selection by frequency: the
``n_keep`` most frequently selected parameters (ties broken by the order of the full-run
screening, then the candidates' order), a set that does not hinge on single cycles.

:func:`selection_frequency` counts the same over any list of sets (e.g. one per seed).
"""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass

import numpy as np

from .screening import ScreeningProblem, screen_parameters

__all__ = ["StabilityReport", "selection_frequency", "resample_cycles", "screening_stability"]


def _generator(rng) -> np.random.Generator:
    if isinstance(rng, np.random.Generator):
        return rng
    if rng is None or isinstance(rng, bool) or not isinstance(rng, (int, np.integer)):
        raise TypeError(f"expected a numpy.random.Generator or an integer seed, got {rng!r}")
    return np.random.default_rng(int(rng))


def selection_frequency(sets, names=None) -> dict:
    """``{name: share of sets containing it}`` (0..1), for ``names`` (default: every name seen,
    most frequent first, ties in order of first appearance)."""
    sets = [tuple(s) for s in sets]
    if not sets:
        raise ValueError("selection_frequency: no sets given")
    count = Counter(n for s in sets for n in set(s))
    if names is None:
        first = {}
        for s in sets:
            for n in s:
                first.setdefault(n, len(first))
        names = sorted(count, key=lambda n: (-count[n], first[n]))
    return {n: count.get(n, 0) / len(sets) for n in names}


def resample_cycles(n_cycles: int, rng) -> np.ndarray:
    """A bootstrap resample of ``n_cycles`` cycle indices (n_cycles,), drawn with replacement and
    sorted (time order kept). ``rng``: seed or Generator."""
    return np.sort(_generator(rng).integers(0, int(n_cycles), int(n_cycles)))


@dataclass
class StabilityReport:
    """Selection over bootstrap resamples of the cycles.

    full: the set screened on all cycles; sets: the set of every resample; frequency: ``{name:
    share of resamples selecting it}`` over every candidate, most frequent first; selected: the
    ``n_keep`` most frequent (the selection by frequency); agreement: share of resamples whose
    set equals ``full`` exactly."""

    full: tuple
    sets: list
    frequency: dict
    selected: tuple
    agreement: float

    @property
    def n_resamples(self) -> int:
        return len(self.sets)

    def unstable(self, low: float = 0.2, high: float = 0.8) -> list:
        """Parameters selected in between ``low`` and ``high`` of the resamples (neither
        clearly in nor clearly out)."""
        return [n for n, f in self.frequency.items() if low < f < high]

    def table(self) -> list:
        """One dict per candidate: name, frequency, in_full, in_selected."""
        return [{"name": n, "frequency": f, "in_full": n in self.full, "in_selected": n in self.selected}
                for n, f in self.frequency.items()]


def screening_stability(problem: ScreeningProblem, n_resamples: int = 50, rng=0, *, n_keep: int = 8,
                        full=None, **screen_kw) -> StabilityReport:
    """Screen ``problem`` on ``n_resamples`` bootstrap resamples of its cycles (module docstring).

    full: the full-run :class:`ScreeningResult` if already computed; screen_kw: passed to
    :func:`screen_parameters` (threshold_mm, statistic, stationarity settings).
    """
    if n_resamples < 1:
        raise ValueError(f"n_resamples must be >= 1, got {n_resamples}")
    gen = _generator(rng)
    full = full or screen_parameters(problem, n_keep, **screen_kw)
    sets = [screen_parameters(problem.with_cycles(resample_cycles(problem.n_cycles, gen)), n_keep,
                              **screen_kw).selected for _ in range(int(n_resamples))]
    freq = selection_frequency(sets, problem.names)
    order = {n: i for i, n in enumerate(full.selected)}
    rank = sorted(problem.names, key=lambda n: (-freq[n], order.get(n, len(order)), problem.names.index(n)))
    freq = {n: freq[n] for n in rank}
    chosen = tuple(n for n in problem.names if n in set(rank[:n_keep]))
    agree = float(np.mean([set(s) == set(full.selected) for s in sets]))
    return StabilityReport(tuple(full.selected), sets, freq, chosen, agree)
