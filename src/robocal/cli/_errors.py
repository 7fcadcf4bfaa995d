"""The last line of defence of the command line: any exception a command lets through becomes one
``Error: ...`` line (never a traceback), with the path named for file-system problems.

Commands still turn the errors they expect into ``click.ClickException`` themselves, with their
own wording; this guard catches what slips through (a binary file where text was expected, a
read-only output folder, a full disk, a corrupted history database).
"""

from __future__ import annotations

import errno
import os
import sqlite3
import sys
import warnings

import click

from ..errors import RobocalError, RobocalWarning
from ..workflows.outputs import describe_os_error

__all__ = ["GuardedGroup", "one_line_error", "EXTRAS", "missing_extra"]

#: The optional dependency a module comes from: ``pip install 'robocal[<extra>]'`` (pyproject.toml).
EXTRAS = {"cv2": "camera", "yaml": "yaml", "sqlalchemy": "db", "psycopg": "postgresql", "psycopg2": "postgresql",
          "dask": "fleet", "distributed": "fleet", "deap": "ik-net", "pinocchio": "bench"}


def missing_extra(exc: ImportError) -> str | None:
    """The line for a missing optional dependency, naming the extra to install (None: not one of them)."""
    name = (getattr(exc, "name", None) or "").split(".")[0]
    extra = EXTRAS.get(name)
    if extra is None:
        return None
    return (f"this needs the optional dependency {name!r}, which is not installed: "
            f"pip install 'robocal[{extra}]'")


def one_line_error(exc: BaseException) -> click.ClickException:
    """The ``click.ClickException`` (one line) for an exception a command did not handle."""
    if isinstance(exc, ImportError) and missing_extra(exc):
        text = missing_extra(exc)
    elif isinstance(exc, (FileNotFoundError, FileExistsError, IsADirectoryError, NotADirectoryError)):
        text = f"{exc.filename}: {exc.strerror}" if exc.filename and exc.strerror else str(exc)
    elif isinstance(exc, OSError):
        text = describe_os_error(exc) if exc.errno else str(exc)
    elif isinstance(exc, sqlite3.DatabaseError):
        text = f"history database: {exc} (the file is damaged or not a robocal history database)"
    elif isinstance(exc, UnicodeError):
        text = f"not a UTF-8 text file: {exc}"
    elif isinstance(exc, RobocalError):
        text = str(exc)
    elif isinstance(exc, (ValueError, KeyError)):
        text = exc.args[0] if isinstance(exc, KeyError) and exc.args else str(exc)
    elif isinstance(exc, MemoryError):
        text = "out of memory: the input is too large for this machine (see docs/reliability.md, row limit)"
    else:
        text = f"unexpected {type(exc).__name__}: {exc} (a bug in robocal; please report it with the command)"
    return click.ClickException(" ".join(str(text).split()) or type(exc).__name__)


def _show_robocal_warning(original):
    """A ``warnings.showwarning`` that prints robocal's own warnings as one ``Warning: ...`` line on
    stderr (no source path and line: they are about the user's files, not robocal's code) and
    leaves every other warning to ``original``."""

    def show(message, category, filename, lineno, file=None, line=None):
        if category.__name__ == "NotConvergedWarning" and category.__module__ == "robocal.calib.solve":
            return  # every fitting command reports its fits' convergence itself: one Warning: line (finish_convergence)
        if issubclass(category, RobocalWarning):
            click.echo(f"Warning: {' '.join(str(message).split())}", err=True)
        else:
            original(message, category, filename, lineno, file, line)

    return show


class GuardedGroup(click.Group):
    """A click group whose commands (and sub-groups) never end in a traceback, and whose
    robocal warnings print as one ``Warning:`` line."""

    def invoke(self, ctx):
        try:
            with warnings.catch_warnings():
                warnings.showwarning = _show_robocal_warning(warnings.showwarning)
                return super().invoke(ctx)
        except (click.ClickException, click.exceptions.Exit, click.Abort, SystemExit, KeyboardInterrupt):
            raise
        except Exception as exc:  # noqa: BLE001 - the guard's purpose
            if _broken_pipe(exc):
                _quiet_exit()
            raise one_line_error(exc) from None


def _broken_pipe(exc: BaseException) -> bool:
    """The reader of our output went away (``robocal ... | head``)."""
    while exc is not None:
        if isinstance(exc, BrokenPipeError) or (isinstance(exc, OSError) and exc.errno == errno.EPIPE):
            return True
        exc = exc.__cause__ or exc.__context__
    return False


def _quiet_exit() -> None:
    """Exit 0 without a word when stdout is a closed pipe: nothing more can be shown, and Python's
    own flush at exit must not complain either (stdout goes to /dev/null)."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
    except (OSError, ValueError, AttributeError):
        pass
    raise SystemExit(0)
