"""Text of other software's exports: decoding, field splitting and numbers with a decimal comma.

Everything here is format-agnostic; the importers (one module per source) build on it. Problems
raise :class:`~robocal.io.header.FileFormatError` naming the file, the 1-based line and the column.
"""

from __future__ import annotations

import csv
import math
import re
from pathlib import Path

from ..header import FileFormatError

__all__ = [
    "read_bytes",
    "decode_file",
    "detect_delimiter",
    "split_fields",
    "detect_decimal",
    "parse_number",
    "number_cell",
    "split_name_unit",
]

_NUMBER_DOT = re.compile(r"^[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?$")
_NUMBER_COMMA = re.compile(r"^[-+]?(?:\d+,?\d*|,\d+)(?:[eE][-+]?\d+)?$")
_HAS_COMMA_DECIMAL = re.compile(r"^[-+]?\d*,\d+(?:[eE][-+]?\d+)?$")
_NAME_UNIT = re.compile(r"^(.*?)\s*(?:\[\s*([^\]]*?)\s*\]|\(\s*([^)]*?)\s*\)|/\s*(mm|m|in|inch|deg|rad|°|s|ms))\s*$", re.I)


def read_bytes(path) -> bytes:
    """The bytes of ``path``; a missing or unreadable file is a :class:`FileFormatError`."""
    try:
        return Path(path).read_bytes()
    except FileNotFoundError:
        raise FileFormatError(path, "file not found") from None
    except OSError as exc:
        raise FileFormatError(path, f"cannot read: {exc}") from None


def decode_file(path, encoding: str | None = None) -> tuple[str, str]:
    """``(text, encoding)`` of ``path``.

    With ``encoding=None``: a UTF-16 or UTF-8 byte-order mark decides; otherwise UTF-8 is tried
    and, if the bytes are not UTF-8, Latin-1 (ISO 8859-1, which decodes every byte) is used, as
    written by many Windows export tools. The returned encoding names what was used.
    """
    data = read_bytes(path)
    if encoding is not None:
        try:
            return data.decode(encoding), encoding
        except (UnicodeDecodeError, LookupError) as exc:
            raise FileFormatError(path, f"cannot decode as {encoding}: {exc}") from None
    if data.startswith((b"\xff\xfe", b"\xfe\xff")):
        return data.decode("utf-16"), "utf-16"
    try:
        return data.decode("utf-8-sig"), "utf-8"
    except UnicodeDecodeError:
        return data.decode("latin-1"), "latin-1"


def detect_delimiter(line: str) -> str | None:
    """The field delimiter of a header line: ``";"``, ``"\\t"``, ``","``, or ``None`` (whitespace)."""
    for delimiter in (";", "\t", ","):
        if delimiter in line:
            return delimiter
    return None


def split_fields(line: str, delimiter: str | None) -> list[str]:
    """Fields of ``line`` (stripped). ``None`` splits on runs of whitespace; otherwise CSV quoting
    rules apply (a quoted field may hold the delimiter)."""
    if delimiter is None:
        return line.split()
    return [f.strip() for f in next(csv.reader([line], delimiter=delimiter))]


def detect_decimal(cells, delimiter: str | None) -> str:
    """``","`` when the numbers in ``cells`` use a decimal comma, else ``"."``.

    A decimal comma is only possible when the delimiter is not a comma (or the cell was quoted);
    it is chosen when some cell looks like ``123,45`` and no cell looks like ``123.45``.
    """
    comma = dot = False
    for cell in cells:
        if _HAS_COMMA_DECIMAL.match(cell):
            comma = True
        elif "." in cell and _NUMBER_DOT.match(cell):
            dot = True
    return "," if comma and not dot else "."


def parse_number(cell: str, decimal: str = ".") -> float | None:
    """The finite float in ``cell`` (``decimal`` is ``"."`` or ``","``), or ``None``."""
    pattern = _NUMBER_COMMA if decimal == "," else _NUMBER_DOT
    if not pattern.match(cell):
        return None
    value = float(cell.replace(",", ".")) if decimal == "," else float(cell)
    return value if math.isfinite(value) else None


def number_cell(cell: str, decimal: str, path, line: int, column: str) -> float:
    """:func:`parse_number` or a :class:`FileFormatError` saying what was expected."""
    value = parse_number(cell, decimal)
    if value is None:
        what = "empty cell" if not cell else f"{cell!r} is not a number"
        sep = "decimal comma, e.g. 1234,56" if decimal == "," else "decimal point, e.g. 1234.56"
        raise FileFormatError(path, f"{what}; expected a number ({sep})", line, column)
    return value


def split_name_unit(header: str, lower: bool = True) -> tuple[str, str | None]:
    """``("x", "mm")`` from ``"X [mm]"``, ``"X (mm)"`` or ``"X/mm"``: the stripped name (lower-cased
    unless ``lower=False``) and the lower-cased unit, ``None`` when the header names none."""
    text = header.strip()
    m = _NAME_UNIT.match(text)
    name, unit = (m.group(1).strip(), next(g for g in m.groups()[1:] if g is not None)) if m and m.group(1) \
        else (text, None)
    return (name.lower() if lower else name), (unit.strip().lower() or None) if unit is not None else None
