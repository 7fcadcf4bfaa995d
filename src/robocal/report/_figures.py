"""The calibration report's figures, as SVG text (:mod:`robocal.report.svg`, no plotting library).

Drawing cost is what a user of ``robocal calibrate`` waits for: these figures are bars, histograms,
error bars and coloured points, written as SVG in milliseconds, without importing matplotlib
(~0.8 s). Nothing here computes results: every value comes from the result dict or the caller's
accuracy map. Each function returns one string with one ``<svg>`` per panel, or None when there is
nothing to draw.
"""

from __future__ import annotations

import html
import math

import numpy as np

from .svg import Panel

__all__ = ["plot_errors_per_pose", "plot_histogram", "plot_parameter_changes", "plot_accuracy_map",
           "plot_convergence"]


def _per_pose(per):
    """Per-pose error magnitudes (RMS over the pose's targets) in first-seen pose order."""
    poses = list(per["pose"])
    order = list(dict.fromkeys(poses))
    idx = {p: i for i, p in enumerate(order)}
    slot = np.array([idx[p] for p in poses], dtype=int)
    count = np.bincount(slot, minlength=len(order))
    out = {}
    for key in ("before", "after"):
        v = np.asarray(per[key], dtype=float)
        out[key] = np.sqrt(np.bincount(slot, weights=v**2, minlength=len(order)) / np.maximum(count, 1))
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


#: At most this many bars per panel (a report's size must not grow with the pose count): beyond it
#: each bar is the RMS over a group of consecutive poses; the per-pose values are in residuals.csv.
MAX_BARS = 2000
#: At most this many points per accuracy-map view: beyond it an evenly spaced subset of the poses.
MAX_MAP_POINTS = 5000


def _grouped(poses, e, limit):
    """(labels, errors, poses per bar): groups of consecutive poses, RMS per group, when over ``limit``."""
    n = len(poses)
    if n <= limit:
        return poses, e, 1
    k = -(-n // limit)  # poses per bar
    starts = np.arange(0, n, k)
    counts = np.minimum(starts + k, n) - starts
    g = {key: np.sqrt(np.add.reduceat(v**2, starts) / counts) for key, v in e.items()}
    return [poses[i] for i in starts], g, k


def plot_errors_per_pose(result) -> str | None:
    """Bars of the position error [mm] per pose, before and after, one panel per pose set (more than
    :data:`MAX_BARS` poses: one bar per group of consecutive poses, the group's RMS)."""
    panels = _error_sets(result)
    if not panels:
        return None
    out = []
    for title, per in panels:
        poses, e = _per_pose(per)
        poses, e, k = _grouped(poses, e, MAX_BARS)
        if k > 1:
            title = f"{title} (RMS over groups of {k} consecutive poses; every pose in residuals.csv)"
        x = np.arange(len(poses))
        positive = np.concatenate([e["before"], e["after"]])
        positive = positive[positive > 0]
        floor = positive.min() / 2 if positive.size else 1e-3
        labelled = len(poses) <= 40
        p = Panel(990, 300 if labelled else 260, title=f"{title}: error per pose", y_log=True,
                  y_label="position error [mm]", x_label="" if labelled else "pose (index in this set, file order)",
                  margins=(70, 20, 28, 80 if labelled else 40))
        p.bars(x - 0.2, e["before"], 0.4, bottom=floor, colour="red", opacity=0.75, label="before (nominal model)")
        p.bars(x + 0.2, e["after"], 0.4, bottom=floor, colour="green", opacity=0.9, label="after (calibrated)")
        p.limits(x=(-0.6, len(poses) - 0.4), y=(floor, max(positive.max() * 1.5, floor * 10) if positive.size else 1.0))
        if labelled:
            p.x_categories(poses)
        out.append(p.svg())
    return "\n".join(out)


def plot_histogram(result) -> str | None:
    """Histograms (log bins) of the point errors [mm] before and after, one panel per pose set."""
    sets = _error_sets(result)
    if not sets:
        return None
    out = []
    for title, per in sets:
        b = np.asarray(per["before"], dtype=float)
        a = np.asarray(per["after"], dtype=float)
        allv = np.concatenate([a, b])
        allv = allv[np.isfinite(allv) & (allv > 0)]
        lo, hi = (allv.min(), allv.max()) if allv.size else (1e-3, 1.0)
        bins = np.geomspace(lo * 0.9, hi * 1.1, 40)
        p = Panel(490, 300, title=title, x_log=True, x_label="position error [mm]", y_label="points")
        p.steps(bins, np.histogram(b[np.isfinite(b)], bins)[0], colour="red", opacity=0.6, label="before")
        p.steps(bins, np.histogram(a[np.isfinite(a)], bins)[0], colour="green", opacity=0.7, label="after")
        p.limits(x=(bins[0], bins[-1]))
        out.append(p.svg())
    return "\n".join(out)


def plot_parameter_changes(result) -> str | None:
    """Bars of the identified geometry changes (lengths [mm], angles [deg]) with 1-std error bars."""
    rows = [p for p in result.get("parameters", []) if p.get("block") == "geometry" and p.get("identifiable")]
    if not rows:
        return None
    groups = [("lengths [mm]", [p for p in rows if p["unit"] == "mm"], 1.0),
              ("angles [deg]", [p for p in rows if p["unit"] == "rad"], 180.0 / math.pi)]
    out = []
    for i, (label, ps, scale) in enumerate(g for g in groups if g[1]):
        x = np.arange(len(ps))
        ch = np.array([p["change"] for p in ps], dtype=float) * scale
        sd = np.array([p["std"] if p["std"] is not None else np.nan for p in ps], dtype=float) * scale
        panel = Panel(990, 300, title="identified parameter changes (calibrated - nominal)" if i == 0 else "",
                      y_label=f"change {label}", margins=(80, 20, 28, 80))
        panel.bars(x, ch, 0.8, colour="blue", opacity=0.8)
        panel.error_bars(x, ch, np.nan_to_num(sd), label="± 1 std")
        panel.hline(0.0)
        panel.limits(x=(-0.6, len(ps) - 0.4))
        panel.x_categories([p["name"] for p in ps])
        out.append(panel.svg())
    return "\n".join(out)


def plot_accuracy_map(amap) -> str | None:
    """Top and side views of the workspace positions [mm] coloured by the map's values [mm]."""
    if not amap:
        return None
    p = np.asarray(amap["positions_mm"], dtype=float).reshape(-1, 3)
    v = np.asarray(amap["values_mm"], dtype=float)
    if p.size == 0:
        return None
    label = amap.get("label", "value [mm]")
    finite = v[np.isfinite(v)]
    vmax = float(np.percentile(finite, 99)) if finite.size else 1.0  # over every pose, not the subset
    heading = str(amap.get("title", "accuracy over the workspace"))
    if len(p) > MAX_MAP_POINTS:
        keep = np.linspace(0, len(p) - 1, MAX_MAP_POINTS).round().astype(int)
        heading += f" ({MAX_MAP_POINTS} of the {len(p)} poses, evenly spaced in file order)"
        p, v = p[keep], v[keep]
    out = [f"<p>{html.escape(heading)}</p>"]
    for i, j, (xl, yl), title in [(0, 1, ("x [mm]", "y [mm]"), "top view"), (0, 2, ("x [mm]", "z [mm]"), "side view")]:
        panel = Panel(495, 420, title=title, x_label=xl, y_label=yl)
        panel.points(p[:, i], p[:, j], v, vmin=0.0, vmax=vmax or 1.0, label=label)
        # equal scales on both axes: widen the narrower range around its centre
        lo, hi = np.nanmin(p[:, [i, j]], axis=0), np.nanmax(p[:, [i, j]], axis=0)
        half = 0.55 * max(float(np.max(hi - lo)), 1.0)
        c = (lo + hi) / 2
        panel.limits(x=(c[0] - half * 1.1, c[0] + half * 1.1), y=(c[1] - half, c[1] + half))
        out.append(panel.svg())
    return "\n".join(out)


def plot_convergence(history, *, label: str = "best objective f [mm^2]", title: str | None = None) -> str | None:
    """The swarm's best objective after initialisation (generation 0) and after each generation,
    log scale; None without a history."""
    h = np.asarray(history, dtype=float)
    if h.size < 2 or not np.isfinite(h).any():
        return None
    g = np.arange(h.size)
    ok = np.isfinite(h) & (h > 0)
    panel = Panel(700, 300, title=title or f"IPSO convergence: {h[0]:.4g} -> {h[-1]:.4g}", y_log=True,
                  x_label="generation", y_label=label)
    panel.line(g[ok], h[ok], colour="blue")
    return panel.svg()
