"""Residuals against gravity torque, before and after an elastic calibration (SVG for the report)."""

from __future__ import annotations

import numpy as np

from .svg import Panel

__all__ = ["plot_residuals_vs_torque"]


def plot_residuals_vs_torque(torque, before_mm, after_mm, *, joint: str, unit: str = "N m") -> str | None:
    """Scatter of per-pose position errors [mm] against the gravity torque of ``joint`` (N,), before
    (geometric baseline) and after the elastic calibration; None without data."""
    t = np.asarray(torque, dtype=float)
    b, a = np.asarray(before_mm, dtype=float), np.asarray(after_mm, dtype=float)
    if t.size == 0:
        return None
    panel = Panel(700, 320, title=f"Residuals against the gravity torque of {joint} (training poses)",
                  x_label=f"gravity torque of {joint} [{unit}]", y_label="position error [mm]")
    panel.points(t, b, colour="red", opacity=0.7, radius=2.5, label="before")
    panel.points(t, a, colour="blue", opacity=0.7, radius=2.5, label="after (elastic)")
    return panel.svg()
