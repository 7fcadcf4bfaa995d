"""matplotlib helpers for the report figures that are PNG files (the fleet summary's plot): a
figure with fixed margins in inches (no layout pass that draws it twice to measure it) and its
PNG bytes. The HTML reports' own figures are SVG text (:mod:`robocal.report.svg`).
"""

from __future__ import annotations

import io

from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

__all__ = ["figure_png"]

_DPI = 90


def figure_png(fig) -> bytes:
    """PNG bytes of a matplotlib figure (a pyplot figure is closed afterwards)."""
    buf = io.BytesIO()
    try:
        fig.savefig(buf, format="png", dpi=_DPI)
    finally:
        if getattr(fig.canvas, "manager", None) is not None:  # made by pyplot: release it
            import matplotlib.pyplot as plt

            plt.close(fig)
    return buf.getvalue()


def _figure(nrows: int, ncols: int, size_in, *, left=0.8, right=0.2, top=0.4, bottom=0.6, hgap=0.8, wgap=0.9):
    """A figure of ``size_in`` (width, height) [inch] with an (nrows, ncols) grid of axes and fixed
    margins and gaps [inch] (cheap: no layout pass that draws the figure to measure it)."""
    w, h = size_in
    fig = Figure(figsize=(w, h))
    FigureCanvasAgg(fig)
    axes = fig.subplots(nrows, ncols, squeeze=False)
    cell_w = (w - left - right - wgap * (ncols - 1)) / ncols
    cell_h = (h - top - bottom - hgap * (nrows - 1)) / nrows
    fig.subplots_adjust(left=left / w, right=1 - right / w, bottom=bottom / h, top=1 - top / h,
                        wspace=wgap / cell_w, hspace=hgap / cell_h)
    return fig, axes


def _title(ax, text: str) -> None:
    """A title at a fixed height (matplotlib otherwise measures the tick labels to place it)."""
    ax.set_title(text, y=1.01)
