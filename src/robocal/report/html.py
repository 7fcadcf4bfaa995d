"""A self-contained HTML report of a calibration (one file, plots embedded as base64 PNG).

The report only draws and formats what it is given: the dict of
:func:`robocal.calib.outputs.result_to_dict` (with an optional ``validation`` entry) and,
optionally, an accuracy map computed by the caller (no numerics here).
"""

from __future__ import annotations

import base64
import html
import io
import math
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from ..io.atomic import atomic_write_text  # noqa: E402

__all__ = ["write_report", "render_report", "figure_png"]

_CSS = """
body { font-family: system-ui, sans-serif; margin: 2em auto; max-width: 1100px; color: #222; }
h1 { font-size: 1.5em; } h2 { font-size: 1.2em; margin-top: 2em; border-bottom: 1px solid #ccc; }
table { border-collapse: collapse; margin: 0.5em 0; font-size: 0.9em; }
th, td { border: 1px solid #ccc; padding: 0.2em 0.6em; text-align: right; }
th { background: #f0f0f0; } td.l, th.l { text-align: left; }
tr.dropped td { color: #888; } .bad { color: #b00; font-weight: bold; } .ok { color: #070; }
img { max-width: 100%; } .note { color: #555; font-size: 0.9em; }
"""


def figure_png(fig) -> bytes:
    """PNG bytes of a matplotlib figure (the figure is closed)."""
    buf = io.BytesIO()
    try:
        fig.savefig(buf, format="png", dpi=110, bbox_inches="tight")
    finally:
        plt.close(fig)
    return buf.getvalue()


def _img(png: bytes, alt: str) -> str:
    return f'<img alt="{html.escape(alt)}" src="data:image/png;base64,{base64.b64encode(png).decode("ascii")}">'


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
# plots
# ---------------------------------------------------------------------------------------------


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


def _plot_errors_per_pose(result) -> bytes | None:
    panels = []
    per = result.get("residuals", {}).get("per_point")
    if per:
        panels.append(("calibration poses", per))
    val = result.get("validation") or {}
    if val.get("per_point"):
        panels.append(("held-out poses", val["per_point"]))
    if not panels:
        return None
    fig, axes = plt.subplots(len(panels), 1, figsize=(11, 3.3 * len(panels)), squeeze=False)
    for ax, (title, per) in zip(axes[:, 0], panels):
        poses, e = _per_pose(per)
        x = np.arange(len(poses))
        ax.bar(x - 0.2, e["before"], width=0.4, color="tab:red", alpha=0.75, label="before (nominal model)")
        ax.bar(x + 0.2, e["after"], width=0.4, color="tab:green", alpha=0.9, label="after (calibrated)")
        ax.set_yscale("log")
        ax.set_ylabel("position error [mm]")
        ax.set_title(f"{title}: error per pose")
        if len(poses) <= 40:
            ax.set_xticks(x, poses, rotation=90, fontsize=7)
        else:
            ax.set_xlabel("pose (index in this set, file order)")
        ax.legend(loc="upper right", fontsize=8)
    fig.tight_layout()
    return figure_png(fig)


def _plot_histogram(result) -> bytes | None:
    sets = []
    per = result.get("residuals", {}).get("per_point")
    if per:
        sets.append(("calibration poses", per))
    val = result.get("validation") or {}
    if val.get("per_point"):
        sets.append(("held-out poses", val["per_point"]))
    if not sets:
        return None
    fig, axes = plt.subplots(1, len(sets), figsize=(5.5 * len(sets), 3.6), squeeze=False)
    for ax, (title, per) in zip(axes[0], sets):
        b = np.asarray(per["before"], dtype=float)
        a = np.asarray(per["after"], dtype=float)
        allv = np.concatenate([a, b])
        allv = allv[allv > 0]
        lo, hi = (allv.min(), allv.max()) if allv.size else (1e-3, 1.0)
        bins = np.geomspace(lo * 0.9, hi * 1.1, 40)
        ax.hist(b, bins=bins, color="tab:red", alpha=0.6, label="before")
        ax.hist(a, bins=bins, color="tab:green", alpha=0.7, label="after")
        ax.set_xscale("log")
        ax.set_xlabel("position error [mm]")
        ax.set_ylabel("points")
        ax.set_title(title)
        ax.legend(fontsize=8)
    fig.tight_layout()
    return figure_png(fig)


def _plot_parameter_changes(result) -> bytes | None:
    rows = [p for p in result.get("parameters", []) if p.get("block") == "geometry" and p.get("identifiable")]
    if not rows:
        return None
    groups = [("lengths [mm]", [p for p in rows if p["unit"] == "mm"], 1.0),
              ("angles [deg]", [p for p in rows if p["unit"] == "rad"], 180.0 / math.pi)]
    groups = [g for g in groups if g[1]]
    fig, axes = plt.subplots(len(groups), 1, figsize=(11, 3.4 * len(groups)), squeeze=False)
    for ax, (label, ps, scale) in zip(axes[:, 0], groups):
        x = np.arange(len(ps))
        ch = np.array([p["change"] for p in ps]) * scale
        sd = np.array([p["std"] if p["std"] is not None else np.nan for p in ps]) * scale
        ax.bar(x, ch, color="tab:blue", alpha=0.8)
        ax.errorbar(x, ch, yerr=np.nan_to_num(sd), fmt="none", ecolor="k", capsize=3, label="± 1 std")
        ax.axhline(0.0, color="k", lw=0.6)
        ax.set_xticks(x, [p["name"] for p in ps], rotation=90, fontsize=8)
        ax.set_ylabel(f"change {label}")
        ax.legend(fontsize=8)
    axes[0, 0].set_title("identified parameter changes (calibrated - nominal)")
    fig.tight_layout()
    return figure_png(fig)


def _plot_accuracy_map(amap) -> bytes | None:
    if not amap:
        return None
    p = np.asarray(amap["positions_mm"], dtype=float)
    v = np.asarray(amap["values_mm"], dtype=float)
    if p.size == 0:
        return None
    label = amap.get("label", "value [mm]")
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.8))
    vmax = float(np.nanpercentile(v, 99)) or 1.0
    for ax, (i, j, lab, title) in zip(axes, [(0, 1, ("x [mm]", "y [mm]"), "top view"),
                                             (0, 2, ("x [mm]", "z [mm]"), "side view")]):
        sc = ax.scatter(p[:, i], p[:, j], c=v, s=14, cmap="viridis", vmin=0.0, vmax=vmax)
        ax.set_xlabel(lab[0])
        ax.set_ylabel(lab[1])
        ax.set_aspect("equal", adjustable="datalim")
        ax.set_title(title)
    fig.colorbar(sc, ax=list(axes), label=label, shrink=0.85)
    fig.suptitle(amap.get("title", "accuracy over the workspace"))
    return figure_png(fig)


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
    """A banner over the report when the sanity gates failed the result (``status``/``reasons``)."""
    if result.get("status", "ok") == "ok":
        return []
    items = "".join(f"<li>{html.escape(str(r))}</li>" for r in result.get("reasons", []))
    return ['<div class="banner" style="border:3px solid #b00;background:#fee;padding:0.6em 1em;margin:1em 0">'
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
    if md:
        out.append("<h2>Inputs</h2>")
        out.append(_table(["item", "value"], [[e(str(k)), e(str(v))] for k, v in md.items()], left=(0, 1)))
    return out


def _errors_section(result: dict) -> list:
    """Position error statistics before/after, per pose and as histograms."""
    out = ["<h2>Position errors [mm]</h2>"]
    rows = _stats_rows(result)
    if rows:
        out.append(_table(["poses", "RMS", "mean", "p95", "max", "n"], rows))
    out.append('<p class="note">"before": nominal kinematics with the best-fit base frame and target points; '
               '"after": the calibrated model. Held-out poses were not used in the fit.</p>')
    for png, alt in ((_plot_errors_per_pose(result), "error per pose"), (_plot_histogram(result), "error histogram")):
        if png:
            out.append(_img(png, alt))
    return out


def _accuracy_map_section(accuracy_map: dict | None) -> list:
    """The accuracy map plot with its note, if one was given."""
    amap_png = _plot_accuracy_map(accuracy_map)
    if not amap_png:
        return []
    out = ["<h2>Accuracy map</h2>"]
    if accuracy_map.get("note"):
        out.append(f'<p class="note">{html.escape(accuracy_map["note"])}</p>')
    out.append(_img(amap_png, "accuracy map"))
    return out


def _parameters_section(result: dict) -> list:
    """Parameter changes (plot and table, angles in degrees) and the parameters not identifiable."""
    e = html.escape
    out = ["<h2>Parameters</h2>"]
    png = _plot_parameter_changes(result)
    if png:
        out.append(_img(png, "parameter changes"))
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
    """The caller's extra tables (preformatted cells), then its extra plots (PNG bytes or files)."""
    e = html.escape
    out = []
    for name, (header, rows) in (extra_tables or {}).items():
        out.append(f"<h2>{e(name)}</h2>")
        out.append(_table([e(str(h)) for h in header], [[e(str(c)) for c in row] for row in rows]))
    for name, png in (extra_plots or {}).items():
        data = png if isinstance(png, (bytes, bytearray)) else Path(png).read_bytes()
        out.append(f"<h2>{e(name)}</h2>" + _img(bytes(data), name))
    return out


def write_report(path, result: dict, *, accuracy_map: dict | None = None, title: str | None = None,
                 extra_plots: dict | None = None, extra_tables: dict | None = None, overwrite: bool = False) -> Path:
    """Write a self-contained ``report.html`` (atomic; an existing file needs ``overwrite``).

    result: the dict of :func:`robocal.calib.outputs.result_to_dict`, optionally with
        ``validation`` = {``before``, ``after`` (statistics dicts), ``per_point`` = {``pose``,
        ``target``, ``before``, ``after``}}.
    accuracy_map: optional {``positions_mm`` (N, 3), ``values_mm`` (N,), ``label``, ``title``,
        ``note``}: a value per workspace position (predicted uncertainty or residual) to map.
    extra_plots: optional {section title: PNG bytes or PNG file path} appended at the end.
    extra_tables: optional {section title: (header, rows)} of preformatted cells, before the plots.

    Contents: error per pose before/after, error histograms, parameter changes with 1-std error
    bars (identified parameters), the accuracy map, and tables of every number.
    """
    text = render_report(result, accuracy_map=accuracy_map, title=title, extra_plots=extra_plots,
                         extra_tables=extra_tables)
    return atomic_write_text(path, text, overwrite=overwrite)
