"""The HTML report of a camera or hand-eye calibration (issue 14 item 5): a few images with the
detected corners (green circles) and the back-projected ones (red crosses), the RMS per image as
bars (skipped images marked), the residual vectors of all corners, and tables of every number.

Nothing is computed here: the caller passes the summary dict (the JSON it writes), the grey
images and the detected and projected pixels.
"""

from __future__ import annotations

import html

import numpy as np

from ..io.atomic import atomic_write_text
from .html import _CSS, _f, _img, _status_banner, _table
from .svg import Panel, image_overlay

__all__ = ["plot_backprojection", "plot_rms_per_image", "plot_residuals", "render_camera_report",
           "write_camera_report"]

DETECTED_COLOUR = "#00c000"
PROJECTED_COLOUR = "#e00000"


def plot_backprojection(gray: np.ndarray, detected: np.ndarray, projected: np.ndarray, title: str) -> str:
    """One image with detected (green circles) and projected (red crosses) points, (P, 2) px each, as SVG."""
    return image_overlay(gray, detected, projected, title=title, circle_colour=DETECTED_COLOUR,
                         cross_colour=PROJECTED_COLOUR)


def plot_rms_per_image(names, rms_px, skipped) -> str:
    """Bars of the RMS reprojection error per image [px]; skipped images as grey marks at zero (SVG)."""
    n = len(names)
    x = np.arange(n, dtype=float)
    values = np.array([np.nan if v is None else v for v in rms_px], dtype=float)
    used = np.isfinite(values)
    panel = Panel(max(420, 26 * n + 120), 300, title="Back-projection error per image", y_label="RMS [px]",
                  margins=(70, 20, 28, 80))
    panel.bars(x[used], values[used], 0.7, colour="#4060c0", opacity=1.0)
    if (~used).any():
        panel.points(x[~used], np.zeros(int((~used).sum())), colour="#888888", radius=4)
        panel.bars([], [], 0.7, colour="#888888", label="skipped (grey dot)")
    top = float(np.nanmax(values)) if used.any() else 1.0
    panel.limits(x=(-0.6, n - 0.4), y=(0.0, 1.1 * top or 1.0))
    panel.x_categories([str(v) for v in names])
    return panel.svg()


def plot_residuals(residuals_px: np.ndarray) -> str | None:
    """Scatter of all corner residuals (detected minus projected) [px], (N, P, 2) with NaN (SVG)."""
    r = np.asarray(residuals_px, dtype=float).reshape(-1, 2)
    r = r[np.isfinite(r).all(axis=1)]
    if len(r) == 0:
        return None
    lim = float(np.max(np.abs(r))) * 1.1 or 1.0
    panel = Panel(420, 420, title=f"Corner residuals ({len(r)} corners)", x_label="du [px]", y_label="dv [px]")
    panel.points(r[:, 0], r[:, 1], colour="#4060c0", opacity=0.5, radius=2)
    panel.hline(0.0, colour="#999999")
    panel.vline(0.0, colour="#999999")
    panel.limits(x=(-lim, lim), y=(-lim, lim))
    return panel.svg()


def _pose_rows(summary: dict) -> list:
    rows = []
    for key in ("camera_pose", "target_pose"):
        p = summary.get(key)
        if not p:
            continue
        sig_p = p.get("sigma_position_mm") or [None] * 3
        sig_r = p.get("sigma_rotation_deg") or [None] * 3
        rows.append([f"{key} (in {p['frame']})"] + [_f(v, 3) for v in p["position_mm"]]
                    + [_f(v, 4) for v in p["rotation_vector_deg"]]
                    + [" / ".join(_f(v, 3) for v in sig_p), " / ".join(_f(v, 4) for v in sig_r)])
    return rows


def render_camera_report(summary: dict, *, title: str, overlays=(), rms_plot: str | None = None,
                         residual_plot: str | None = None) -> str:
    """The HTML text. summary: the command's JSON dict (``images`` rows, ``camera``, optional
    ``camera_pose``/``target_pose``/``linear``/``identifiability``); overlays: SVG text of
    :func:`plot_backprojection`."""
    e = html.escape
    out = [f"<!DOCTYPE html><html><head><meta charset='utf-8'><title>{e(title)}</title><style>{_CSS}</style>"
           f"</head><body><h1>{e(title)}</h1>"]
    out += _status_banner(summary)
    status = "ok" if summary.get("converged", True) else "bad"
    out.append(f'<p class="{status}">{e(str(summary.get("message", "")))}</p>')
    out.append(f"<p>Reprojection RMS: <b>{_f(summary.get('reprojection_rms_px'), 3)} px</b> over "
               f"{summary.get('n_corners', '?')} corners in {summary.get('n_images_used', '?')} of "
               f"{summary.get('n_images', '?')} images.</p>")
    pose_rows = _pose_rows(summary)
    if pose_rows:
        out.append("<h2>Result</h2>")
        out.append(_table(["transform", "x [mm]", "y [mm]", "z [mm]", "rx [deg]", "ry [deg]", "rz [deg]",
                           "1-sigma x/y/z [mm]", "1-sigma rotation [deg]"], pose_rows))
        out.append('<p class="note">Rotation vectors (axis times angle) in degrees; '
                   f"{e(str(summary.get('convention', '')))}</p>")
    ident = summary.get("identifiability")
    if ident:
        out.append("<h2>Identifiability</h2><ul>" + "".join(f"<li>{e(str(x))}</li>" for x in ident) + "</ul>")
    linear = summary.get("linear") or {}
    if linear:
        out.append("<h2>Linear solutions on the same detections</h2>")
        rows = [[e(m)] + [_f(v, 2) for v in d["position_mm"]] + [_f(d.get("difference_position_mm"), 2),
                                                                   _f(d.get("difference_rotation_deg"), 3),
                                                                   _f(d.get("reprojection_rms_px"), 2)]
                for m, d in linear.items()]
        out.append(_table(["method", "x [mm]", "y [mm]", "z [mm]", "to refined [mm]", "to refined [deg]",
                           "RMS [px]"], rows))
    cam = summary.get("camera") or {}
    if cam:
        out.append("<h2>Camera</h2>")
        sig = cam.get("sigma") or {}
        rows = [[k, _f(v, 5), _f(sig.get(k), 5)] for k, v in cam.get("parameters", {}).items()]
        out.append(_table(["parameter", "value", "1-sigma"], rows))
    out.append("<h2>Images</h2>")
    rows, classes = [], []
    for r in summary.get("images", []):
        rows.append([e(r["name"]), _f(r.get("n_points")), _f(r.get("rms_px"), 3), _f(r.get("rms_mm"), 3),
                     e(r.get("skip_reason") or "")])
        classes.append("" if r.get("used") else "dropped")
    out.append(_table(["image", "points", "RMS [px]", "RMS [mm on target]", "skipped because"], rows,
                      left=(0, 4), row_class=classes))
    if rms_plot:
        out.append(_img(rms_plot, "RMS per image"))
    if residual_plot:
        out.append("<h2>Residuals</h2>" + _img(residual_plot, "corner residuals"))
    if overlays:
        out.append("<h2>Back-projection</h2><p class='note'>Detected corners: green circles; the target "
                   "projected with the solution: red crosses.</p>")
        out += [_img(png, "back-projection") for png in overlays]
    out.append('<p class="note">Written by robocal; every number is in the JSON output.</p></body></html>')
    return "\n".join(out) + "\n"


def write_camera_report(path, summary: dict, *, title: str, overlays=(), overwrite: bool = False):
    """Write the report (atomic); figures are drawn from ``summary``; ``overlays`` are SVG texts of
    :func:`plot_backprojection`."""
    rows = summary.get("images", [])
    rms_plot = plot_rms_per_image([r["name"] for r in rows], [r.get("rms_px") for r in rows],
                                  [not r.get("used") for r in rows]) if rows else None
    residual_plot = plot_residuals(summary["_residuals_px"]) if "_residuals_px" in summary else None
    text = render_camera_report({k: v for k, v in summary.items() if not k.startswith("_")}, title=title,
                                overlays=overlays, rms_plot=rms_plot, residual_plot=residual_plot)
    return atomic_write_text(path, text, overwrite=overwrite)
