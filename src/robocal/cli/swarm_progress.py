"""A progress bar over the swarm's generations (``robocal calibrate --method ipso``), on stderr
when it is a terminal; nothing otherwise (pipes and logs stay clean)."""

from __future__ import annotations

import sys

import click

__all__ = ["swarm_progress_bar"]


def swarm_progress_bar(method: str, generations: int, stream=None):
    """``progress(generation, best_f)`` drawing a click progress bar, or None (LM, or not a terminal)."""
    stream = sys.stderr if stream is None else stream
    if method not in ("ipso", "ipso+lm") or not getattr(stream, "isatty", lambda: False)():
        return None
    state = {"bar": None, "done": 0}

    def progress(generation, best_f):
        if state["bar"] is None:
            state["bar"] = click.progressbar(length=generations, label="IPSO generations", file=stream,
                                             show_pos=True, show_eta=False)
            state["bar"].__enter__()
        bar = state["bar"]
        if generation - state["done"] >= 20 or generation == generations:  # redraw ~100 times per run
            bar.label = f"IPSO generations (best f {best_f:.4g} mm^2)"
            bar.update(generation - state["done"])
            state["done"] = generation
        if generation == generations:
            bar.__exit__(None, None, None)

    return progress
