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


def predicted_point_std(problem, result, q, stations=None) -> np.ndarray:
    """Standard deviation (N, K) [mm] of the predicted position: sqrt(trace of the covariance)."""
    cov = predicted_point_covariance(problem, result, q, stations)
    return np.sqrt(np.maximum(np.trace(cov, axis1=-2, axis2=-1), 0.0))
