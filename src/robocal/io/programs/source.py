"""Source text of robot programs: numbers with their spans, comment masking, line numbers, and
number formatting in the program's own style."""

from __future__ import annotations

import bisect
import re

from ..importers.text import read_bytes

__all__ = ["NUMBER", "NUMBER_RE", "NUMBER_FULL", "decode_program", "mask", "LineIndex", "format_like"]

#: A decimal number as controllers write it: ``-12``, ``12.50``, ``.5``, ``-.000``, ``9E+09``.
NUMBER = r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?"
NUMBER_RE = re.compile(NUMBER)
#: A whole text that is one such number.
NUMBER_FULL = re.compile(rf"^{NUMBER}$")
_NUMBER_PARTS = re.compile(r"^([-+]?)(\d*)(?:(\.)(\d*))?(?:([eE])([-+]?\d+))?$")


def decode_program(path) -> tuple[str, str]:
    """``(text, encoding)``: UTF-8 if the bytes are UTF-8, else Latin-1 (controller files written on
    Windows). Line endings and a byte-order mark stay in the text, so encoding it back with the same
    encoding gives the original bytes."""
    data = read_bytes(path)
    try:
        return data.decode("utf-8"), "utf-8"
    except UnicodeDecodeError:
        return data.decode("latin-1"), "latin-1"


def mask(text: str, comment: str, quotes: str = '"') -> str:
    """``text`` with comments (``comment`` to the end of the line) and quoted strings replaced by
    spaces; same length and same line breaks, so offsets and line numbers still hold."""
    out = list(text)
    i, n = 0, len(text)
    while i < n:
        ch = text[i]
        if ch in quotes:
            end = text.find(ch, i + 1)
            newline = text.find("\n", i + 1)
            end = end if end != -1 and (newline == -1 or end < newline) else (newline if newline != -1 else n)
            for k in range(i, min(end + 1, n)):
                if out[k] not in "\r\n":
                    out[k] = " "
            i = end + 1
        elif text.startswith(comment, i):
            end = text.find("\n", i)
            end = n if end == -1 else end
            for k in range(i, end):
                if out[k] != "\r":
                    out[k] = " "
            i = end
        else:
            i += 1
    return "".join(out)


class LineIndex:
    """1-based line numbers of character offsets in a text."""

    def __init__(self, text: str):
        self._starts = [0] + [m.end() for m in re.finditer("\n", text)]

    def line(self, offset: int) -> int:
        return bisect.bisect_right(self._starts, offset)


def format_like(value: float, original: str, min_decimals: int = 0) -> str:
    """``value`` written in the style of ``original`` (a number as found in the program).

    Same number of decimals (at least ``min_decimals``), same exponent form (``9E+09``), same
    leading sign ``+`` and leading-zero style (``.500``) as the original. A value that rounds to
    zero is written without a minus sign unless the original had one.
    """
    m = _NUMBER_PARTS.match(original.strip())
    if m is None:
        raise ValueError(f"format_like: {original!r} is not a number")
    sign, integer, dot, fraction, exp_char, _ = m.groups()
    decimals = max(len(fraction or ""), min_decimals)
    if exp_char:
        text = f"{value:.{decimals}{exp_char}}"
    else:
        text = f"{value:.{decimals}f}"
        if dot and decimals == 0:
            text += "."
    if text.startswith("-") and float(text) == 0.0 and not original.strip().startswith("-"):
        text = text[1:]
    if not integer and not exp_char:  # ".500" style: no leading zero
        text = re.sub(r"^(-?)0\.", r"\1.", text)
    if sign == "+" and not text.startswith("-"):
        text = "+" + text
    return text
