"""The online sphere poses for a parameter set (thesis 5.1: 6 of the 20 screening poses).

:func:`select_online_poses` picks the ``n`` poses that minimise the predicted noise of the
compensation at the monitored points, ``trace(J_s (A_s^T A_s)^+ J_s^T)`` for independent equal
sphere noise (I-optimal design; ``A_s``, ``J_s``: the set's unit-norm sphere and monitored
columns), over every subset or, beyond ``max_combinations``, by greedy exchange. Subsets that
cannot identify the set are never chosen while any subset can; a set that no subset identifies
(e.g. all four parameters of the last link seen through a single sphere centre, which the
screening's truncated SVD accepts) gets the subset of the highest rank and, among those, the
least min-norm noise -- the screening's (3-10) solve handles it the same way online.
"""

from __future__ import annotations

import functools
import itertools
import math

import numpy as np

__all__ = ["select_online_poses"]


def select_online_poses(problem, names, n: int = 6, *, max_combinations: int = 250_000) -> np.ndarray:
    """The ``n`` sphere poses (sorted indices into the problem's poses, a
    :class:`~robocal.thermal.screening.ScreeningProblem`) best for identifying ``names`` online
    (module docstring): every subset if ``C(m, n) <= max_combinations``, else greedy exchange
    from the best D-optimal greedy start. Raises ``ValueError`` for ``n`` out of range or fewer
    equations than parameters."""
    cols = problem.columns(names)
    m = problem.n_poses
    k = len(cols)
    if not 1 <= n <= m:
        raise ValueError(f"n must be in [1, {m}], got {n}")
    if 3 * n < k:
        raise ValueError(f"{k} parameters need at least {-(-k // 3)} poses, got n = {n}")
    A = problem._An[:, cols].reshape(m, 3, k)
    info = np.einsum("pik,pil->pkl", A, A)                              # per-pose information (m, k, k)
    Js = problem._Jn[:, cols]
    G = Js.T @ Js                                                       # (k, k): trace(J N^-1 J^T) = trace(N^-1 G)
    search = _best_subset if math.comb(m, n) <= max_combinations else _greedy_exchange
    try:
        return search(functools.partial(_i_optimal_cost, info, G), info, m, n, names)
    except _NotIdentifiable:
        return search(functools.partial(_i_optimal_cost, info, G, tolerant=True), info, m, n, names)


class _NotIdentifiable(ValueError):
    """No pose subset identifies the set (only raised inside the strict search)."""


#: cost added per missing rank in the tolerant search (dominates any noise trace)
_RANK_PENALTY = 1e30


def _i_optimal_cost(info, G, subsets, tolerant: bool = False) -> np.ndarray:
    """``trace(N^-1 G)`` (B,) for pose subsets (B, n), ``N`` = summed per-pose information
    ``info`` (m, k, k); ``inf`` where ``N`` is (numerically) singular -- or, ``tolerant``,
    ``trace(N^+ G)`` plus :data:`_RANK_PENALTY` per missing rank."""
    N = info[subsets].sum(axis=1)
    ev = np.linalg.eigvalsh(N)
    if tolerant:
        deficit = np.sum(ev <= 1e-10 * ev[:, -1:], axis=1)
        return deficit * _RANK_PENALTY + np.einsum("bkl,lk->b", np.linalg.pinv(N, rcond=1e-10, hermitian=True), G)
    ok = ev[:, 0] > 1e-10 * ev[:, -1]
    out = np.full(len(subsets), np.inf)
    if ok.any():
        inv = np.linalg.inv(N[ok])
        out[ok] = np.einsum("bkl,lk->b", inv, G)
    return out


def _fast_cost(info, G, subsets):
    """``(trace(N^-1 G) (B,), N (B, k, k))`` without the singularity test (``None`` if a matrix
    is exactly singular); only the winner is tested afterwards."""
    N = info[subsets].sum(axis=1)
    try:
        return np.einsum("bkl,lk->b", np.linalg.inv(N), G), N
    except np.linalg.LinAlgError:
        return None, N


def _best_subset(cost, info, m: int, n: int, names) -> np.ndarray:
    """The cheapest of all ``C(m, n)`` subsets (sorted indices), evaluated in batches. The strict
    cost is first evaluated without the singularity test and the winner tested; if it is
    singular (or a matrix exactly so) the batches are evaluated with the test -- same result."""
    combos = np.array(list(itertools.combinations(range(m), n)), dtype=np.int64)
    if not cost.keywords.get("tolerant", False):
        G = cost.args[1]
        best, best_c = None, np.inf
        for i in range(0, len(combos), 20000):
            c, _ = _fast_cost(info, G, combos[i:i + 20000])
            if c is None:
                break
            j = int(np.argmin(np.where(np.isnan(c), np.inf, c)))
            if c[j] < best_c:
                best, best_c = combos[i + j], c[j]
        else:
            if best is not None and np.isfinite(cost(best[None])[0]):
                return np.sort(best)
    best, best_c = None, np.inf
    for i in range(0, len(combos), 20000):
        c = cost(combos[i:i + 20000])
        j = int(np.argmin(c))
        if c[j] < best_c:
            best, best_c = combos[i + j], c[j]
    if best is None:
        raise _NotIdentifiable(f"no {n}-pose subset identifies {list(names)}")
    return np.sort(best)


def _greedy_exchange(cost, info, m: int, n: int, names) -> np.ndarray:
    """A greedy D-optimal start, then single-pose exchanges while the cost drops (sorted indices)."""
    k = info.shape[1]
    chosen: list = []
    for _ in range(n):
        rest = [p for p in range(m) if p not in chosen]
        N = info[chosen].sum(axis=0) if chosen else np.zeros((k, k))
        scores = [np.linalg.slogdet(N + info[p] + 1e-9 * np.eye(k))[1] for p in rest]
        chosen.append(rest[int(np.argmax(scores))])
    cur = cost(np.array([chosen]))[0]
    improved = True
    while improved:
        improved = False
        for i in range(n):
            for p in range(m):
                if p in chosen:
                    continue
                trial = chosen.copy()
                trial[i] = p
                c = cost(np.array([trial]))[0]
                if c < cur - 1e-12:
                    chosen, cur, improved = trial, c, True
    if not np.isfinite(cur):
        raise _NotIdentifiable(f"no {n}-pose subset identifies {list(names)}")
    return np.sort(np.array(chosen))
