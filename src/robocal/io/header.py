"""The shared parts of robocal's text file formats: reading a file's text, the ``# key: value``
header block, declared units, and the error type that names file, line and column.

Every reader in :mod:`robocal.io` raises a subclass of :class:`FileFormatError` (itself a
``ValueError``); a missing file raises ``FileNotFoundError`` where the format says so.
"""

from __future__ import annotations
from ..errors import InputFileError

import re

__all__ = ["FileFormatError", "KEY_RE", "read_header_block", "read_text", "open_text", "declared_unit",
           "header_value"]

#: ``# key: value`` header lines of measurement, target, program and sensor-point files.
KEY_RE = re.compile(r"^#\s*([A-Za-z][A-Za-z0-9_.-]*)\s*:(.*)$")


class FileFormatError(InputFileError):
    """A file is malformed or implausible; the base of every reader's error in :mod:`robocal.io`.

    The message names the file, the 1-based line number and the column where known; the same are
    available as ``path``, ``line`` and ``column`` (``None`` when not applicable). With ``path``
    ``None`` the message is taken as it is: it names the place itself (a YAML key path, an XML
    element), as :class:`~robocal.io.datasets.DatasetError` and :class:`~robocal.io.urdf.UrdfError` do.
    """

    def __init__(self, path, message: str, line: int | None = None, column: str | None = None):
        self.path = None if path is None else str(path)
        self.line = line
        self.column = column
        if path is None:
            super().__init__(message)
            return
        where = self.path if line is None else f"{self.path}, line {line}"
        if column is not None:
            where += f", column {column!r}"
        super().__init__(f"{where}: {message}")


def read_text(path, error=FileFormatError, what: str | None = None) -> str:
    """The text of ``path`` (UTF-8, a byte-order mark allowed).

    Problems raise ``error(path, message)``: a directory, a file that is not UTF-8, an unreadable
    file. A missing file raises ``FileNotFoundError("<path>: no such <what> file")`` when ``what``
    names the kind of file (``"measurement"``, ``"program"``), else ``error(path, "file not found")``.
    """
    with open_text(path, error, what) as fh:
        try:
            return fh.read()
        except UnicodeDecodeError as exc:
            raise error(path, f"not a UTF-8 text file ({exc.reason} at byte {exc.start})") from None
        except OSError as exc:
            raise error(path, f"cannot read: {exc}") from None


def open_text(path, error=FileFormatError, what: str | None = None):
    """``path`` opened for reading text line by line (UTF-8, a byte-order mark allowed), for
    readers that stream; the same errors as :func:`read_text` for a missing file, a directory or an
    unreadable file (a decoding error shows while reading: the caller turns it into ``error``)."""
    try:
        return open(path, encoding="utf-8-sig", newline=None)
    except FileNotFoundError:
        if what is not None:
            raise FileNotFoundError(f"{path}: no such {what} file") from None
        raise error(path, "file not found") from None
    except IsADirectoryError:
        raise error(path, f"is a directory, expected a {what or 'text'} file") from None
    except OSError as exc:
        raise error(path, f"cannot read: {exc.strerror or exc}") from None


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


def declared_unit(values: dict, key_line: dict, key: str, units: dict, fail, default: str | None = None):
    """The unit a header declares under ``key`` (``length_unit``, ``angle_unit``), checked against
    ``units`` (name -> factor to mm / rad, e.g. ``robocal.transforms.LENGTH_UNITS``).

    Returns ``default`` when the key is absent. An unknown unit calls ``fail(message, line)``
    (which must raise) naming the valid ones.
    """
    unit = values.get(key)
    if unit is None:
        return default
    if unit not in units:
        fail(f"unknown {key} {unit!r}; valid: {', '.join(units)}", key_line.get(key))
    return unit


def header_value(path, key: str) -> str | None:
    """The value of ``# key:`` in the header block of the text file ``path``, read only as far as
    the header goes; ``None`` when absent or the file cannot be read."""
    key = key.lower()
    try:
        with open(path, encoding="utf-8-sig") as fh:
            for raw in fh:
                s = raw.strip()
                if s and not s.startswith("#"):
                    break
                m = KEY_RE.match(s)
                if m and m.group(1).lower() == key:
                    return m.group(2).strip()
    except (OSError, UnicodeDecodeError):
        return None
    return None
