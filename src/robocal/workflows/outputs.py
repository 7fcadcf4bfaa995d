"""All-or-nothing output folders: a command's files are written into a temporary folder next to
the destination and moved into place together, so a failure (disk full, permission, a crash)
leaves nothing half-written and no mixture of old and new files.

    with staged_outputs(out_dir, ["result.json", "report.html"], overwrite=False) as stage:
        write(stage / "result.json") ...
    # here both files are in out_dir, or (on an exception) none of them changed

Existing files are checked before any work (``FileExistsError`` naming the file, "pass
--overwrite"); ``OSError`` problems are re-raised as :class:`OutputError` naming the path.
"""

from __future__ import annotations
from ..errors import OutputExistsError, RobocalError

import contextlib
import errno
import os
import shutil
import tempfile
from pathlib import Path

__all__ = ["OutputError", "check_output_folder", "check_outputs_free", "ensure_writable_dir", "staged_outputs",
           "describe_os_error"]


class OutputError(RobocalError, OSError):
    """An output could not be written; the message names the path and the cause."""


def describe_os_error(exc: OSError, path=None) -> str:
    """One line naming the path and the cause of ``exc`` (disk full, permission, ...)."""
    where = path or exc.filename or "output"
    cause = {errno.ENOSPC: "no space left on device (disk full)", errno.EACCES: "permission denied",
             errno.EROFS: "read-only file system", errno.EPERM: "operation not permitted",
             errno.EDQUOT: "disk quota exceeded"}.get(exc.errno, exc.strerror or str(exc))
    return f"{where}: cannot write: {cause}"


def check_outputs_free(out_dir, names, overwrite: bool) -> None:
    """``OutputExistsError`` (a ``FileExistsError``) naming the first of ``out_dir / names`` that exists (unless ``overwrite``);
    ``NotADirectoryError`` when ``out_dir`` is a file."""
    out = Path(out_dir)
    if out.exists() and not out.is_dir():
        raise NotADirectoryError(f"{out}: exists and is not a folder")
    if overwrite:
        return
    for name in names:
        p = out / name
        if p.exists():
            raise OutputExistsError(f"{p}: output file exists; pass --overwrite to replace it")


def check_output_folder(out_dir, names, inputs, overwrite: bool) -> None:
    """The rules of an output folder (docs/cli.md), before any work: the folder and each of
    ``out_dir / names`` must not be one of the command's ``inputs`` (a path, a list or ``{what:
    path}``; refused even with ``overwrite``, :class:`~robocal.io.output_paths.OutputIsInputError`),
    then :func:`check_outputs_free`."""
    from ..io.output_paths import check_not_inputs

    out = Path(out_dir)
    if isinstance(inputs, dict):  # only paths (a robot may be given as a model object)
        inputs = {k: v for k, v in inputs.items() if isinstance(v, (str, os.PathLike))}
    check_not_inputs([out] + [out / n for n in names], inputs)
    check_outputs_free(out, names, overwrite)


def ensure_writable_dir(out_dir) -> Path:
    """Create ``out_dir`` if needed and prove it writable (a temporary file), before any long work;
    :class:`OutputError` naming the folder otherwise (read-only mount, permission, disk full)."""
    out = Path(out_dir)
    try:
        out.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryFile(dir=out):
            pass
    except OSError as exc:
        if isinstance(exc, (FileExistsError, NotADirectoryError)):
            raise NotADirectoryError(f"{out}: exists and is not a folder") from None
        raise OutputError(describe_os_error(exc, out)) from None
    return out


@contextlib.contextmanager
def staged_outputs(out_dir, names, overwrite: bool = False):
    """Yield a temporary folder (same file system as ``out_dir``) to write ``names`` into; on a
    normal exit move every file written there into ``out_dir`` (``os.replace``), on an exception
    remove the temporary folder. Names not written are skipped (and, with ``overwrite``, a stale
    file of that name in ``out_dir`` is removed so old and new results never mix)."""
    out = Path(out_dir)
    check_outputs_free(out, names, overwrite)
    try:
        out.mkdir(parents=True, exist_ok=True)
        stage = Path(tempfile.mkdtemp(prefix=".robocal-staging-", dir=out))
    except OSError as exc:
        raise OutputError(describe_os_error(exc, out)) from None
    try:
        yield stage
        _commit(stage, out, names, overwrite)
    except OSError as exc:
        if isinstance(exc, (OutputError, FileExistsError, FileNotFoundError, NotADirectoryError)):
            raise
        raise OutputError(describe_os_error(exc, out)) from None
    finally:
        shutil.rmtree(stage, ignore_errors=True)


def _commit(stage: Path, out: Path, names, overwrite: bool) -> None:
    written = [n for n in names if (stage / n).exists()]
    if not overwrite:
        check_outputs_free(out, written, overwrite)  # someone else may have written meanwhile
    for name in written:
        if overwrite and (stage / name).is_dir() and (out / name).is_dir():
            shutil.rmtree(out / name)  # a folder output (demo's calibration/) is replaced whole
        os.replace(stage / name, out / name)
    if overwrite:
        for name in names:
            if name not in written and (out / name).is_file():
                (out / name).unlink()
            elif name not in written and (out / name).is_dir():
                shutil.rmtree(out / name)
