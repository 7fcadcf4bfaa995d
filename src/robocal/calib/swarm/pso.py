"""The improved particle swarm (IPSO) of METHODS.md section 3 on any batched objective.

Algorithm (the IPSO paper, steps 1-11):

* initial positions and velocities from scrambled Halton sequences (``scipy.stats.qmc``, seeded):
  positions fill the box ``[lower, upper]``; velocities lie in ``±(upper - lower) / 2``;
* velocity update with Clerc's constriction factor (METHODS.md, IPSO):
  ``v <- K (v + c1 r1 (pbest - x) + c2 r2 (gbest - x))``, ``K = 2 / |2 - phi - sqrt(phi^2 - 4 phi)|``,
  ``phi = c1 + c2 > 4`` (c1 = c2 = 2.05 gives K = 0.7298); ``x <- x + v`` (time step 1);
* velocity clamping: ``|v_i| <= upper_i - lower_i`` per dimension (one box width);
* box handling: a particle leaving the box is put back on the wall it crossed and that velocity
  component is set to zero (absorbing walls), so every evaluated point lies in the box;
* a non-finite objective (a candidate whose forward kinematics blows up) counts as ``+inf``: the
  particle never becomes a personal or global best, and the number of such evaluations is
  reported (``PSOOutcome.non_finite``).

The whole swarm is evaluated in one call per generation: ``fun(X)`` with X (P, n) returns (P,).
"""

from __future__ import annotations
from ...errors import InputError

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["constriction_factor", "halton_swarm", "run_pso", "PSOOutcome", "SwarmInputError"]


class SwarmInputError(InputError):
    """Bad swarm input: empty or inverted bounds, no particles or generations, bad coefficients,
    an objective that is not finite anywhere in the initial swarm."""


def constriction_factor(c1: float = 2.05, c2: float = 2.05) -> float:
    """Clerc's constriction factor ``K = 2 / |2 - phi - sqrt(phi^2 - 4 phi)|``, ``phi = c1 + c2 > 4``."""
    phi = c1 + c2
    if not phi > 4.0:
        raise SwarmInputError(f"constriction needs c1 + c2 > 4, got {phi}")
    return 2.0 / abs(2.0 - phi - math.sqrt(phi * phi - 4.0 * phi))


def check_box(lower, upper) -> tuple[np.ndarray, np.ndarray]:
    """Validated (lower, upper) as float arrays (n,): finite, same shape, non-empty, lower < upper."""
    lo, up = np.atleast_1d(np.asarray(lower, dtype=float)), np.atleast_1d(np.asarray(upper, dtype=float))
    if lo.shape != up.shape or lo.ndim != 1:
        raise SwarmInputError(f"bounds: lower {lo.shape} and upper {up.shape} must be 1-D of the same length")
    if lo.size == 0:
        raise SwarmInputError("bounds: empty search box (no variable to search)")
    if not (np.all(np.isfinite(lo)) and np.all(np.isfinite(up))):
        raise SwarmInputError("bounds: every bound must be a finite number")
    bad = np.flatnonzero(~(up > lo))
    if bad.size:
        i = int(bad[0])
        raise SwarmInputError(f"bounds: variable {i} has upper {up[i]} <= lower {lo[i]} (inverted or empty interval)")
    return lo, up


def halton_swarm(lower, upper, particles: int, seed) -> tuple[np.ndarray, np.ndarray]:
    """Initial positions (P, n) in the box and velocities (P, n) in ``±(upper - lower) / 2`` from two
    scrambled Halton sequences (seeded; scipy.stats.qmc)."""
    lo, up = check_box(lower, upper)
    n = lo.size
    ss = np.random.SeedSequence(seed)
    s_pos, s_vel = ss.spawn(2)
    from scipy.stats import qmc  # here: scipy.stats costs ~0.7 s to import, and only a swarm needs it

    u = qmc.Halton(d=n, scramble=True, seed=np.random.default_rng(s_pos)).random(particles)
    w = qmc.Halton(d=n, scramble=True, seed=np.random.default_rng(s_vel)).random(particles)
    return lo + u * (up - lo), (w - 0.5) * (up - lo)


@dataclass
class PSOOutcome:
    """best_x (n,), best_f; history (G + 1,) best f after initialisation and after every
    generation; generations run; evaluations; non_finite: evaluations that gave NaN or inf."""

    best_x: np.ndarray
    best_f: float
    history: np.ndarray
    generations: int
    evaluations: int
    non_finite: int


def _finite_or_inf(f, P):
    f = np.asarray(f, dtype=float).reshape(-1)
    if f.shape != (P,):
        raise SwarmInputError(f"objective: expected {P} values (one per particle), got {f.shape}")
    bad = ~np.isfinite(f)
    return np.where(bad, np.inf, f), int(bad.sum())


def run_pso(fun, lower, upper, *, particles: int = 20, generations: int = 2000, seed=0, c1: float = 2.05,
            c2: float = 2.05, progress=None) -> PSOOutcome:
    """Minimise ``fun`` over the box with the constriction-factor swarm (see the module docstring).

    fun: callable X (P, n) -> f (P,); lower, upper (n,); particles >= 1, generations >= 1;
    seed: int or SeedSequence (the Halton scrambling and the r1, r2 draws); progress: optional
    callable ``progress(generation, best_f)`` after every generation.
    """
    lo, up = check_box(lower, upper)
    if int(particles) != particles or particles < 1:
        raise SwarmInputError(f"particles must be a positive integer, got {particles}")
    if int(generations) != generations or generations < 1:
        raise SwarmInputError(f"generations must be a positive integer, got {generations}")
    P, n, G = int(particles), lo.size, int(generations)
    K = constriction_factor(c1, c2)
    x, v = halton_swarm(lo, up, P, seed)
    vmax = up - lo
    rng = np.random.default_rng(np.random.SeedSequence(seed).spawn(3)[2])
    f, bad = _finite_or_inf(fun(x), P)
    if not np.isfinite(f).any():
        raise SwarmInputError("objective: not finite for any particle of the initial swarm "
                              "(the forward kinematics fails everywhere in the box?)")
    pbest, pbest_f = x.copy(), f.copy()
    g = int(np.argmin(f))
    gbest, gbest_f = x[g].copy(), float(f[g])
    history = np.empty(G + 1)
    history[0] = gbest_f
    Kc1, Kc2 = K * c1, K * c2
    for gen in range(1, G + 1):
        r = rng.random((2, P, n))
        v *= K
        v += Kc1 * r[0] * (pbest - x)
        v += Kc2 * r[1] * (gbest - x)
        np.clip(v, -vmax, vmax, out=v)
        x += v
        out = (x < lo) | (x > up)
        if out.any():
            np.clip(x, lo, up, out=x)
            v[out] = 0.0
        f, nb = _finite_or_inf(fun(x), P)
        bad += nb
        better = f < pbest_f
        pbest[better] = x[better]
        pbest_f[better] = f[better]
        g = int(np.argmin(pbest_f))
        if pbest_f[g] < gbest_f:
            gbest, gbest_f = pbest[g].copy(), float(pbest_f[g])
        history[gen] = gbest_f
        if progress is not None:
            progress(gen, gbest_f)
    return PSOOutcome(gbest, gbest_f, history, G, P * (G + 1), bad)
