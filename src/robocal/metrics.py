"""Error statistics used by validation, reports and the demo (no I/O)."""

from __future__ import annotations

import numpy as np

__all__ = ["error_statistics"]


def error_statistics(errors) -> dict:
    """RMS, mean, 95th percentile, max and count of error magnitudes.

    errors: (N,) non-negative magnitudes, or (N, 3) vectors whose Euclidean norms are taken.
    Units are those of the input. NaNs are refused.
    """
    e = np.asarray(errors, dtype=float)
    if e.ndim == 2:
        e = np.linalg.norm(e, axis=-1)
    if e.ndim != 1 or e.size == 0:
        raise ValueError(f"errors: expected a non-empty (N,) or (N, 3) array, got shape {np.shape(errors)}")
    if not np.all(np.isfinite(e)):
        raise ValueError("errors: contains NaN or infinite values")
    return {"rms": float(np.sqrt(np.mean(e**2))), "mean": float(e.mean()), "p95": float(np.percentile(e, 95)),
            "max": float(e.max()), "n": int(e.size)}
