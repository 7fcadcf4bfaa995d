"""The swarm's convergence curve (best objective per generation) as PNG bytes for the report."""

from __future__ import annotations

import numpy as np

from ._figures import _figure, _log_axis, _title, figure_png

__all__ = ["plot_convergence"]


def plot_convergence(history, *, label: str = "best objective f [mm^2]", title: str | None = None) -> bytes | None:
    """Best f after initialisation (generation 0) and after each generation, log scale;
    None without a history."""
    h = np.asarray(history, dtype=float)
    if h.size < 2 or not np.isfinite(h).any():
        return None
    fig, axes = _figure(1, 1, (7.0, 3.2))
    ax = axes[0, 0]
    g = np.arange(h.size)
    ok = np.isfinite(h) & (h > 0)
    ax.plot(g[ok], h[ok], color="tab:blue", linewidth=1.2)
    ax.set_yscale("log")
    _log_axis(ax.yaxis)
    ax.set_xlabel("generation")
    ax.set_ylabel(label)
    _title(ax, title or f"IPSO convergence: {h[0]:.4g} -> {h[-1]:.4g}")
    return figure_png(fig)
