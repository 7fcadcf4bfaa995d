"""Atomic file writes: a temporary file in the same directory, then a rename (or a no-clobber link).

Nothing the user had is overwritten unless asked, and a crash never leaves a half-written file.
"""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

__all__ = ["atomic_write_bytes", "atomic_write_text"]


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def atomic_write_bytes(path, data: bytes, overwrite: bool = False, *, durable: bool = True) -> Path:
    """Write ``data`` to ``path`` via a temporary file in the same directory and a rename.

    Without ``overwrite`` an existing ``path`` raises ``FileExistsError`` and is left untouched
    (the final step is a hard link, which fails atomically if the name exists). With
    ``overwrite=True`` the old file is replaced atomically (``os.replace``): a reader sees either
    the old or the new content, never a mixture. ``durable=False`` skips the ``fsync`` before the
    rename (milliseconds of waiting on a VM's disk): for markers whose loss after a power cut only
    means redoing work, never for results.
    """
    path = Path(path)
    directory = path.parent if str(path.parent) else Path(".")
    if not directory.is_dir():
        raise FileNotFoundError(f"{path}: directory {directory} does not exist")
    if not overwrite and path.exists():
        raise FileExistsError(f"{path}: file exists; pass overwrite=True to replace it")
    try:
        return _write_via_temporary(path, directory, data, overwrite, durable)
    except (FileExistsError, FileNotFoundError):
        raise
    except OSError as exc:  # disk full, permission, read-only: name the file being written
        raise OSError(exc.errno, exc.strerror or str(exc), str(path)) from None


def _write_via_temporary(path: Path, directory: Path, data: bytes, overwrite: bool, durable: bool = True) -> Path:
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=directory)
    try:
        os.fchmod(fd, 0o666 & ~_umask())  # mkstemp creates 0600; give the file the usual mode
        with os.fdopen(fd, "wb") as fh:
            fh.write(data)
            fh.flush()
            if durable:
                os.fsync(fh.fileno())
        if overwrite:
            os.replace(tmp, path)
        else:
            try:
                os.link(tmp, path)  # atomic no-clobber
            except FileExistsError:
                raise FileExistsError(f"{path}: file exists; pass overwrite=True to replace it") from None
            except OSError:  # file system without hard links
                if path.exists():
                    raise FileExistsError(f"{path}: file exists; pass overwrite=True to replace it") from None
                os.replace(tmp, path)
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)
    return path


def atomic_write_text(path, text: str, overwrite: bool = False, *, durable: bool = True) -> Path:
    """Write ``text`` (UTF-8) atomically; see :func:`atomic_write_bytes`."""
    return atomic_write_bytes(path, text.encode("utf-8"), overwrite=overwrite, durable=durable)
