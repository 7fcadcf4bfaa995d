"""A self-contained HTML report of a calibration (one file; figures inline as SVG, callers' extra
PNG plots embedded as base64).

The figures are drawn by :mod:`robocal.report._figures` (SVG text, no plotting library).

The report only draws and formats what it is given: the dict of
:func:`robocal.calib.outputs.result_to_dict` (with an optional ``validation`` entry) and,
optionally, an accuracy map computed by the caller (no numerics here).
"""

from __future__ import annotations

import base64
import html
import math
from pathlib import Path

import numpy as np

from ..io.atomic import atomic_write_text
from ._figures import (
    plot_accuracy_map,
    plot_errors_per_pose,
    plot_histogram,
    plot_parameter_changes,
)

__all__ = ["write_report", "render_report"]

_CSS = """
body { font-family: system-ui, sans-serif; margin: 2em auto; max-width: 1100px; color: #222; }
h1 { font-size: 1.5em; } h2 { font-size: 1.2em; margin-top: 2em; border-bottom: 1px solid #ccc; }
table { border-collapse: collapse; margin: 0.5em 0; font-size: 0.9em; }
th, td { border: 1px solid #ccc; padding: 0.2em 0.6em; text-align: right; }
th { background: #f0f0f0; } td.l, th.l { text-align: left; }
tr.dropped td { color: #888; } .bad { color: #b00; font-weight: bold; } .ok { color: #070; }
img, .fig svg { max-width: 100%; height: auto; } .note { color: #555; font-size: 0.9em; }
"""


def _img(figure, alt: str) -> str:
    """A figure for the page: SVG text inline, PNG bytes as an embedded image."""
    if isinstance(figure, str):
        return f'<div class="fig" role="img" aria-label="{html.escape(alt)}">{figure}</div>'
    return f'<img alt="{html.escape(alt)}" src="data:image/png;base64,{base64.b64encode(figure).decode("ascii")}">'


def _f(x, digits=4) -> str:
    if x is None:
        return "&ndash;"
    if isinstance(x, bool):
        return "yes" if x else "no"
    if isinstance(x, (int, np.integer)):
        return str(int(x))
    x = float(x)
    if not math.isfinite(x):
        return "&ndash;"
    if x != 0 and (abs(x) >= 1e6 or abs(x) < 10 ** (-digits)):
        return f"{x:.{digits}e}"
    return f"{x:.{digits}f}"


def _table(header, rows, left=(0,), row_class=None) -> str:
    out = ["<table><tr>" + "".join(f'<th class="{"l" if i in left else ""}">{html.escape(h)}</th>'
                                   for i, h in enumerate(header)) + "</tr>"]
    for r, row in enumerate(rows):
        cls = f' class="{row_class[r]}"' if row_class and row_class[r] else ""
        out.append(f"<tr{cls}>" + "".join(f'<td class="{"l" if i in left else ""}">{c}</td>'
                                          for i, c in enumerate(row)) + "</tr>")
    return "\n".join(out) + "</table>"


def _display(value, unit):
    """Angles in degrees for reading; lengths stay mm."""
    if value is None:
        return None, unit
    return (math.degrees(value), "deg") if unit == "rad" else (value, unit)


# ---------------------------------------------------------------------------------------------
# the page
# ---------------------------------------------------------------------------------------------


def _stats_rows(result):
    rows = []
    res = result.get("residuals", {})
    for tag, key in (("calibration poses, before", "before"), ("calibration poses, after", "after")):
        s = res.get(key)
        if s:
            rows.append([tag, _f(s["rms"]), _f(s["mean"]), _f(s["p95"]), _f(s["max"]), _f(s["n"])])
    val = result.get("validation") or {}
    for tag, key in (("held-out poses, before", "before"), ("held-out poses, after", "after")):
        s = val.get(key)
        if s:
            rows.append([tag, _f(s["rms"]), _f(s["mean"]), _f(s["p95"]), _f(s["max"]), _f(s["n"])])
    return rows


def render_report(result: dict, *, accuracy_map: dict | None = None, title: str | None = None,
                  extra_plots: dict | None = None, extra_tables: dict | None = None) -> str:
    """The HTML text of the report (see :func:`write_report`)."""
    title = title or f"Calibration report: {result.get('robot', '?')}"
    out = [f"<!DOCTYPE html><html><head><meta charset='utf-8'><title>{html.escape(title)}</title>"
           f"<style>{_CSS}</style></head><body>",
           f"<h1>{html.escape(title)}</h1>"]
    out += _status_banner(result)
    out += _solver_section(result)
    out += _errors_section(result)
    out += _accuracy_map_section(accuracy_map)
    out += _parameters_section(result)
    out += _frames_section(result)
    out += _extra_sections(extra_tables, extra_plots)
    out.append('<p class="note">Written by robocal. Every number is in result.json (lengths mm, angles rad).</p>')
    out.append("</body></html>")
    return "\n".join(out) + "\n"


def _status_banner(result: dict) -> list:
    """A banner over the report when a fit did not converge (``convergence``) or the sanity gates
    failed the result (``status``/``reasons``)."""
    out = []
    conv = result.get("convergence") or {}
    if conv.get("converged") is False:
        items = "".join(f"<li>{html.escape(str(r))}</li>" for r in conv.get("reasons", []))
        out.append('<div class="banner" style="border:3px solid #b00;background:#fee;padding:0.6em 1em;margin:1em 0">'
                   f'<p><b class="bad">NOT CONVERGED: {conv.get("n_not_converged")} of {conv.get("n_fits")} fit(s) '
                   'did not converge; no model file is written unless --allow-unconverged.</b></p>'
                   f'<ul>{items}</ul><p>Try: {html.escape(str(conv.get("what_to_try", "")))}</p></div>')
    if result.get("status", "ok") == "ok":
        return out
    items = "".join(f"<li>{html.escape(str(r))}</li>" for r in result.get("reasons", []))
    return out + ['<div class="banner" style="border:3px solid #b00;background:#fee;padding:0.6em 1em;margin:1em 0">'
                  '<p><b class="bad">FAILED: this result did not pass the sanity gates; do not use it to move a '
                  f'robot.</b></p><ul>{items}</ul></div>']


def _solver_section(result: dict) -> list:
    """Convergence, rank and condition of the solve; the inputs (metadata) table."""
    e = html.escape
    solver = result.get("solver", {})
    md = result.get("metadata") or {}
    conv = solver.get("converged")
    status = '<span class="ok">converged</span>' if conv else '<span class="bad">NOT CONVERGED</span>'
    out = [f"<p>{status} after {_f(solver.get('iterations'))} iterations ({e(str(solver.get('reason', '')))}); "
           f"rank {_f(solver.get('rank'))} of {_f(solver.get('n_variables'))} variables, condition number "
           f"{_f(solver.get('condition_number'), 3)}, a-posteriori sigma0 {_f(solver.get('sigma0'), 4)}.</p>"]
    if solver.get("warning"):
        out.append(f'<p class="bad">Warning: {e(str(solver["warning"]))}</p>')
    if md:
        out.append("<h2>Inputs</h2>")
        out.append(_table(["item", "value"], [[e(str(k)), e(str(v))] for k, v in md.items()], left=(0, 1)))
    return out


def _orientation_rows(orient) -> list:
    """The orientation error table of a 6-D calibration (``result["orientation"]``), or nothing."""
    if not orient:
        return []
    rows = []
    for key, split in (("train", "calibration"), ("holdout", "held-out")):
        for state in ("nominal", "baseline", "calibrated"):
            st = (orient.get(key) or {}).get(state)
            if st:
                rows.append([f"{split} poses, {state}", _f(st["rms"]), _f(st["mean"]), _f(st["p95"]), _f(st["max"]),
                             _f(st["n"])])
    return ["<h2>Orientation errors [deg]</h2>", _table(["poses", "RMS", "mean", "p95", "max", "n"], rows),
            '<p class="note">Angle between the measured and the predicted tool orientation per pose. "nominal": '
            'nominal geometry with the start estimates of the base and tool frames; "baseline": nominal geometry '
            'with the best-fit frames; "calibrated": the identified model and frames.</p>']


def _errors_section(result: dict) -> list:
    """Position error statistics before/after, per pose and as histograms."""
    out = ["<h2>Position errors [mm]</h2>"]
    rows = _stats_rows(result)
    if rows:
        out.append(_table(["poses", "RMS", "mean", "p95", "max", "n"], rows))
    out.append('<p class="note">"before": nominal kinematics with the best-fit base frame and target points; '
               '"after": the calibrated model. Held-out poses were not used in the fit.</p>')
    out += _orientation_rows(result.get("orientation"))
    for fig, alt in ((plot_errors_per_pose(result), "error per pose"), (plot_histogram(result), "error histogram")):
        if fig:
            out.append(_img(fig, alt))
    return out


def _accuracy_map_section(accuracy_map: dict | None) -> list:
    """The accuracy map plot with its note, if one was given."""
    amap_fig = plot_accuracy_map(accuracy_map)
    if not amap_fig:
        return []
    out = ["<h2>Accuracy map</h2>"]
    if accuracy_map.get("note"):
        out.append(f'<p class="note">{html.escape(accuracy_map["note"])}</p>')
    out.append(_img(amap_fig, "accuracy map"))
    return out


def _parameters_section(result: dict) -> list:
    """Parameter changes (plot and table, angles in degrees) and the parameters not identifiable."""
    e = html.escape
    out = ["<h2>Parameters</h2>"]
    fig = plot_parameter_changes(result)
    if fig:
        out.append(_img(fig, "parameter changes"))
    prow, pcls = [], []
    for p in result.get("parameters", []):
        init, unit = _display(p["initial"], p["unit"])
        val, _ = _display(p["value"], p["unit"])
        ch, _ = _display(p["change"], p["unit"])
        sd, _ = _display(p["std"], p["unit"])
        prow.append([e(p["name"]), e(p.get("block", "")), e(unit), _f(init, 6), _f(val, 6), _f(ch, 6), _f(sd, 6),
                     _f(bool(p["identifiable"]))])
        pcls.append("" if p["identifiable"] else "dropped")
    out.append(_table(["name", "block", "unit", "initial", "value", "change", "std", "identified"], prow,
                      left=(0, 1, 2), row_class=pcls))
    out.append('<p class="note">Angles shown in degrees (result.json keeps radians). Base: rotation vector and '
               'origin of the robot base in the instrument frame.</p>')
    ident = result.get("identifiability", {})
    if ident.get("dropped"):
        out.append("<h2>Parameters not identifiable from these data</h2>")
        out.append("<p>Held at their initial values:</p>")
        out.append(_table(["name", "why"], [[e(d["name"]), e(d["why"] or "")] for d in ident["dropped"]], left=(0, 1)))
    return out


def _frames_section(result: dict) -> list:
    """Tables of the base frame(s), the targets and the down-weighted poses, where present."""
    e = html.escape
    out = []
    if result.get("bases"):
        out.append("<h2>Base frame(s)</h2>")
        rows = []
        for b in result["bases"]:
            xyz = b["xyz_mm"]
            rpy = [math.degrees(v) for v in b["rpy_rad"]]
            rows.append([e(b["name"])] + [_f(v, 4) for v in xyz] + [_f(v, 6) for v in rpy] + [_f(b.get("n_poses"))])
        out.append(_table(["frame", "x [mm]", "y [mm]", "z [mm]", "roll [deg]", "pitch [deg]", "yaw [deg]", "poses"],
                          rows))
    if result.get("targets"):
        out.append("<h2>Targets (in the end-effector frame)</h2>")
        rows = []
        for t in result["targets"]:
            sd = t.get("std_mm") or [None] * 3
            rows.append([e(t["name"]), e(t["end_effector"])] + [_f(v, 4) for v in t["point_mm"]]
                        + [_f(v, 4) for v in sd])
        out.append(_table(["target", "end effector", "x [mm]", "y [mm]", "z [mm]", "std x", "std y", "std z"], rows,
                          left=(0, 1)))
    if result.get("outliers"):
        out.append("<h2>Outliers (down-weighted poses)</h2>")
        out.append(_table(["pose", "weight", "reason"],
                          [[e(str(o.get("pose_id", o["pose"]))), _f(o["weight"], 3), e(o["reason"])]
                           for o in result["outliers"]], left=(0, 2)))
    return out


def _extra_sections(extra_tables: dict | None, extra_plots: dict | None) -> list:
    """The caller's extra tables (preformatted cells), then its extra plots (SVG text, PNG bytes or files)."""
    e = html.escape
    out = []
    for name, (header, rows) in (extra_tables or {}).items():
        out.append(f"<h2>{e(name)}</h2>")
        out.append(_table([e(str(h)) for h in header], [[e(str(c)) for c in row] for row in rows]))
    for name, fig in (extra_plots or {}).items():
        if isinstance(fig, str) and fig.lstrip().startswith("<svg"):
            data = fig
        else:
            data = bytes(fig) if isinstance(fig, (bytes, bytearray)) else Path(fig).read_bytes()
        out.append(f"<h2>{e(name)}</h2>" + _img(data, name))
    return out


def write_report(path, result: dict, *, accuracy_map: dict | None = None, title: str | None = None,
                 extra_plots: dict | None = None, extra_tables: dict | None = None, overwrite: bool = False) -> Path:
    """Write a self-contained ``report.html`` (atomic; an existing file needs ``overwrite``).

    result: the dict of :func:`robocal.calib.outputs.result_to_dict`, optionally with
        ``validation`` = {``before``, ``after`` (statistics dicts), ``per_point`` = {``pose``,
        ``target``, ``before``, ``after``}}.
    accuracy_map: optional {``positions_mm`` (N, 3), ``values_mm`` (N,), ``label``, ``title``,
        ``note``}: a value per workspace position (predicted uncertainty or residual) to map.
    extra_plots: optional {section title: SVG text, PNG bytes or PNG file path} appended at the end.
    extra_tables: optional {section title: (header, rows)} of preformatted cells, before the plots.

    Contents: error per pose before/after, error histograms, parameter changes with 1-std error
    bars (identified parameters), the accuracy map, and tables of every number.
    """
    text = render_report(result, accuracy_map=accuracy_map, title=title, extra_plots=extra_plots,
                         extra_tables=extra_tables)
    return atomic_write_text(path, text, overwrite=overwrite)
