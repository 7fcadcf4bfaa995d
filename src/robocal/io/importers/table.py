"""A delimited text table with a header row somewhere near the top (tracker and controller exports).

Lines before the header row (job name, date, units line, ...) are kept as the preamble; blank
lines and lines starting with ``#`` or ``//`` are skipped everywhere. The header row is the first
line whose column names satisfy the caller's test; its delimiter (``;``, tab, ``,`` or whitespace)
is used for the whole table, and the decimal separator is detected from the data cells.
"""

from __future__ import annotations

from dataclasses import dataclass

from ..header import FileFormatError
from .text import decode_file, detect_decimal, detect_delimiter, split_fields, split_name_unit

__all__ = ["Table", "read_table"]

_COMMENT_PREFIXES = ("#", "//")
_MAX_PREAMBLE = 50  # lines searched for the header row


@dataclass(frozen=True)
class Table:
    """The cells of a table as text.

    columns: header names as written; names: the same lower-cased without unit; units: the unit in
    the header (``"X [mm]"`` -> ``"mm"``) or ``None``; rows: the data cells (stripped), one list per
    row, as long as ``columns``; lines: 1-based line number of each row; header_line: line of the
    header row; preamble: ``(line, text)`` of the lines above it.
    """

    path: str
    columns: tuple
    names: tuple
    units: tuple
    rows: tuple
    lines: tuple
    header_line: int
    preamble: tuple
    delimiter: str | None
    decimal: str
    encoding: str

    def index(self, candidates) -> int | None:
        """Index of the first column whose name is in ``candidates`` (lower case), or ``None``."""
        for i, name in enumerate(self.names):
            if name in candidates:
                return i
        return None

    def fail(self, message: str, line: int | None = None, column: str | None = None):
        raise FileFormatError(self.path, message, line, column)


def read_table(path, is_header, what: str, *, delimiter: str | None = "auto", decimal: str | None = None,
               encoding: str | None = None) -> Table:
    """Read ``path`` as a table whose header row satisfies ``is_header(names)``.

    is_header: called with the lower-cased names (units removed) of each candidate line.
    what: the expected header, for the error message (e.g. ``"Name;X;Y;Z"``).
    delimiter: ``"auto"`` (detect from the header row), ``";"``, ``","``, ``"\\t"`` or ``None``
        (runs of whitespace). decimal: ``"."``, ``","`` or ``None`` (detect).
    """
    text, used_encoding = decode_file(path, encoding)
    lines = text.splitlines()
    preamble, header = [], None
    for k, raw in enumerate(lines[:_MAX_PREAMBLE]):
        stripped = raw.strip()
        if not stripped:
            continue
        delim = detect_delimiter(stripped) if delimiter == "auto" else delimiter
        names = [split_name_unit(c)[0] for c in split_fields(stripped, delim)]
        if is_header(names):
            header = (k, delim)
            break
        preamble.append((k + 1, stripped))
    if header is None:
        first = next((s.strip() for s in lines if s.strip()), "")
        raise FileFormatError(path, f"no header row naming the columns ({what}) in the first {_MAX_PREAMBLE} "
                                    f"lines; the file starts with {first[:60]!r}")
    k0, delim = header
    columns = split_fields(lines[k0].strip(), delim)
    while columns and not columns[-1]:  # a trailing delimiter
        columns.pop()
    rows, row_lines = [], []
    for k in range(k0 + 1, len(lines)):
        stripped = lines[k].strip()
        if not stripped or stripped.startswith(_COMMENT_PREFIXES):
            continue
        fields = split_fields(stripped, delim)
        if len(fields) > len(columns) and not any(fields[len(columns):]):
            fields = fields[:len(columns)]
        if len(fields) != len(columns):
            raise FileFormatError(path, f"{len(fields)} fields, expected {len(columns)} "
                                        f"(one per column of the header on line {k0 + 1})", k + 1)
        rows.append(fields)
        row_lines.append(k + 1)
    if not rows:
        raise FileFormatError(path, f"no data rows after the header on line {k0 + 1}")
    split = [split_name_unit(c) for c in columns]
    dec = decimal or detect_decimal((c for r in rows for c in r), delim)
    return Table(path=str(path), columns=tuple(columns), names=tuple(n for n, _ in split),
                 units=tuple(u for _, u in split), rows=tuple(rows), lines=tuple(row_lines),
                 header_line=k0 + 1, preamble=tuple(preamble), delimiter=delim, decimal=dec,
                 encoding=used_encoding)
