"""The shared parts of robocal's text file formats: the ``# key: value`` header block and the
error type that names file, line and column."""

from __future__ import annotations

import re

__all__ = ["FileFormatError", "KEY_RE", "read_header_block", "read_text"]

#: ``# key: value`` header lines of measurement, target, program and sensor-point files.
KEY_RE = re.compile(r"^#\s*([A-Za-z][A-Za-z0-9_.-]*)\s*:(.*)$")


class FileFormatError(ValueError):
    """A file is malformed or implausible.

    The message names the file, the 1-based line number and the column where known; the same are
    available as ``path``, ``line`` and ``column`` (``None`` when not applicable).
    """

    def __init__(self, path, message: str, line: int | None = None, column: str | None = None):
        self.path = str(path)
        self.line = line
        self.column = column
        where = self.path if line is None else f"{self.path}, line {line}"
        if column is not None:
            where += f", column {column!r}"
        super().__init__(f"{where}: {message}")


def read_header_block(lines, fail):
    """Parse the leading ``#`` lines of ``lines`` (a list of str).

    Returns ``(values, key_line, index)``: key -> value (keys lower-cased; repeated ``note`` lines
    joined with newlines), key -> 1-based line number, and the index of the first line that is
    neither blank nor a ``#`` line. Other ``#`` lines are free comments. A key given twice calls
    ``fail(message, line)`` (which must raise).
    """
    values: dict[str, str] = {}
    key_line: dict[str, int] = {}
    notes: list[str] = []
    i = 0
    while i < len(lines):
        raw = lines[i].strip()
        if not raw:
            i += 1
            continue
        if not raw.startswith("#"):
            break
        m = KEY_RE.match(raw)
        if m:
            key, value = m.group(1).lower(), m.group(2).strip()
            if key == "note":
                notes.append(value)
                key_line.setdefault("note", i + 1)
            elif key in values:
                fail(f"header key {key!r} given twice (first on line {key_line[key]})", i + 1)
            else:
                values[key], key_line[key] = value, i + 1
        i += 1
    if notes:
        values["note"] = "\n".join(notes)
    return values, key_line, i


def read_text(path, error=FileFormatError) -> str:
    """The text of ``path`` (UTF-8, a byte-order mark allowed); problems raise ``error(path, message)``."""
    from pathlib import Path

    try:
        return Path(path).read_text(encoding="utf-8-sig")
    except FileNotFoundError:
        raise error(path, "file not found") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise error(path, f"cannot read: {exc}") from None
