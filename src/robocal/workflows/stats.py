"""Small summaries shared by the multi-seed studies (thermal table 5-2, tool-frame accuracy)."""

from __future__ import annotations

import numpy as np

__all__ = ["summarise"]


def summarise(values) -> dict:
    """median, q25, q75 (quartiles), min, max and n of ``values`` (n,)."""
    v = np.asarray(values, float)
    q25, med, q75 = np.percentile(v, [25, 50, 75])
    return {"median": float(med), "q25": float(q25), "q75": float(q75), "min": float(v.min()), "max": float(v.max()),
            "n": int(len(v))}
