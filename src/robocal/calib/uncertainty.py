"""Uncertainty propagation: predicted position uncertainty of calibrated targets at any pose."""

from __future__ import annotations

import numpy as np

__all__ = ["predicted_point_covariance", "predicted_point_std"]


def predicted_point_covariance(problem, result, q, stations=None) -> np.ndarray:
    """Covariance (N, K, 3, 3) [mm^2] of the predicted target positions at joints ``q`` (N, n).

    First-order propagation ``J C J^T`` of the result's parameter covariance through the
    prediction Jacobian, over the identifiable variables (the others were held fixed and carry
    no estimated uncertainty).
    """
    q = np.asarray(q, dtype=float)
    stations = np.zeros(len(q), dtype=int) if stations is None else np.asarray(stations, dtype=int)
    _, J = problem.predict_points(result.state, q=q, stations=stations, jacobian=True)
    active = np.isfinite(np.diag(result.covariance))
    C = result.covariance[np.ix_(active, active)]
    Ja = J[..., active]
    return Ja @ C @ np.swapaxes(Ja, -1, -2)


#: Poses per block of :func:`predicted_point_std`: the prediction Jacobian of a block (block x K x 3 x
#: n floats) stays a few MB however many poses are asked for.
STD_BLOCK = 4096


def predicted_point_std(problem, result, q, stations=None) -> np.ndarray:
    """Standard deviation (N, K) [mm] of the predicted position: sqrt(trace of the covariance).

    Computed over blocks of :data:`STD_BLOCK` poses, so the memory does not grow with N beyond the
    (N, K) result."""
    q = np.asarray(q, dtype=float)
    stations = np.zeros(len(q), dtype=int) if stations is None else np.asarray(stations, dtype=int)
    parts = []
    for i0 in range(0, len(q), STD_BLOCK):
        cov = predicted_point_covariance(problem, result, q[i0:i0 + STD_BLOCK], stations[i0:i0 + STD_BLOCK])
        parts.append(np.sqrt(np.maximum(np.trace(cov, axis1=-2, axis2=-1), 0.0)))
    return np.concatenate(parts) if parts else np.zeros((0, len(problem.targets)))
