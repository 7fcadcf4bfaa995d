"""Pose selection: the k most informative poses of a candidate set (greedy D-optimal design).

Each candidate pose contributes a block of rows ``J_i`` (r, n) to the identification Jacobian
(columns scaled to unit norm over all candidates so mm and rad compare). Greedy selection adds,
one at a time, the pose that most increases ``log det(sum J_i^T J_i)`` -- the product of the
singular values, i.e. observability index O1 (Borm & Menq) -- using the matrix determinant lemma
``det(A + J^T J) = det(A) det(I + J A^-1 J^T)`` evaluated for all candidates at once.
"""

from __future__ import annotations

import numpy as np

from .identifiability import analyse_identifiability, observability_indices

__all__ = ["select_poses", "pose_jacobians"]


def pose_jacobians(problem, state=None) -> np.ndarray:
    """Per-pose prediction Jacobian blocks (N, 3K, n) of a problem's point measurements."""
    state = problem.initial_state() if state is None else state
    _, J = problem.predict_points(state, jacobian=True)
    N = J.shape[0]
    return J.reshape(N, -1, J.shape[-1])


def select_poses(J_blocks, k: int, *, names=None, blocks=None, must_include=()) -> dict:
    """Choose ``k`` pose indices from candidate Jacobian blocks (N, r, n).

    Only columns identifiable from the whole candidate set take part (others would make every
    determinant zero). Returns ``{"indices": (k,) array in selection order, "identifiable": names,
    "indices_O1".."O4" of the selected set, "all_candidates": indices of the full set}``.
    """
    J_blocks = np.asarray(J_blocks, dtype=float)
    N, r, n = J_blocks.shape
    if not 1 <= k <= N:
        raise ValueError(f"k must be in 1..{N} (number of candidates), got {k}")
    names = [f"p{i}" for i in range(n)] if names is None else list(names)
    flat = J_blocks.reshape(N * r, n)
    ident = analyse_identifiability(flat, names, blocks)
    cols = [names.index(nm) for nm in ident.identifiable]
    norms = np.linalg.norm(flat[:, cols], axis=0)
    Jb = J_blocks[..., cols] / norms
    m = len(cols)
    A = np.eye(m) * 1e-9 * N * r / m  # tiny ridge so early determinants are defined
    chosen = list(must_include)
    for i in chosen:
        A += Jb[i].T @ Jb[i]
    remaining = np.setdiff1d(np.arange(N), chosen)
    while len(chosen) < k:
        Ainv = np.linalg.inv(A)
        Jr = Jb[remaining]
        M = np.eye(r) + Jr @ Ainv @ np.swapaxes(Jr, 1, 2)
        gain = np.linalg.slogdet(M)[1]
        best = int(remaining[np.argmax(gain)])
        chosen.append(best)
        A += Jb[best].T @ Jb[best]
        remaining = remaining[remaining != best]
    idx = np.array(chosen)
    obs = observability_indices(J_blocks[idx].reshape(-1, n)[:, cols])
    return {"indices": idx, "identifiable": ident.identifiable, **{f"selected_{k_}": v for k_, v in obs.items()},
            **{f"all_{k_}": v for k_, v in observability_indices(flat[:, cols]).items()}}
