"""The last line of defence of the command line: any exception a command lets through becomes one
``Error: ...`` line (never a traceback), with the path named for file-system problems.

Commands still turn the errors they expect into ``click.ClickException`` themselves, with their
own wording; this guard catches what slips through (a binary file where text was expected, a
read-only output folder, a full disk, a corrupted history database).
"""

from __future__ import annotations

import sqlite3
import warnings

import click

from ..errors import RobocalError, RobocalWarning
from ..workflows.outputs import describe_os_error

__all__ = ["GuardedGroup", "one_line_error"]


def one_line_error(exc: BaseException) -> click.ClickException:
    """The ``click.ClickException`` (one line) for an exception a command did not handle."""
    if isinstance(exc, (FileNotFoundError, FileExistsError, IsADirectoryError, NotADirectoryError)):
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
            raise one_line_error(exc) from None
