"""The CSV table under the header block of robocal's text formats (measurement, program, target and
tool-calibration files): the column row, the data rows and their numeric cells.

Line numbers are 1-based and counted in the file; problems are reported through the reader's
``fail(message, line=None, column=None)`` (which must raise, see :mod:`robocal.io.header`).
"""

from __future__ import annotations

import csv

import numpy as np

from .stream import check_cell

__all__ = ["csv_cells", "data_rows", "check_field_counts", "check_unique_labels", "parse_number", "number_columns"]


def csv_cells(line: str) -> list:
    """The cells of one CSV line, stripped of surrounding white space."""
    return [c.strip() for c in next(csv.reader([line]))]


def data_rows(lines, start: int) -> list:
    """``[(line number, cells), ...]`` of ``lines[start:]``, skipping blank and ``#`` lines."""
    rows = []
    for k in range(start, len(lines)):
        raw = lines[k]
        if raw.strip() and not raw.lstrip().startswith("#"):
            rows.append((k + 1, csv_cells(raw)))
    return rows


def check_field_counts(rows, n_columns: int, header_line: int, fail) -> None:
    """Every row of ``rows`` (from :func:`data_rows`) has one cell per column of the column row."""
    for line, cells in rows:
        if len(cells) != n_columns:
            fail(f"{len(cells)} fields, expected {n_columns} (one per column of line {header_line})", line)


def check_unique_labels(rows, what: str, column: str, fail) -> dict:
    """The first cell of every row of ``rows`` (from :func:`data_rows`) is a non-empty label given
    once; returns ``{label: line}``. ``what`` names the labels in messages (``"pose"``, ``"image"``)."""
    seen: dict = {}
    for line, cells in rows:
        if not cells[0]:
            fail(f"empty {what} label", line, column)
        if cells[0] in seen:
            fail(f"duplicate {what} {cells[0]!r} (first on line {seen[cells[0]]})", line, column)
        seen[cells[0]] = line
    return seen


def parse_number(cell: str) -> float:
    """The finite float in ``cell``; ``ValueError`` with ``"empty cell"``, ``"'x' is not a number"``
    or ``"'inf' is not a finite number"`` otherwise (:func:`robocal.io.stream.check_cell`: plain
    decimal numbers only, no ``1_000``, magnitudes up to 1e12)."""
    return check_cell(cell)


def number_columns(rows, index, fail_cell) -> np.ndarray:
    """The cells ``index`` (column positions) of ``rows`` (from :func:`data_rows`) as floats,
    shape ``(len(rows), len(index))``. A bad cell calls ``fail_cell(problem, line, position)``
    (which must raise) with the problem text of :func:`parse_number`."""
    out = np.empty((len(rows), len(index)))
    for r, (line, cells) in enumerate(rows):
        for c, j in enumerate(index):
            try:
                out[r, c] = parse_number(cells[j])
            except ValueError as exc:
                fail_cell(str(exc), line, j)
    return out
