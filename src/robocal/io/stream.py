"""Streaming numeric tables: the data rows of a large CSV file read line by line into a float
array, with memory proportional to the rows kept (not to the text), a stated row limit, and
number syntax that is refused where Python alone would accept it.

Cells must be plain decimal numbers (``12``, ``-0.5``, ``1.2e3``); refused are Python-only
spellings (``1_000``), ``nan`` / ``inf``, and magnitudes above :data:`MAX_MAGNITUDE` (no length in
mm or angle in deg is that large, and converting it would overflow).
"""

from __future__ import annotations

import csv
import math
from dataclasses import dataclass

import numpy as np

__all__ = ["MAX_ROWS", "MAX_MAGNITUDE", "NumericTable", "read_numeric_table", "check_cell"]

#: Data rows a measurement file may have (a 200 MB file has about 2 M rows of 10 columns).
MAX_ROWS = 2_000_000
#: Largest magnitude of a number cell.
MAX_MAGNITUDE = 1.0e12


@dataclass(frozen=True)
class NumericTable:
    """Rows of a CSV table: ``lines`` (N,) 1-based line numbers in the file, ``ids`` N strings
    (the first column), ``values`` (N, n_columns) floats (column 0, the ids, is NaN)."""

    lines: np.ndarray
    ids: list
    values: np.ndarray

    def __len__(self) -> int:
        return len(self.ids)

    def subset(self, keep) -> "NumericTable":
        keep = np.asarray(keep)
        return NumericTable(self.lines[keep], [self.ids[i] for i in keep], self.values[keep])


def check_cell(cell: str) -> float:
    """The number in one cell, or ``ValueError`` naming the problem (module docstring)."""
    if not cell:
        raise ValueError("empty cell")
    if "_" in cell:
        raise ValueError(f"{cell!r} is not a number (digit separators '_' are not allowed)")
    try:
        v = float(cell)
    except ValueError:
        raise ValueError(f"{cell!r} is not a number") from None
    if not math.isfinite(v):
        raise ValueError(f"{cell!r} is not a finite number")
    if abs(v) > MAX_MAGNITUDE:
        raise ValueError(f"{cell!r} is implausibly large (above {MAX_MAGNITUDE:g} in magnitude)")
    return v


def _cells(raw: str) -> list:
    if '"' in raw:
        return [c.strip() for c in next(csv.reader([raw]))]
    return [c.strip() for c in raw.split(",")]


def read_numeric_table(lines, first_line_no: int, n_columns: int, fail, *, max_rows: int = MAX_ROWS,
                       header_line: int | None = None) -> NumericTable:
    """Read the data rows of ``lines`` (an iterable of text lines, e.g. an open file, whose first
    line is line ``first_line_no`` of the file); blank and ``#`` lines are skipped.

    Every row has ``n_columns`` cells: an id, then numbers. Problems call ``fail(message, line,
    column_index)`` (which must raise): a wrong number of fields, a bad cell, more than
    ``max_rows`` rows.
    """
    cap = 1024
    values = np.empty((cap, n_columns))
    line_nos = np.empty(cap, dtype=np.int64)
    ids: list = []
    n = 0
    for k, raw in enumerate(lines, first_line_no):
        s = raw.strip()
        if not s or s.startswith("#"):
            continue
        cells = _cells(s)
        if len(cells) != n_columns:
            fail(f"{len(cells)} fields, expected {n_columns} (one per column of line {header_line})", k, None)
        if n >= max_rows:
            fail(f"more than {max_rows:,} data rows, the limit of a measurement file: split the campaign "
                 "into several files or thin it out", k, None)
        if n == cap:
            cap *= 2
            values = np.resize(values, (cap, n_columns))
            line_nos = np.resize(line_nos, cap)
        try:
            values[n, 1:] = [float(c) for c in cells[1:]]
        except ValueError:
            values[n, 1:] = _row_numbers(cells, k, fail)
        if "_" in s.partition(",")[2]:  # 1_000: float() takes it, a CSV reader must not
            values[n, 1:] = _row_numbers(cells, k, fail)
        ids.append(cells[0])
        line_nos[n] = k
        n += 1
    values, line_nos = values[:n].copy(), line_nos[:n].copy()
    values[:, 0] = np.nan
    with np.errstate(invalid="ignore"):
        bad = ~(np.abs(values[:, 1:]) <= MAX_MAGNITUDE)  # NaN, inf or too large
    if bad.any():
        r = int(np.argwhere(bad)[0][0])
        _row_numbers([ids[r]] + [repr(float(v)) for v in values[r, 1:]], int(line_nos[r]), fail)
    return NumericTable(line_nos, ids, values)


def _row_numbers(cells, line: int, fail) -> list:
    out = []
    for j, c in enumerate(cells[1:], 1):
        try:
            out.append(check_cell(c))
        except ValueError as exc:
            fail(f"{exc} (column {j + 1})", line, j)
    return out
