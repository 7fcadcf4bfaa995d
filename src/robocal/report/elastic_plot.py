"""Residuals against gravity torque, before and after an elastic calibration (PNG for the report)."""

from __future__ import annotations

import numpy as np

from ._figures import _figure, _title, figure_png

__all__ = ["plot_residuals_vs_torque"]


def plot_residuals_vs_torque(torque, before_mm, after_mm, *, joint: str, unit: str = "N m") -> bytes | None:
    """Scatter of per-pose position errors [mm] against the gravity torque of ``joint`` (N,), before
    (geometric baseline) and after the elastic calibration; None without data."""
    t = np.asarray(torque, dtype=float)
    b, a = np.asarray(before_mm, dtype=float), np.asarray(after_mm, dtype=float)
    if t.size == 0:
        return None
    fig, axes = _figure(1, 1, (7.0, 3.4))
    ax = axes[0, 0]
    ax.scatter(t, b, s=10, color="tab:red", alpha=0.7, label="before")
    ax.scatter(t, a, s=10, color="tab:blue", alpha=0.7, label="after (elastic)")
    ax.set_xlabel(f"gravity torque of {joint} [{unit}]")
    ax.set_ylabel("position error [mm]")
    ax.legend(loc="upper left", fontsize=8)
    _title(ax, f"Residuals against the gravity torque of {joint} (training poses)")
    return figure_png(fig)
