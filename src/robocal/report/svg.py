"""Small SVG charts for the HTML reports, written as text (no plotting library).

The calibration report's figures are bars, histograms, error bars, a line and coloured points:
as SVG text they render in milliseconds, are smaller than PNGs at the same legibility, stay sharp
when zoomed, and spare a ``robocal calibrate`` run the ~0.8 s import of matplotlib (issue 12).

A :class:`Panel` is one plot area with its own axes (linear or log on each side). Marks are
recorded first; limits and ticks are computed when :meth:`Panel.svg` renders. Coordinates are data
units; sizes are SVG pixels. Non-finite values are left out of every mark.
"""

from __future__ import annotations

import html
import math

import numpy as np

__all__ = ["Panel", "viridis", "nice_ticks", "log_ticks", "png_gray", "image_overlay"]

# viridis (matplotlib's default colour map, CC0; published table sampled at 17 evenly spaced points),
# linearly interpolated in between (within 4/255 of the full table)
_VIRIDIS = np.array([[68, 1, 84], [72, 24, 106], [71, 45, 123], [66, 64, 134], [59, 82, 139], [51, 99, 141],
                     [44, 114, 142], [38, 130, 142], [33, 145, 140], [31, 160, 136], [40, 174, 128],
                     [63, 188, 115], [94, 201, 98], [132, 212, 75], [173, 220, 48], [216, 226, 25],
                     [253, 231, 37]], dtype=float)

COLOURS = {"red": "#d62728", "green": "#2ca02c", "blue": "#1f77b4", "orange": "#ff7f0e", "grey": "#7f7f7f",
           "black": "#222222"}


def viridis(t) -> list[str]:
    """Hex colours for values ``t`` in [0, 1] (clipped; NaN -> grey)."""
    t = np.asarray(t, dtype=float)
    out = []
    for v in np.atleast_1d(t):
        if not math.isfinite(v):
            out.append("#bbbbbb")
            continue
        s = min(max(v, 0.0), 1.0) * (len(_VIRIDIS) - 1)
        i = min(int(s), len(_VIRIDIS) - 2)
        c = _VIRIDIS[i] + (s - i) * (_VIRIDIS[i + 1] - _VIRIDIS[i])
        out.append("#%02x%02x%02x" % tuple(int(round(x)) for x in c))
    return out


def nice_ticks(lo: float, hi: float, target: int = 6) -> np.ndarray:
    """Tick values at 1, 2 or 5 times a power of ten inside [lo, hi]."""
    if not (math.isfinite(lo) and math.isfinite(hi)) or hi <= lo:
        return np.array([lo]) if math.isfinite(lo) else np.array([])
    raw = (hi - lo) / max(target, 1)
    mag = 10.0 ** math.floor(math.log10(raw))
    step = next(m * mag for m in (1.0, 2.0, 5.0, 10.0) if m * mag >= raw)
    first = math.ceil(lo / step - 1e-9) * step
    ticks = np.arange(first, hi + step * 1e-9, step)
    return np.where(np.abs(ticks) < step * 1e-9, 0.0, ticks)


def log_ticks(lo: float, hi: float) -> np.ndarray:
    """Decades inside [lo, hi] (lo > 0), with 2 and 5 added when the range spans under two decades."""
    if not (lo > 0 and hi > lo):
        return np.array([])
    e0, e1 = math.floor(math.log10(lo)), math.ceil(math.log10(hi))
    mult = (1.0, 2.0, 5.0) if e1 - e0 <= 2 else (1.0,)
    t = np.array([m * 10.0**e for e in range(e0, e1 + 1) for m in mult])
    return t[(t >= lo * (1 - 1e-9)) & (t <= hi * (1 + 1e-9))]


def _fmt(v: float) -> str:
    return f"{v:g}"


def _esc(text) -> str:
    return html.escape(str(text), quote=True)


class Panel:
    """One chart: ``width`` x ``height`` SVG pixels, margins (left, right, top, bottom) around the
    plot area; ``x_log`` / ``y_log`` for logarithmic axes."""

    def __init__(self, width: int = 900, height: int = 280, *, title: str = "", x_label: str = "",
                 y_label: str = "", x_log: bool = False, y_log: bool = False, margins=(70, 20, 28, 48)):
        self.width, self.height = int(width), int(height)
        self.title, self.x_label, self.y_label = title, x_label, y_label
        self.x_log, self.y_log = x_log, y_log
        self.left, self.right, self.top, self.bottom = margins
        self._marks = []          # (kind, payload)
        self._legend = []         # (label, colour, opacity)
        self._xlim = self._ylim = None
        self._xticks = None       # (positions, labels, rotate)
        self._colourbar = None
        self._xs, self._ys = [], []

    # ------------------------------------------------------------------ marks
    def _extent(self, x, y):
        self._xs.append(np.asarray(x, dtype=float).ravel())
        self._ys.append(np.asarray(y, dtype=float).ravel())

    def bars(self, x, heights, width: float, *, bottom: float = 0.0, colour: str = "blue", opacity: float = 0.85,
             label: str | None = None) -> None:
        """Bars centred at ``x`` (n,) of ``heights`` (n,) from ``bottom`` (data units)."""
        x, h = np.asarray(x, dtype=float), np.asarray(heights, dtype=float)
        ok = np.isfinite(x) & np.isfinite(h)
        self._marks.append(("bars", (x[ok], h[ok], float(width), float(bottom), colour, opacity)))
        self._extent(np.concatenate([x[ok] - width / 2, x[ok] + width / 2]), np.append(h[ok], bottom))
        if label:
            self._legend.append((label, colour, opacity))

    def steps(self, edges, counts, *, colour: str = "blue", opacity: float = 0.6, label: str | None = None) -> None:
        """A filled step histogram: ``edges`` (m + 1,), ``counts`` (m,)."""
        e, c = np.asarray(edges, dtype=float), np.asarray(counts, dtype=float)
        self._marks.append(("steps", (e, c, colour, opacity)))
        self._extent(e, np.append(c, 0.0))
        if label:
            self._legend.append((label, colour, opacity))

    def error_bars(self, x, y, err, *, colour: str = "black", label: str | None = None) -> None:
        """Vertical bars y +- err (n,) with caps."""
        x, y, err = (np.asarray(a, dtype=float) for a in (x, y, err))
        ok = np.isfinite(x) & np.isfinite(y) & np.isfinite(err)
        self._marks.append(("errors", (x[ok], y[ok], err[ok], colour)))
        self._extent(x[ok], np.concatenate([y[ok] - err[ok], y[ok] + err[ok]]))
        if label:
            self._legend.append((label, colour, 1.0))

    def segments(self, x, lo, hi, *, colour: str = "grey") -> None:
        """Vertical segments from ``lo`` to ``hi`` (n,) at ``x`` (n,), without caps."""
        x, lo, hi = (np.asarray(a, dtype=float) for a in (x, lo, hi))
        ok = np.isfinite(x) & np.isfinite(lo) & np.isfinite(hi)
        self._marks.append(("segments", (x[ok], lo[ok], hi[ok], colour)))
        self._extent(np.concatenate([x[ok], x[ok]]), np.concatenate([lo[ok], hi[ok]]))

    def line(self, x, y, *, colour: str = "blue", label: str | None = None) -> None:
        x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
        ok = np.isfinite(x) & np.isfinite(y)
        self._marks.append(("line", (x[ok], y[ok], colour)))
        self._extent(x[ok], y[ok])
        if label:
            self._legend.append((label, colour, 1.0))

    def points(self, x, y, values=None, *, vmin: float = 0.0, vmax: float = 1.0, radius: float = 3.0,
               label: str = "", colour: str = "blue", opacity: float = 1.0) -> None:
        """Points coloured by ``values`` on viridis over [vmin, vmax], with a colour bar titled
        ``label``; without ``values``, all in ``colour``."""
        x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
        ok = np.isfinite(x) & np.isfinite(y)
        if values is None:
            colours = [self._fill(colour)] * int(ok.sum())
            if label:
                self._legend.append((label, colour, opacity))
        else:
            span = (vmax - vmin) or 1.0
            colours = viridis((np.asarray(values, dtype=float)[ok] - vmin) / span)
            self._colourbar = (vmin, vmax, label)
        self._marks.append(("points", (x[ok], y[ok], colours, radius, opacity)))
        self._extent(x[ok], y[ok])

    def hline(self, y: float, colour: str = "black") -> None:
        self._marks.append(("hline", (float(y), colour)))

    def x_categories(self, labels, rotate: bool = True) -> None:
        """Category labels at x = 0, 1, ... (rotated to vertical when ``rotate``)."""
        self._xticks = (np.arange(len(labels), dtype=float), [str(s) for s in labels], rotate)

    def limits(self, x=None, y=None) -> None:
        """Fix the axis ranges (lo, hi) in data units; None keeps the automatic range."""
        self._xlim = x if x is not None else self._xlim
        self._ylim = y if y is not None else self._ylim

    # ------------------------------------------------------------------ rendering
    def _auto(self, values, log: bool, pad: float):
        v = np.concatenate(values) if values else np.array([])
        v = v[np.isfinite(v) & ((v > 0) if log else True)]
        if v.size == 0:
            return (1.0, 10.0) if log else (0.0, 1.0)
        lo, hi = float(v.min()), float(v.max())
        if log:
            lo, hi = (lo / 1.5, hi * 1.5) if hi > lo else (lo / 2, hi * 2)
        else:
            d = (hi - lo) or max(abs(hi), 1.0)
            lo, hi = lo - pad * d, hi + pad * d
        return lo, hi

    def _scale(self, lim, log: bool, p0: float, p1: float):
        lo, hi = lim
        if log:
            a, b = math.log10(lo), math.log10(hi)
            return lambda v: p0 + (np.log10(np.maximum(np.asarray(v, dtype=float), 1e-300)) - a) / (b - a) * (p1 - p0)
        return lambda v: p0 + (np.asarray(v, dtype=float) - lo) / ((hi - lo) or 1.0) * (p1 - p0)

    def svg(self) -> str:
        """The chart as a standalone ``<svg>`` element."""
        xlim = self._xlim or self._auto(self._xs, self.x_log, 0.02)
        ylim = self._ylim or self._auto(self._ys, self.y_log, 0.05)
        x0, x1 = self.left, self.width - self.right - (70 if self._colourbar else 0)
        y0, y1 = self.height - self.bottom, self.top
        X, Y = self._scale(xlim, self.x_log, x0, x1), self._scale(ylim, self.y_log, y0, y1)
        self._rendered_ylim = ylim
        out = [f'<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 {self.width} {self.height}" '
               f'width="{self.width}" height="{self.height}" font-family="sans-serif" font-size="11">',
               f'<rect x="{x0}" y="{y1}" width="{x1 - x0}" height="{y0 - y1}" fill="white" stroke="#444"/>']
        out += self._grid(xlim, ylim, X, Y, x0, x1, y0, y1)
        out.append(f'<svg x="{x0}" y="{y1}" width="{x1 - x0}" height="{y0 - y1}" '
                   f'viewBox="{x0} {y1} {x1 - x0} {y0 - y1}" overflow="hidden">')
        for kind, data in self._marks:
            out += getattr(self, "_draw_" + kind)(data, X, Y, x0, x1, y0, y1)
        out.append("</svg>")
        if self.title:
            out.append(f'<text x="{(x0 + x1) / 2:.1f}" y="{y1 - 9}" text-anchor="middle" font-size="13">'
                       f'{_esc(self.title)}</text>')
        if self.x_label:
            out.append(f'<text x="{(x0 + x1) / 2:.1f}" y="{self.height - 6}" text-anchor="middle">{_esc(self.x_label)}</text>')
        if self.y_label:
            cy = (y0 + y1) / 2
            out.append(f'<text x="14" y="{cy:.1f}" text-anchor="middle" transform="rotate(-90 14 {cy:.1f})">'
                       f'{_esc(self.y_label)}</text>')
        out += self._legend_svg(x1, y1)
        out += self._colourbar_svg(x1, y0, y1)
        out.append("</svg>")
        return "\n".join(out)

    def _grid(self, xlim, ylim, X, Y, x0, x1, y0, y1) -> list:
        out = []
        yt = log_ticks(*ylim) if self.y_log else nice_ticks(*ylim)
        for t in yt:
            py = float(Y(t))
            out.append(f'<line x1="{x0}" x2="{x1}" y1="{py:.1f}" y2="{py:.1f}" stroke="#e4e4e4"/>')
            out.append(f'<text x="{x0 - 4}" y="{py + 4:.1f}" text-anchor="end">{_fmt(t)}</text>')
        if self._xticks is not None:
            pos, labels, rotate = self._xticks
            keep = (pos >= xlim[0]) & (pos <= xlim[1])
            for p, lab in zip(pos[keep], np.asarray(labels, dtype=object)[keep]):
                px = float(X(p))
                if rotate:
                    out.append(f'<text x="{px + 3:.1f}" y="{y0 + 6}" text-anchor="end" font-size="9" '
                               f'transform="rotate(-90 {px + 3:.1f} {y0 + 6})">{_esc(lab)}</text>')
                else:
                    out.append(f'<text x="{px:.1f}" y="{y0 + 14}" text-anchor="middle">{_esc(lab)}</text>')
        else:
            for t in (log_ticks(*xlim) if self.x_log else nice_ticks(*xlim)):
                px = float(X(t))
                out.append(f'<line x1="{px:.1f}" x2="{px:.1f}" y1="{y0}" y2="{y0 + 4}" stroke="#444"/>')
                out.append(f'<text x="{px:.1f}" y="{y0 + 15}" text-anchor="middle">{_fmt(t)}</text>')
        return out

    @staticmethod
    def _fill(colour: str) -> str:
        return COLOURS.get(colour, colour)

    def _draw_bars(self, data, X, Y, *_):
        x, h, w, bottom, colour, opacity = data
        if x.size == 0:
            return []
        left, right = X(x - w / 2), X(x + w / 2)
        top, base = Y(h), Y(np.full_like(h, bottom))
        ytop, hgt = np.minimum(top, base), np.abs(base - top)
        rects = "".join(f'<rect x="{a:.1f}" y="{b:.1f}" width="{max(c - a, 0.5):.1f}" height="{d:.1f}"/>'
                        for a, b, c, d in zip(left, ytop, right, hgt))
        return [f'<g fill="{self._fill(colour)}" fill-opacity="{opacity}">{rects}</g>']

    def _draw_steps(self, data, X, Y, *_):
        e, c, colour, opacity = data
        base = float(Y(self._rendered_ylim[0] if self.y_log else 0.0))
        pts = [f"{float(X(e[0])):.1f},{base:.1f}"]
        for i, v in enumerate(c):
            py = float(Y(v)) if (v > 0 or not self.y_log) else base
            pts += [f"{float(X(e[i])):.1f},{py:.1f}", f"{float(X(e[i + 1])):.1f},{py:.1f}"]
        pts.append(f"{float(X(e[-1])):.1f},{base:.1f}")
        return [f'<polygon points="{" ".join(pts)}" fill="{self._fill(colour)}" fill-opacity="{opacity}"/>']

    def _draw_errors(self, data, X, Y, *_):
        x, y, err, colour = data
        px, lo, hi = X(x), Y(y - err), Y(y + err)
        segs = "".join(f"M{a:.1f} {b:.1f}V{c:.1f}M{a - 3:.1f} {b:.1f}h6M{a - 3:.1f} {c:.1f}h6"
                       for a, b, c in zip(px, lo, hi))
        return [f'<path d="{segs}" stroke="{self._fill(colour)}" fill="none"/>'] if segs else []

    def _draw_segments(self, data, X, Y, *_):
        x, lo, hi, colour = data
        segs = "".join(f"M{a:.1f} {b:.1f}V{c:.1f}" for a, b, c in zip(X(x), Y(lo), Y(hi)))
        return [f'<path d="{segs}" stroke="{self._fill(colour)}" fill="none"/>'] if segs else []

    def _draw_line(self, data, X, Y, *_):
        x, y, colour = data
        if x.size == 0:
            return []
        pts = " ".join(f"{a:.1f},{b:.1f}" for a, b in zip(X(x), Y(y)))
        return [f'<polyline points="{pts}" fill="none" stroke="{self._fill(colour)}" stroke-width="1.5"/>']

    def _draw_points(self, data, X, Y, *_):
        x, y, colours, r, opacity = data
        return [f'<g fill-opacity="{opacity}">' + "".join(f'<circle cx="{a:.1f}" cy="{b:.1f}" r="{r}" fill="{c}"/>'
                                                   for a, b, c in zip(X(x), Y(y), colours)) + "</g>"]

    def vline(self, x: float, colour: str = "black") -> None:
        self._marks.append(("vline", (float(x), colour)))

    def _draw_vline(self, data, X, Y, x0, x1, y0, y1):
        x, colour = data
        px = float(X(x))
        return [f'<line x1="{px:.1f}" x2="{px:.1f}" y1="{y0}" y2="{y1}" stroke="{self._fill(colour)}" stroke-width="0.8"/>']

    def _draw_hline(self, data, X, Y, x0, x1, *_):
        y, colour = data
        py = float(Y(y))
        return [f'<line x1="{x0}" x2="{x1}" y1="{py:.1f}" y2="{py:.1f}" stroke="{self._fill(colour)}" stroke-width="0.8"/>']

    def _legend_svg(self, x1, y1) -> list:
        if not self._legend:
            return []
        out = [f'<rect x="{x1 - 196}" y="{y1 + 4}" width="192" height="{15 * len(self._legend) + 6}" '
               f'fill="white" fill-opacity="0.85" stroke="#ccc"/>']
        for i, (label, colour, opacity) in enumerate(self._legend):
            y = y1 + 8 + 15 * i
            out.append(f'<rect x="{x1 - 190}" y="{y}" width="12" height="10" fill="{self._fill(colour)}" '
                       f'fill-opacity="{opacity}"/><text x="{x1 - 173}" y="{y + 9}">{_esc(label)}</text>')
        return out

    def _colourbar_svg(self, x1, y0, y1) -> list:
        if self._colourbar is None:
            return []
        vmin, vmax, label = self._colourbar
        n, h = 24, (y0 - y1) / 24
        xb = x1 + 14
        out = [f'<rect x="{xb}" y="{y1 + (n - 1 - i) * h:.1f}" width="14" height="{h + 0.5:.1f}" fill="{c}"/>'
               for i, c in enumerate(viridis((np.arange(n) + 0.5) / n))]
        for t in nice_ticks(vmin, vmax, 5):
            py = y0 - (t - vmin) / ((vmax - vmin) or 1.0) * (y0 - y1)
            out.append(f'<text x="{xb + 18}" y="{py + 4:.1f}">{_fmt(t)}</text>')
        cy = (y0 + y1) / 2
        out.append(f'<text x="{xb + 60}" y="{cy:.1f}" text-anchor="middle" transform="rotate(-90 {xb + 60} {cy:.1f})">'
                   f'{_esc(label)}</text>')
        return out


def png_gray(gray) -> bytes:
    """An 8-bit greyscale PNG (bytes) of ``gray`` (H, W) uint8 or float in [0, 255] (PNG spec: IHDR
    colour type 0, filter 0 per row, zlib-compressed IDAT)."""
    import struct
    import zlib

    g = np.clip(np.asarray(gray, dtype=float), 0, 255).astype(np.uint8)
    if g.ndim != 2:
        raise ValueError(f"gray: expected an (H, W) image, got shape {g.shape}")
    h, w = g.shape
    raw = np.concatenate([np.zeros((h, 1), np.uint8), g], axis=1).tobytes()

    def chunk(kind: bytes, data: bytes) -> bytes:
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)

    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 0, 0, 0, 0))
            + chunk(b"IDAT", zlib.compress(raw, 6)) + chunk(b"IEND", b""))


def image_overlay(gray, circles, crosses, *, title: str = "", max_width: int = 800,
                  circle_colour: str = "#00c000", cross_colour: str = "#e00000", legend=("detected", "projected")) -> str:
    """An image with marks, as SVG: ``gray`` (H, W) embedded as PNG (downsampled by an integer
    factor to at most ``max_width`` px), ``circles`` and ``crosses`` (P, 2) pixel coordinates of the
    full-size image (NaN rows skipped)."""
    import base64

    g = np.asarray(gray)
    h, w = g.shape[:2]
    step = max(1, int(math.ceil(w / max_width)))
    small = g[::step, ::step]
    sh, sw = small.shape[:2]
    s = 1.0 / step
    top = 22 if title else 0
    out = [f'<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 {sw} {sh + top}" width="{sw}" height="{sh + top}" '
           f'font-family="sans-serif" font-size="12">']
    if title:
        out.append(f'<text x="{sw / 2:.1f}" y="15" text-anchor="middle">{_esc(title)}</text>')
    href = "data:image/png;base64," + base64.b64encode(png_gray(small)).decode("ascii")
    out.append(f'<image x="0" y="{top}" width="{sw}" height="{sh}" href="{href}"/>')
    c = np.asarray(circles, dtype=float).reshape(-1, 2)
    c = c[np.isfinite(c).all(axis=1)] * s
    out.append(f'<g fill="none" stroke="{circle_colour}" stroke-width="1.3">'
               + "".join(f'<circle cx="{a:.1f}" cy="{b + top:.1f}" r="5"/>' for a, b in c) + "</g>")
    x = np.asarray(crosses, dtype=float).reshape(-1, 2)
    x = x[np.isfinite(x).all(axis=1)] * s
    d = "".join(f"M{a - 3.5:.1f} {b + top - 3.5:.1f}l7 7M{a - 3.5:.1f} {b + top + 3.5:.1f}l7 -7" for a, b in x)
    out.append(f'<path d="{d}" stroke="{cross_colour}" stroke-width="1.2"/>')
    out.append(f'<rect x="{sw - 130}" y="{sh + top - 40}" width="126" height="36" fill="white" fill-opacity="0.8"/>'
               f'<circle cx="{sw - 118}" cy="{sh + top - 29}" r="5" fill="none" stroke="{circle_colour}"/>'
               f'<text x="{sw - 106}" y="{sh + top - 25}">{_esc(legend[0])}</text>'
               f'<path d="M{sw - 121.5} {sh + top - 16.5}l7 7M{sw - 121.5} {sh + top - 9.5}l7 -7" stroke="{cross_colour}"/>'
               f'<text x="{sw - 106}" y="{sh + top - 9}">{_esc(legend[1])}</text>')
    out.append("</svg>")
    return "\n".join(out)
