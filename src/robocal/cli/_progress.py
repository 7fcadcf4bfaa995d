"""Progress that reads well on a terminal and in a log file (docs/cli.md).

On a terminal: click's bar with position and ETA. Without one (a log file, a CI job, ``nohup``):
one line every ``every_s`` seconds, ``label: 37/200 (18 %), 12 s elapsed, ETA 53 s``, printed by a
background thread (so a long first item is not silence either), and a last one when there were
any (a command done within ``every_s`` prints nothing).
"""

from __future__ import annotations

import sys
import threading
import time

import click

__all__ = ["Progress"]


class Progress:
    """Counts of ``label`` out of ``length`` (settable; None: unknown) on stderr.

    Use as a context manager; :meth:`update` adds done items (the interface of
    ``click.progressbar`` that the commands use: ``length`` and ``update(n)``).
    """

    def __init__(self, label: str, length: int | None = None, *, every_s: float = 5.0, file=None, tty=None):
        self.label, self.length, self.done, self.every_s = label, length, 0, every_s
        self.file = file if file is not None else sys.stderr
        self.tty = bool(getattr(self.file, "isatty", lambda: False)()) if tty is None else tty
        self._bar = None
        self._stop = threading.Event()
        self._lock = threading.Lock()
        self._thread = None
        self._t0 = time.monotonic()
        self._printed = 0

    def __enter__(self):
        self._t0 = time.monotonic()
        if self.tty:
            self._bar = click.progressbar(length=self.length or 1, label=self.label, file=self.file, show_pos=True,
                                          show_eta=True)
            self._bar.__enter__()
        else:
            self._thread = threading.Thread(target=self._tick, daemon=True)
            self._thread.start()
        return self

    def __exit__(self, *exc):
        if self._bar is not None:
            return self._bar.__exit__(*exc)
        self._stop.set()
        if self._thread is not None:
            self._thread.join()
        if self._printed:
            self._print()
        return False

    def update(self, n: int = 1) -> None:
        with self._lock:
            self.done += n
        if self._bar is not None:
            self._bar.length = self.length or max(self.done, 1)
            self._bar.update(n)

    def line(self) -> str:
        """``label: done/length (pct %), elapsed, ETA`` (counts only when the length is known)."""
        elapsed = time.monotonic() - self._t0
        with self._lock:
            done, length = self.done, self.length
        if not length:
            return f"{self.label}: {done} done, {elapsed:.0f} s elapsed"
        eta = f"ETA {elapsed * (length - done) / done:.0f} s" if 0 < done < length else (
            "done" if done >= length else "ETA unknown")
        return f"{self.label}: {done}/{length} ({100.0 * done / length:.0f} %), {elapsed:.0f} s elapsed, {eta}"

    def _print(self) -> None:
        click.echo(self.line(), file=self.file)

    def _tick(self) -> None:
        while not self._stop.wait(self.every_s):
            self._print()
            self._printed += 1
