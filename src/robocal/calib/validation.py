"""Validation: seeded train/holdout splits and error statistics before and after calibration."""

from __future__ import annotations

import numpy as np

from ..metrics import error_statistics

__all__ = ["train_holdout_split", "holdout_errors"]


def train_holdout_split(n_poses: int, holdout_fraction: float, seed: int):
    """Seeded random split of pose indices: ``(train, holdout)`` sorted integer arrays.

    holdout_fraction in [0, 1); 0 gives an empty holdout set.
    """
    if not 0.0 <= holdout_fraction < 1.0:
        raise ValueError(f"holdout fraction must be in [0, 1), got {holdout_fraction}")
    n_hold = int(round(n_poses * holdout_fraction))
    perm = np.random.default_rng(seed).permutation(n_poses)
    return np.sort(perm[n_hold:]), np.sort(perm[:n_hold])


def holdout_errors(problem, result, q, points, stations=None, rotations=None) -> dict:
    """Position (and orientation) errors on held-out poses, before and after calibration.

    q (N, n) joints; points (N, K, 3) measured [mm] (NaN = missing); rotations (N, 3, 3) optional
    measured orientations of the problem's rotation end effector. "Before" uses the problem's
    initial state (nominal parameters with the initial base and targets).
    Returns per-pose errors and statistics (RMS, mean, p95, max) in mm (and rad).
    """
    from ..transforms import so3_log

    out = {}
    for label, state in (("before", problem.initial_state()), ("after", result.state)):
        pred = problem.predict_points(state, q=q, stations=stations)
        e = np.linalg.norm(pred - np.asarray(points, dtype=float), axis=-1)
        e = e[np.isfinite(e)]
        out[f"position_{label}"] = error_statistics(e)
        out[f"position_errors_{label}"] = e
        if rotations is not None:
            T = problem.model.kinematics_with(q, state.params, np.eye(4), [problem.rotation_ee])[0][:, 0]
            st = np.zeros(len(q), dtype=int) if stations is None else np.asarray(stations)
            R = state.bases[st, :3, :3] @ T[:, :3, :3]
            ang = np.linalg.norm(so3_log(np.asarray(rotations) @ np.swapaxes(R, 1, 2)), axis=-1)
            out[f"orientation_{label}"] = error_statistics(ang)
    return out
