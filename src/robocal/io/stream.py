"""Streaming numeric tables: the data rows of a large CSV file read line by line into a float
array, with memory proportional to the rows kept (not to the text), a stated row limit, and
number syntax that is refused where Python alone would accept it.

Cells must be plain decimal numbers (``12``, ``-0.5``, ``1.2e3``); refused are Python-only
spellings (``1_000``), ``nan`` / ``inf``, and magnitudes above :data:`MAX_MAGNITUDE` (no length in
mm or angle in deg is that large, and converting it would overflow).
"""

from __future__ import annotations

import csv
import itertools
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
        keep = np.asarray(keep, dtype=np.int64)
        return NumericTable(self.lines[keep], [self.ids[i] for i in keep], self.values[keep])


def check_cell(cell: str) -> float:
    """The number in one cell, or ``ValueError`` naming the problem (module docstring)."""
    if not cell:
        raise ValueError("empty cell")
    if "_" in cell or not cell.isascii():
        raise ValueError(f"{cell!r} is not a number (plain decimal digits only; no '_' separators)")
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
                       header_line: int | None = None, chunk_rows: int = 50_000) -> NumericTable:
    """Read the data rows of ``lines`` (an iterable of text lines, e.g. an open file, whose first
    line is line ``first_line_no`` of the file); blank and ``#`` lines are skipped.

    Every row has ``n_columns`` cells: an id, then numbers. Problems call ``fail(message, line,
    column_index)`` (which must raise): a wrong number of fields, a bad cell, more than
    ``max_rows`` rows. Lines are parsed ``chunk_rows`` at a time (numpy's C parser; a chunk with
    a problem is re-read cell by cell to name the line and column).
    """
    blocks: list = []
    n, k0 = 0, first_line_no
    it = iter(lines)
    while True:
        raw = [s.strip() for s in itertools.islice(it, chunk_rows)]
        if not raw:
            break
        buf = [s for s in raw if s and s[0] != "#"]
        if len(buf) == len(raw):
            nos = np.arange(k0, k0 + len(raw), dtype=np.int64)
        else:
            nos = k0 + np.array([i for i, s in enumerate(raw) if s and s[0] != "#"], dtype=np.int64)
        k0 += len(raw)
        if n + len(buf) > max_rows:
            fail(f"more than {max_rows:,} data rows, the limit of a measurement file: split the campaign "
                 "into several files or thin it out", int(nos[max_rows - n]), None)
        n += len(buf)
        if buf:
            blocks.append(_chunk(buf, nos, n_columns, fail, header_line))
    if not blocks:
        return NumericTable(np.zeros(0, np.int64), [], np.zeros((0, n_columns)))
    line_nos = np.concatenate([b[0] for b in blocks])
    ids = [i for b in blocks for i in b[1]]
    values = np.empty((len(ids), n_columns))
    values[:, 0] = np.nan
    start = 0
    while blocks:  # fill and free the chunks one by one
        _, _, v = blocks.pop(0)
        values[start:start + len(v), 1:] = v
        start += len(v)
    return NumericTable(line_nos, ids, values)


def _chunk(buf, nos, n_columns: int, fail, header_line) -> tuple:
    """``(line numbers (n,), ids (n,) str, numbers (n, n_columns - 1))`` of the stripped rows
    ``buf``: numpy's C parser (``np.loadtxt``, which refuses ``1_000`` and non-ASCII digits) when
    the fields add up and there are no quotes; else, or on any problem, the exact cell-by-cell
    path that names the line and column."""
    text = "\n".join(buf)
    if text.count(",") == len(buf) * (n_columns - 1) and '"' not in text:
        try:  # a row short of fields fails here, so a row with too many cannot hide in the sum
            values = np.loadtxt(buf, delimiter=",", dtype=float, usecols=range(1, n_columns), comments=None,
                                ndmin=2)
        except ValueError:
            values = None
        if values is not None and (np.abs(values) <= MAX_MAGNITUDE).all():
            ids = [r.partition(",")[0].rstrip() for r in buf]
            return np.asarray(nos, dtype=np.int64), ids, values
    return _chunk_by_cell(buf, nos, n_columns, fail, header_line)


def _chunk_by_cell(buf, nos, n_columns: int, fail, header_line) -> tuple:
    """The slow, exact path of :func:`_chunk`: each row split as CSV and each cell checked."""
    ids, rows = [], []
    for k, s in zip(nos, buf):
        cells = _cells(s)
        if len(cells) != n_columns:
            fail(f"{len(cells)} fields, expected {n_columns} (one per column of line {header_line})", k, None)
        rows.append(_row_numbers(cells, k, fail))
        ids.append(cells[0])
    values = np.array(rows, dtype=float).reshape(len(rows), n_columns - 1)
    return np.array(nos, dtype=np.int64), ids, values


def _row_numbers(cells, line: int, fail) -> list:
    out = []
    for j, c in enumerate(cells[1:], 1):
        try:
            out.append(check_cell(c))
        except ValueError as exc:
            fail(f"{exc} (column {j + 1})", line, j)
    return out
