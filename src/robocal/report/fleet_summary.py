"""The fleet summary: one HTML page with a table of every robot and a plot of the accuracy before
and after calibration per robot, outliers flagged (``robocal fleet calibrate``).

Nothing here computes: the rows (and their ``outlier`` flags) come from
:mod:`robocal.workflows.fleet`.
"""

from __future__ import annotations

import base64
import html
import math
from pathlib import Path

import numpy as np

from ..io.atomic import atomic_write_bytes, atomic_write_text
from ._mpl import _figure, figure_png

__all__ = ["plot_fleet_accuracy", "write_fleet_summary_html"]


def _accuracy(row, when: str):
    """Held-out RMS [mm] when the robot has held-out poses, else the calibration poses' RMS."""
    v = row.get(f"holdout_rms_{when}_mm")
    return v if v is not None else row.get(f"rms_{when}_mm")


def plot_fleet_accuracy(rows, title: str) -> bytes:
    """PNG: accuracy before and after calibration per robot (log scale, mm), outliers in red."""
    done = [r for r in rows if _accuracy(r, "after") is not None]
    n = max(1, len(done))
    fig, axes = _figure(1, 1, (min(5.0 + 0.18 * n, 24.0), 4.6), left=0.9, bottom=1.0, top=0.8)
    ax = axes[0, 0]
    x = np.arange(len(done))
    before = np.array([_accuracy(r, "before") for r in done], dtype=float)
    after = np.array([_accuracy(r, "after") for r in done], dtype=float)
    flagged = np.array([bool(r.get("outlier")) for r in done], dtype=bool)
    if len(done):
        ax.vlines(x, after, before, color="0.75", lw=1.0)
        ax.plot(x, before, "o", ms=4, color="tab:gray", label="before (nominal model)")
        ax.plot(x[~flagged], after[~flagged], "o", ms=4, color="tab:blue", label="after calibration")
        if flagged.any():
            ax.plot(x[flagged], after[flagged], "s", ms=6, color="tab:red", label="after: outlier")
        ax.set_yscale("log")
        ax.set_xticks(x)
        ax.set_xticklabels([r["id"] for r in done], rotation=90, fontsize=6 if n > 40 else 8)
        ax.legend(fontsize=8, loc="lower left", bbox_to_anchor=(0.0, 1.01), ncol=3, frameon=False)
    ax.set_ylabel("position error RMS [mm]\n(held-out poses)")
    ax.set_title(title, fontsize=10, pad=22)
    ax.grid(True, axis="y", alpha=0.3)
    return figure_png(fig)


def _cell(v, digits=4) -> str:
    if v is None or (isinstance(v, float) and not math.isfinite(v)):
        return "-"
    if isinstance(v, float):
        return f"{v:.{digits}f}"
    return html.escape(str(v))


def write_fleet_summary_html(path, summary: dict, png: bytes, png_name: str) -> Path:
    """Write the fleet summary page ``path`` (the plot embedded, and also saved as ``png_name``
    beside it); ``summary`` is the dict written to summary.json."""
    path = Path(path)
    atomic_write_bytes(path.parent / png_name, png, overwrite=True)
    rows = summary["robots"]
    head = ("<tr><th>robot</th><th>status</th><th>model</th><th>cell</th><th>poses</th>"
            "<th>before [mm]</th><th>after [mm]</th><th>outlier</th><th>reason</th></tr>")
    body = []
    for r in rows:
        cls = "failed" if r["status"] != "ok" else ("outlier" if r.get("outlier") else "")
        link = f'<a href="{html.escape(r["result"])}">{html.escape(r["id"])}</a>' if r.get("result") else html.escape(
            str(r["id"]))
        body.append(f'<tr class="{cls}"><td>{link}</td><td>{html.escape(r["status"])}</td><td>{_cell(r.get("model"))}'
                    f'</td><td>{_cell(r.get("cell"))}</td><td>{_cell(r.get("n_poses"))}</td>'
                    f'<td>{_cell(_accuracy(r, "before"))}</td><td>{_cell(_accuracy(r, "after"))}</td>'
                    f'<td>{"yes" if r.get("outlier") else ""}</td><td>{_cell(r.get("reason"))}</td></tr>')
    c = summary["counts"]
    img = base64.b64encode(png).decode()
    text = f"""<!DOCTYPE html>
<html><head><meta charset="utf-8"><title>Fleet calibration: {html.escape(summary['fleet'])}</title>
<style>body{{font-family:sans-serif;margin:1.5em}} table{{border-collapse:collapse;font-size:13px}}
td,th{{border:1px solid #ccc;padding:2px 6px;text-align:right}} td:first-child,td:nth-child(3),td:nth-child(4),
td:last-child{{text-align:left}} tr.failed{{background:#fdd}} tr.outlier{{background:#ffe8c0}}</style></head>
<body><h1>Fleet calibration: {html.escape(summary['fleet'])}</h1>
<p>{c['robots']} robots: {c['ok']} ok, {c['failed']} failed, {c['outliers']} outlier(s); {c['skipped']} unchanged
since an earlier run (skipped). Accuracy is the RMS position error on the held-out poses (the calibration poses
when none were held out), before (nominal model, best-fit base) and after calibration. Outlier: {html.escape(
        summary['outlier_rule'])}.</p>
<img alt="accuracy before and after per robot" src="data:image/png;base64,{img}">
<table>{head}{''.join(body)}</table></body></html>
"""
    return atomic_write_text(path, text, overwrite=True)
