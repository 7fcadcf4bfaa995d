"""The console table of ``robocal calibrate``: identified parameters with change and sigma, and
the ones not identified with the reason (from the ``result.json`` dict)."""

from __future__ import annotations

import math

__all__ = ["parameter_table", "statistics_table", "fixed_columns"]

_DEG = 180.0 / math.pi


def _shown(value, unit):
    """(value in display units, display unit): angles in degrees."""
    if value is None:
        return float("nan"), unit
    return (value * _DEG, "deg") if unit == "rad" else (value, unit)


def fixed_columns(rows, decimals: int, min_width: int) -> list:
    """Each row of numbers formatted with ``decimals`` places, right-aligned in columns as wide as
    the widest entry needs (at least ``min_width``), with one blank between columns: no two numbers
    run together at any magnitude. Returns the cells (lists of str) and the column widths."""
    cells = [[f"{v:.{decimals}f}" for v in row] for row in rows]
    n = max((len(r) for r in cells), default=0)
    widths = [max([min_width] + [len(r[j]) + 1 for r in cells if j < len(r)]) for j in range(n)]
    return cells, widths


def statistics_table(title: str, rows, decimals: int = 4) -> list:
    """Console lines of error statistics: ``title`` then one row per ``(label, stats)`` (RMS,
    mean, p95, max), columns widened to the largest value."""
    keys = ("rms", "mean", "p95", "max")
    cells, widths = fixed_columns([[s[k] for k in keys] for _, s in rows], decimals, 9)
    if not widths:
        widths = [9] * 4
    label_w = max([30] + [len(label) + 2 for label, _ in rows] + [len(title) + 2])
    out = [f"{title:<{label_w}}" + "".join(f"{k.upper() if k == 'rms' else k:>{w}}" for k, w in zip(keys, widths))]
    out += [f"{label:<{label_w}}" + "".join(f"{c:>{w}}" for c, w in zip(row, widths))
            for (label, _), row in zip(rows, cells)]
    return out


def _row(p, widths=(14, 12, 11)) -> str:
    value, unit = _shown(p["value"], p["unit"])
    change, _ = _shown(p["change"], p["unit"])
    std, _ = _shown(p["std"], p["unit"])
    cells = [f"{v:.5f}" for v in (value, change, std)]
    return f"  {p['name']:<16}{unit:<5}" + "".join(f"{c:>{w}}" for c, w in zip(cells, widths))


def parameter_table(result: dict, *, include_base: bool = False) -> list:
    """Lines: one per identified variable (name, unit, value, change from the start, 1-std;
    angles in degrees), then the variables held at their initial values with the reason. Base
    frame variables are left out unless ``include_base`` (they place the instrument, not the robot)."""
    params = result.get("parameters") or []
    shown = [p for p in params if p.get("identifiable") and (include_base or p.get("block") != "base")]
    widths = [14, 12, 11]
    for p in shown:  # widen a column whose numbers would touch their neighbour's
        for j, key in enumerate(("value", "change", "std")):
            widths[j] = max(widths[j], len(f"{_shown(p[key], p['unit'])[0]:.5f}") + 1)
    lines = [f"identified ({len(shown)} of {len(params)} variables{'' if include_base else ', base frame not shown'}):",
             f"  {'name':<16}{'unit':<5}{'value':>{widths[0]}}{'change':>{widths[1]}}{'sigma':>{widths[2]}}"]
    lines += [_row(p, widths) for p in shown]
    dropped = (result.get("identifiability") or {}).get("dropped") or []
    if dropped:
        lines.append(f"not identified ({len(dropped)}, held at their initial values):")
        lines += [f"  {d['name']:<16}{d['why']}" for d in dropped]
    return lines
