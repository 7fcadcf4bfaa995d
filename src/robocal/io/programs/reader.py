"""Reading a robot program: the format from the file name, the targets from the text."""

from __future__ import annotations

from pathlib import Path

from .fanuc import parse_fanuc
from .krl import parse_krl
from .rapid import parse_rapid
from .source import decode_program
from .target import Program
from .urscript import parse_urscript

__all__ = ["PROGRAM_FORMATS", "SUFFIXES", "read_program", "parse_program"]

#: Format name -> parser ``(text, path) -> (targets, skipped)``.
PROGRAM_FORMATS = {"krl": parse_krl, "rapid": parse_rapid, "fanuc": parse_fanuc, "urscript": parse_urscript}
#: File name suffix (lower case) -> format name.
SUFFIXES = {".src": "krl", ".dat": "krl", ".mod": "rapid", ".modx": "rapid", ".prg": "rapid", ".sys": "rapid",
            ".ls": "fanuc", ".script": "urscript", ".urscript": "urscript"}


def _format_of(path, format) -> str:
    if format is not None:
        if format not in PROGRAM_FORMATS:
            raise ValueError(f"format: expected one of {', '.join(PROGRAM_FORMATS)}, got {format!r}")
        return format
    suffix = Path(path).suffix.lower()
    if suffix not in SUFFIXES:
        raise ValueError(f"{path}: cannot tell the program format from the suffix {suffix!r} (known: "
                         f"{', '.join(sorted(SUFFIXES))}); pass format= one of {', '.join(PROGRAM_FORMATS)}")
    return SUFFIXES[suffix]


def parse_program(text: str, format: str, path="<text>") -> Program:
    """The :class:`Program` of a source ``text`` in ``format`` (``krl``, ``rapid``, ``fanuc``, ``urscript``)."""
    fmt = _format_of(path, format)
    targets, skipped = PROGRAM_FORMATS[fmt](text, path)
    return Program(path=str(path), format=fmt, text=text, encoding="utf-8", targets=tuple(targets),
                   skipped=tuple(skipped))


def read_program(path, format: str | None = None) -> Program:
    """Read the targets of the robot program ``path``.

    format: ``krl`` (``.src``, ``.dat``), ``rapid`` (``.mod``, ``.modx``, ``.prg``, ``.sys``),
        ``fanuc`` (``.ls``) or ``urscript`` (``.script``, ``.urscript``); default from the suffix.

    Raises :class:`~robocal.io.header.FileFormatError` for a malformed target declaration (file,
    line, what was expected).
    """
    fmt = _format_of(path, format)
    text, encoding = decode_program(path)
    targets, skipped = PROGRAM_FORMATS[fmt](text, path)
    return Program(path=str(path), format=fmt, text=text, encoding=encoding, targets=tuple(targets),
                   skipped=tuple(skipped))
