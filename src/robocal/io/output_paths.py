"""No user file replaced by accident (issue 29): the one check every command runs before it writes.

* An output path that resolves to one of the same command's inputs (the same path, a symbolic or
  hard link to it) is refused **even with** ``--overwrite``: a second run would read its own
  output (a program compensated twice, a robot file replaced by its plan).
* An existing output is refused without ``--overwrite``.

Both raise :class:`~robocal.errors.OutputExistsError` naming the file, one line each.
"""

from __future__ import annotations

import hashlib
import os
import re
from pathlib import Path

from ..errors import OutputExistsError

__all__ = ["OutputIsInputError", "same_file", "check_outputs", "check_not_inputs", "safe_file_stem", "path_under",
           "PathEscapeError"]


class OutputIsInputError(OutputExistsError):
    """An output path is one of the command's inputs."""


def same_file(a, b) -> bool:
    """True when paths ``a`` and ``b`` name the same file (after resolving links; hard links too)."""
    a, b = Path(a), Path(b)
    try:
        if a.resolve() == b.resolve():
            return True
        return a.exists() and b.exists() and os.path.samefile(a, b)
    except OSError:
        return False


def _pairs(items):
    if items is None:
        return []
    if isinstance(items, dict):
        return [(str(k), v) for k, v in items.items() if v is not None]
    if isinstance(items, (str, os.PathLike)):
        return [("", items)]
    return [("", v) for v in items if v is not None]


def check_not_inputs(outputs, inputs) -> None:
    """:class:`OutputIsInputError` when an output names an input file (refused even with
    ``--overwrite``). outputs, inputs: a path, a list of paths or ``{what: path}`` (None skipped;
    ``what`` names the option in the message, e.g. ``"--program"``)."""
    # :func:`same_file` of every pair, in time linear in the count (a fleet has ~10 outputs and ~2
    # inputs per robot): two existing files are the same file when they have the same identity
    # (device, inode), whatever links lead to them; an output that does not exist is no input. One
    # os.stat per path (pathlib's resolve and parsing had cost ~8 ms of a 100-robot fleet's start);
    # the resolved path is compared only where a file system gives no inode numbers (st_ino 0).
    by_id, by_path = {}, {}
    for what_in, inp in _pairs(inputs):
        try:
            st = os.stat(inp)
        except (OSError, ValueError):  # a shipped robot's name is no file
            continue
        by_id.setdefault((st.st_dev, st.st_ino), what_in)
        if not st.st_ino:
            by_path.setdefault(os.path.realpath(inp), what_in)
    if not by_id:
        return
    for _, out in _pairs(outputs):
        try:
            st = os.stat(out)
        except (OSError, ValueError):
            continue
        what_in = by_id.get((st.st_dev, st.st_ino)) if st.st_ino else by_path.get(os.path.realpath(out))
        if what_in is not None:
            label = f" ({what_in})" if what_in else ""
            raise OutputIsInputError(
                f"{out}: is an input of this command{label}; write the output to a new file "
                "(refused even with --overwrite, so that nothing you had is replaced)")


def check_outputs(outputs, inputs=None, *, overwrite: bool = False) -> None:
    """:func:`check_not_inputs`, then :class:`OutputExistsError` naming the first existing output
    (unless ``overwrite``)."""
    check_not_inputs(outputs, inputs)
    if overwrite:
        return
    for _, out in _pairs(outputs):
        if Path(out).exists():
            raise OutputExistsError(f"{out}: output file exists; pass --overwrite to replace it")


class PathEscapeError(OutputExistsError):
    """A path built from data (a robot id, a label) would leave its output folder."""


_UNSAFE = re.compile(r"[^A-Za-z0-9._-]")


def safe_file_stem(text: str) -> str:
    """A file-name stem for ``text`` (a robot id from a database, a label): letters, digits, ``. _ -``
    only; any other character becomes ``_`` and a short hash of the original keeps two ids apart
    (``line1/cell3`` -> ``line1_cell3-1a2b3c4d``). Never empty, never starting with a dot."""
    text = str(text)
    stem = _UNSAFE.sub("_", text).lstrip(".") or "_"
    if stem != text:
        stem = f"{stem[:80]}-{hashlib.sha256(text.encode('utf-8', 'surrogatepass')).hexdigest()[:8]}"
    return stem


def path_under(folder, name: str) -> Path:
    """``folder / name``, checked to stay inside ``folder`` after resolving (``PathEscapeError``)."""
    base = Path(folder).resolve()
    p = (base / name).resolve()
    if p != base and base not in p.parents:
        raise PathEscapeError(f"{name!r}: would be written outside {folder}; refused")
    return p
