"""The outputs of ``robocal iso9283 evaluate``: JSON, the standard's table as text, an HTML report."""

from __future__ import annotations

import html
import json
from pathlib import Path

from ...report.iso9283_figures import iso_figures
from .iso9283_evaluate import iso_table_lines
from ..outputs import check_output_folder, ensure_writable_dir, staged_outputs

__all__ = ["write_iso_outputs"]

NAMES = ["iso9283.json", "iso9283.txt", "report.html"]


def _html(result: dict) -> str:
    parts = ["<!doctype html><meta charset='utf-8'><title>ISO 9283 performance test</title>",
             "<style>body{font-family:sans-serif;max-width:1000px;margin:auto}pre{background:#f6f6f6;padding:8px}"
             "table{border-collapse:collapse}td,th{border:1px solid #ccc;padding:3px 8px;text-align:right}"
             ".figs{display:flex;flex-wrap:wrap;gap:6px}.figs svg{max-width:100%;height:auto}</style>",
             f"<h1>ISO 9283 performance test: {html.escape(str(result.get('robot')))}</h1>"]
    cond = result.get("conditions") or {}
    if cond:
        parts.append("<p>" + "<br>".join(f"<b>{html.escape(k)}</b>: {html.escape(str(v))}" for k, v in cond.items())
                     + "</p>")
    for i, run in enumerate(result["runs"]):
        label = ("before" if i == 0 else "after") if len(result["runs"]) == 2 else "result"
        parts.append(f"<h2>{label}</h2><pre>{html.escape(chr(10).join(iso_table_lines(run)))}</pre>")
        for heading, svgs in iso_figures(run):
            parts.append(f"<h3>{html.escape(heading)}</h3><div class='figs'>" + "".join(svgs) + "</div>")
        if run["drift"]:
            blocks = run["drift"]["per_block"]
            parts.append("<h3>drift of P1 per block</h3><table><tr><th>time [min]</th><th>AP [mm]</th>"
                         "<th>RP [mm]</th></tr>" + "".join(
                             f"<tr><td>{b['time_min']:.0f}</td><td>{b['AP_mm']:.4f}</td><td>{b['RP_mm']:.4f}</td></tr>"
                             for b in blocks) + "</table>")
        for kind, v in run["path"].items():
            parts.append(f"<h3>path {kind}: deviation per evaluation plane</h3><table><tr><th>plane</th>"
                         "<th>deviation [mm]</th><th>l̄+3S [mm]</th></tr>" + "".join(
                             f"<tr><td>{k + 1}</td><td>{a:.4f}</td><td>{b:.4f}</td></tr>"
                             for k, (a, b) in enumerate(zip(v["deviation_mm"], v["repeatability_mm"]))) + "</table>")
    if "comparison" in result:
        parts.append("<h2>before / after</h2><table><tr><th>characteristic</th><th>before</th><th>after</th>"
                     "<th>gain</th></tr>" + "".join(
                         f"<tr><td>{html.escape(r['characteristic'])}</td><td>{r['before']:.4f}</td>"
                         f"<td>{r['after']:.4f}</td><td>{r['gain']:+.4f}</td></tr>" for r in result["comparison"])
                     + "</table>")
    return "\n".join(parts) + "\n"


def write_iso_outputs(out_dir, result: dict, *, overwrite: bool = False, inputs=None) -> dict:
    """Write the three outputs (all or nothing); returns their paths. ``inputs``: the command's input
    paths (``{argument: path}``); an output that is one of them is refused even with ``overwrite``."""
    check_output_folder(out_dir, NAMES, inputs or {}, overwrite)
    out = ensure_writable_dir(out_dir) if not Path(out_dir).exists() else Path(out_dir)
    with staged_outputs(out, NAMES, overwrite=overwrite) as stage:
        (stage / "iso9283.json").write_text(json.dumps(result, indent=1, default=float) + "\n", encoding="utf-8")
        lines = []
        for run in result["runs"]:
            lines += iso_table_lines(run) + [""]
        (stage / "iso9283.txt").write_text("\n".join(lines), encoding="utf-8")
        (stage / "report.html").write_text(_html(result), encoding="utf-8")
    return {n: str(out / n) for n in NAMES}
