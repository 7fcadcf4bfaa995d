"""Drift over time from the history database: parameter deltas and cycle metrics (PNG).

Takes the :class:`robocal.store.Series` the store returns; no database access and no numerics here.
"""

from __future__ import annotations

from datetime import datetime, timezone

import numpy as np

from .plots import plt, save_figure
from .units import display_unit

__all__ = ["plot_history"]

_EVENT_STYLE = {"geometric_calibration": ("tab:green", "geometric calibration"),
                "tool_recalibration": ("tab:red", "tool recalibration")}


def _display(unit: str):
    return display_unit(unit)  # the console and JSON of `robocal history` show the same units


def plot_history(parameters: dict, metrics: dict, path, title: str, *, events=(), max_metrics: int = 4,
                 field: str = "delta", verifications=()):
    """Parameters grouped by unit (one panel per unit: lengths in mm, angles in deg) and one panel
    per metric, against time (UTC).

    parameters, metrics: ``{name: Series}`` from ``HistoryStore.parameter_history`` /
    ``metric_history``; events: ``(time, kind)`` pairs drawn as vertical lines (geometric and tool
    calibrations); field: the name of the plotted parameter quantity, for the axis label.
    Returns the written path (saved atomically).
    """
    groups: dict = {}
    for name, s in parameters.items():
        if len(s):
            groups.setdefault(s.unit, []).append((name, s))
    mets = [(n, s) for n, s in metrics.items() if len(s)][:max_metrics]
    verifications = list(verifications)
    n_panels = len(groups) + len(mets) + bool(verifications)
    if n_panels == 0:
        raise ValueError("nothing to plot: no parameter or metric values in the selection")
    fig, axes = plt.subplots(n_panels, 1, figsize=(11, 2.6 * n_panels + 0.8), sharex=True, squeeze=False,
                             layout="constrained")
    axes = axes[:, 0]
    label = "Δ" if field == "delta" else "value"
    units = sorted(groups, key=lambda u: (u not in ("mm", "rad"), u))
    for ax, unit in zip(axes, units):
        _parameter_panel(ax, unit, groups[unit], label)
    for ax, (name, s) in zip(axes[len(units):], mets):
        _metric_panel(ax, name, s)
    if verifications:
        _verification_panel(axes[-1], verifications)
    _event_lines(fig, axes, events)
    axes[-1].set_xlabel("time (UTC)")
    for lab in axes[-1].get_xticklabels():
        lab.set_rotation(25)
        lab.set_horizontalalignment("right")
    fig.suptitle(title)
    return save_figure(fig, path)


def _parameter_panel(ax, unit: str, items, label: str) -> None:
    """One panel: the parameters ``items`` ((name, Series) pairs) stored in ``unit``, in display
    units, with 1-std error bars where stored."""
    k, shown = _display(unit)
    for name, s in items:
        line, = ax.plot(s.times, s.values * k, marker="o", ms=3, lw=1.2, label=name)
        ok = np.isfinite(s.std)
        if ok.any():
            ax.errorbar(s.times[ok], s.values[ok] * k, yerr=s.std[ok] * k, fmt="none", ecolor=line.get_color(),
                        alpha=0.5, capsize=2)
    ax.axhline(0.0, color="0.6", lw=0.8)
    ax.set_ylabel(f"{label} [{shown}]")
    ax.set_title(f"parameters in {shown}", loc="left", fontsize=10)
    ax.legend(fontsize=8, ncol=min(6, max(1, (len(items) + 5) // 6)), loc="upper left", frameon=False)
    ax.grid(alpha=0.3)


def _metric_panel(ax, name: str, s) -> None:
    """One panel: the metric ``name`` (a Series) in display units."""
    k, shown = _display(s.unit)
    ax.plot(s.times, s.values * k, marker="o", ms=3, lw=1.2, color="tab:purple")
    ax.set_ylabel(f"[{shown}]")
    ax.set_title(name, loc="left", fontsize=10)
    ax.grid(alpha=0.3)


_OUTCOMES = (("ok", "tab:green"), ("recalibrate", "tab:orange"), ("mechanical fault suspected", "tab:red"))


def _verification_panel(ax, verifications) -> None:
    """One panel: each quick verification's decision (ok / recalibrate / fault) at its time."""
    for level, (decision, colour) in enumerate(_OUTCOMES):
        ts = [np.datetime64(t.astimezone(timezone.utc).replace(tzinfo=None), "us") if isinstance(t, datetime) else t
              for t, d in verifications if d == decision]
        if ts:
            ax.plot(ts, [level] * len(ts), "o", color=colour, ms=7)
    ax.set_yticks(range(len(_OUTCOMES)), [d for d, _ in _OUTCOMES], fontsize=8)
    ax.set_ylim(-0.5, len(_OUTCOMES) - 0.5)
    ax.set_title("verifications", loc="left", fontsize=10)
    ax.grid(alpha=0.3)


def _event_lines(fig, axes, events) -> None:
    """Vertical dashed lines at geometric and tool calibrations ((time, kind) pairs) on every
    panel, with a figure legend of the kinds shown."""
    seen = set()
    for t, kind in events:
        if kind not in _EVENT_STYLE:
            continue
        color = _EVENT_STYLE[kind][0]
        if isinstance(t, datetime) and t.tzinfo is not None:
            t = t.astimezone(timezone.utc).replace(tzinfo=None)
        for ax in axes:
            ax.axvline(np.datetime64(t, "us"), color=color, ls="--", lw=1.0)
        seen.add(kind)
    if seen:
        handles = [plt.Line2D([], [], color=_EVENT_STYLE[k][0], ls="--", label=_EVENT_STYLE[k][1]) for k in sorted(seen)]
        fig.legend(handles=handles, loc="outside upper right", fontsize=8, frameon=False, ncol=len(handles))
