"""``--json`` for commands whose text output is a table: the same command, its text moved to
stderr, and one JSON document on stdout (docs/cli.md).

A command gets the flag with :func:`json_option` and hands its result over with
:func:`set_json_result`; the document is printed even when the command then exits with a
non-zero code of the exit-code table (3 failed sanity gates, 4 not converged, 5 not reached).
"""

from __future__ import annotations

import contextlib
import functools
import sys

import click

__all__ = ["json_option", "set_json_result"]

_KEY = "robocal.json_result"


def set_json_result(document) -> None:
    """The result document of the running command (numbers, strings, lists, dicts, arrays, paths;
    other objects are left out)."""
    click.get_current_context().meta[_KEY] = document


def _plain(obj):
    """``obj`` as JSON values: arrays to lists, paths to str, NaN to None; other objects dropped."""
    import math
    from pathlib import PurePath

    import numpy as np

    if isinstance(obj, dict):
        out = {str(k): _plain(v) for k, v in obj.items()}
        return {k: v for k, v in out.items() if v is not _DROP}
    if isinstance(obj, (list, tuple)):
        return [v for v in (_plain(x) for x in obj) if v is not _DROP]
    if isinstance(obj, np.ndarray):
        return _plain(obj.tolist())
    if isinstance(obj, (bool, np.bool_)):
        return bool(obj)
    if isinstance(obj, (int, np.integer)):
        return int(obj)
    if isinstance(obj, (float, np.floating)):
        return float(obj) if math.isfinite(obj) else None
    if obj is None or isinstance(obj, str):
        return obj
    if isinstance(obj, PurePath):
        return str(obj)
    return _DROP


_DROP = object()


def json_option(command_function):
    """Decorate a click command function (below ``@click.command``) with ``--json``."""

    @click.option("--json", "as_json_document", is_flag=True,
                  help="Print the result as one JSON document on stdout (the text goes to stderr).")
    @functools.wraps(command_function)
    def run(*args, as_json_document=False, **kwargs):
        if not as_json_document:
            return command_function(*args, **kwargs)
        ctx = click.get_current_context()
        try:
            with contextlib.redirect_stdout(sys.stderr):
                return command_function(*args, **kwargs)
        finally:
            document = ctx.meta.get(_KEY)
            if document is not None:
                import json

                click.echo(json.dumps(_plain(document), indent=2, allow_nan=False))

    return run
