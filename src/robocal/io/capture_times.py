"""Matching images to joint readings by time stamp (issue 15: camera self-calibration).

The files are ``robocal-joint-log/1`` and ``robocal-frames/1`` (:mod:`robocal.io.joint_log_files`,
docs/joint-log-files.md). :func:`match_capture_times` gives each image its joints: the nearest log
row (``"nearest"``) or the linear interpolation of the two rows around the capture time
(``"interpolate"``), if within ``tolerance`` seconds; otherwise the image is unmatched and gets a
reason.
"""

from __future__ import annotations

import numpy as np

__all__ = ["match_capture_times", "MATCH_MODES"]

MATCH_MODES = ("nearest", "interpolate")


def match_capture_times(image_times, log_times, log_joints, *, tolerance: float, mode: str = "nearest",
                        offset: float = 0.0):
    """``(joints (N, n) NaN where unmatched, dt (N,) [s] image time minus the matched reading's,
    reasons (N,) None or why unmatched)``.

    log_times (M,) [s] increasing; tolerance [s]: how far the nearest reading (``"nearest"``), or
    both readings around the image (``"interpolate"``), may be from the capture time; offset [s]
    is added to the log's times (a known clock difference).
    """
    if mode not in MATCH_MODES:
        raise ValueError(f"match mode must be one of {', '.join(MATCH_MODES)}, got {mode!r}")
    if not tolerance > 0:
        raise ValueError(f"tolerance: expected a positive number of seconds, got {tolerance!r}")
    t = np.asarray(image_times, dtype=float)
    tl = np.asarray(log_times, dtype=float) + offset
    Q = np.asarray(log_joints, dtype=float)
    M = len(tl)
    k = np.searchsorted(tl, t)  # tl[k-1] <= t < tl[k]
    lo, hi = np.clip(k - 1, 0, M - 1), np.clip(k, 0, M - 1)
    d_lo, d_hi = np.abs(t - tl[lo]), np.abs(tl[hi] - t)
    nearest = np.where(d_lo <= d_hi, lo, hi)
    dt = t - tl[nearest]
    q = Q[nearest].copy()
    reasons = [None] * len(t)
    if mode == "interpolate":
        both = (k > 0) & (k < M) & (d_lo <= tolerance) & (d_hi <= tolerance)
        span = np.where(tl[hi] > tl[lo], tl[hi] - tl[lo], 1.0)
        f = np.clip((t - tl[lo]) / span, 0.0, 1.0)[:, None]
        q = np.where(both[:, None], (1 - f) * Q[lo] + f * Q[hi], q)
        dt = np.where(both, 0.0, dt)
        bad = ~both
    else:
        bad = np.abs(dt) > tolerance
    for i in np.flatnonzero(bad):
        if mode == "interpolate" and abs(dt[i]) <= tolerance:
            reasons[i] = (f"no joint readings on both sides within {tolerance:g} s (nearest {dt[i]:+.3f} s away; "
                          "use --match nearest)")
        else:
            reasons[i] = (f"no joint reading within {tolerance:g} s of the capture time (nearest "
                          f"{dt[i]:+.3f} s away; log {tl.min():.3f}..{tl.max():.3f} s)")
    q[bad] = np.nan
    return q, dt, reasons
