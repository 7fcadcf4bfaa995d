"""The calibration report's figures, as PNG bytes (matplotlib's Agg canvas, no pyplot).

Drawing cost is what a user of ``robocal calibrate`` waits for, so the figures are laid out with
fixed margins in inches (no ``tight_layout`` and no ``bbox_inches="tight"``, which each draw the
figure once more to measure it), titles at a fixed height, no minor ticks on log axes, and a set
of bars or a histogram is one polygon collection rather than one patch per bar. Nothing here computes:
every value comes from the result dict or the caller's accuracy map.
"""

from __future__ import annotations

import io
import math

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.collections import PolyCollection
from matplotlib.figure import Figure
from matplotlib.patches import Patch
from matplotlib.ticker import FuncFormatter, NullLocator

__all__ = ["figure_png", "plot_errors_per_pose", "plot_histogram", "plot_parameter_changes", "plot_accuracy_map"]

_DPI = 90
_PLAIN = FuncFormatter(lambda value, _: f"{value:g}")


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


def _log_axis(axis) -> None:
    """No minor ticks, and decade labels as plain numbers (0.01, 0.1, 1: no mathtext to lay out)."""
    axis.set_minor_locator(NullLocator())
    axis.set_major_formatter(_PLAIN)


def _title(ax, text: str) -> None:
    """A title at a fixed height (matplotlib otherwise measures the tick labels to place it)."""
    ax.set_title(text, y=1.01)


def _bars(ax, x, heights, width: float, bottom: float = 0.0, **style):
    """Bars centred at ``x`` with ``heights`` from ``bottom``, drawn as one collection."""
    x = np.asarray(x, dtype=float)
    h = np.asarray(heights, dtype=float)
    x0, x1 = x - width / 2, x + width / 2
    verts = np.stack([np.stack([x0, np.full_like(h, bottom)], -1), np.stack([x0, h], -1),
                      np.stack([x1, h], -1), np.stack([x1, np.full_like(h, bottom)], -1)], axis=1)
    ax.add_collection(PolyCollection(verts[np.isfinite(h)], linewidths=0, **style))
    ax.autoscale_view()
    return Patch(**style)


def _per_pose(per):
    """Per-pose error magnitudes (RMS over the pose's targets) in first-seen pose order."""
    order, idx = [], {}
    for p in per["pose"]:
        if p not in idx:
            idx[p] = len(order)
            order.append(p)
    out = {}
    for key in ("before", "after"):
        vals = np.zeros(len(order))
        cnt = np.zeros(len(order))
        for p, v in zip(per["pose"], per[key]):
            vals[idx[p]] += float(v) ** 2
            cnt[idx[p]] += 1
        out[key] = np.sqrt(vals / np.maximum(cnt, 1))
    return order, out


def _error_sets(result) -> list:
    """[(title, per_point)] for the calibration and the held-out poses (those present)."""
    sets = []
    per = result.get("residuals", {}).get("per_point")
    if per:
        sets.append(("calibration poses", per))
    val = result.get("validation") or {}
    if val.get("per_point"):
        sets.append(("held-out poses", val["per_point"]))
    return sets


def plot_errors_per_pose(result) -> bytes | None:
    """Bars of the position error [mm] per pose, before and after, one panel per pose set."""
    panels = _error_sets(result)
    if not panels:
        return None
    labelled = any(len(_per_pose(per)[0]) <= 40 for _, per in panels)
    fig, axes = _figure(len(panels), 1, (11, 3.3 * len(panels)), bottom=1.0 if labelled else 0.6,
                        hgap=1.3 if labelled else 0.8)
    for ax, (title, per) in zip(axes[:, 0], panels):
        poses, e = _per_pose(per)
        x = np.arange(len(poses))
        positive = np.concatenate([e["before"], e["after"]])
        positive = positive[positive > 0]
        floor = positive.min() / 2 if positive.size else 1e-3
        ax.set_yscale("log")
        handles = [_bars(ax, x - 0.2, e["before"], 0.4, floor, facecolor="tab:red", alpha=0.75),
                   _bars(ax, x + 0.2, e["after"], 0.4, floor, facecolor="tab:green", alpha=0.9)]
        ax.set_xlim(-0.6, len(poses) - 0.4)
        ax.set_ylim(bottom=floor)
        _log_axis(ax.yaxis)
        ax.set_ylabel("position error [mm]")
        _title(ax, f"{title}: error per pose")
        if len(poses) <= 40:
            ax.set_xticks(x, poses, rotation=90, fontsize=7)
        else:
            ax.set_xlabel("pose (index in this set, file order)")
        ax.legend(handles, ["before (nominal model)", "after (calibrated)"], loc="upper right", fontsize=8)
    return figure_png(fig)


def plot_histogram(result) -> bytes | None:
    """Histograms (log bins) of the point errors [mm] before and after, one panel per pose set."""
    sets = _error_sets(result)
    if not sets:
        return None
    fig, axes = _figure(1, len(sets), (5.5 * len(sets), 3.6))
    for ax, (title, per) in zip(axes[0], sets):
        b = np.asarray(per["before"], dtype=float)
        a = np.asarray(per["after"], dtype=float)
        allv = np.concatenate([a, b])
        allv = allv[allv > 0]
        lo, hi = (allv.min(), allv.max()) if allv.size else (1e-3, 1.0)
        bins = np.geomspace(lo * 0.9, hi * 1.1, 40)
        ax.hist(b, bins=bins, histtype="stepfilled", color="tab:red", alpha=0.6, label="before")
        ax.hist(a, bins=bins, histtype="stepfilled", color="tab:green", alpha=0.7, label="after")
        ax.set_xscale("log")
        _log_axis(ax.xaxis)
        ax.set_xlabel("position error [mm]")
        ax.set_ylabel("points")
        _title(ax, title)
        ax.legend(fontsize=8)
    return figure_png(fig)


def plot_parameter_changes(result) -> bytes | None:
    """Bars of the identified geometry changes (lengths [mm], angles [deg]) with 1-std error bars."""
    rows = [p for p in result.get("parameters", []) if p.get("block") == "geometry" and p.get("identifiable")]
    if not rows:
        return None
    groups = [("lengths [mm]", [p for p in rows if p["unit"] == "mm"], 1.0),
              ("angles [deg]", [p for p in rows if p["unit"] == "rad"], 180.0 / math.pi)]
    groups = [g for g in groups if g[1]]
    fig, axes = _figure(len(groups), 1, (11, 3.4 * len(groups)), left=0.9, bottom=0.9, hgap=1.0)
    for ax, (label, ps, scale) in zip(axes[:, 0], groups):
        x = np.arange(len(ps))
        ch = np.array([p["change"] for p in ps]) * scale
        sd = np.array([p["std"] if p["std"] is not None else np.nan for p in ps]) * scale
        _bars(ax, x, ch, 0.8, facecolor="tab:blue", alpha=0.8)
        ax.errorbar(x, ch, yerr=np.nan_to_num(sd), fmt="none", ecolor="k", capsize=3, label="± 1 std")
        ax.axhline(0.0, color="k", lw=0.6)
        ax.set_xticks(x, [p["name"] for p in ps], rotation=90, fontsize=8)
        ax.set_ylabel(f"change {label}")
        ax.legend(fontsize=8)
    _title(axes[0, 0], "identified parameter changes (calibrated - nominal)")
    return figure_png(fig)


def plot_accuracy_map(amap) -> bytes | None:
    """Top and side views of the workspace positions [mm] coloured by the map's values [mm]."""
    if not amap:
        return None
    p = np.asarray(amap["positions_mm"], dtype=float)
    v = np.asarray(amap["values_mm"], dtype=float)
    if p.size == 0:
        return None
    label = amap.get("label", "value [mm]")
    fig, axes = _figure(1, 2, (12, 4.8), top=0.7, right=1.6, wgap=1.0)
    vmax = float(np.nanpercentile(v, 99)) or 1.0
    for ax, (i, j, lab, title) in zip(axes[0], [(0, 1, ("x [mm]", "y [mm]"), "top view"),
                                                (0, 2, ("x [mm]", "z [mm]"), "side view")]):
        sc = ax.scatter(p[:, i], p[:, j], c=v, s=14, cmap="viridis", vmin=0.0, vmax=vmax)
        ax.set_xlabel(lab[0])
        ax.set_ylabel(lab[1])
        ax.set_aspect("equal", adjustable="datalim")
        _title(ax, title)
    fig.colorbar(sc, ax=list(axes[0]), label=label, shrink=0.85)
    fig.suptitle(amap.get("title", "accuracy over the workspace"))
    return figure_png(fig)
