"""The compiled kernels, imported on first use, with a one-time notice when numba compiles.

``import robocal.kinematics`` (and loading or writing a robot) must not import numba: it costs
about a second before anything is computed. :data:`kernels` stands in for the module
:mod:`robocal.kinematics._kernels`; its first attribute access imports it (numba then loads the
compiled machine code from its cache, or compiles it: the first time after installing, or after
the kernels' source changed). A compile takes 1-2 s of CPU per kernel, so it is announced once per
process on the terminal's stderr instead of a silent pause. Small problems do not get here: the
kernels run in numpy until the work pays for a compile (:mod:`robocal.kinematics._backend`).
"""

from __future__ import annotations

import sys

NOTICE = "robocal: compiling kernels, once per install (a few seconds; later runs load them from cache)..."


class _Kernels:
    """Lazy stand-in for :mod:`robocal.kinematics._kernels` (attributes copied in on first use)."""

    def __getattr__(self, name):
        from . import _kernels

        _watch_compiles()
        self.__dict__.update({k: v for k, v in vars(_kernels).items() if not k.startswith("__")})
        return getattr(_kernels, name)


kernels = _Kernels()
_announced = False


def _announce(module: str) -> None:
    global _announced
    if _announced or not module.startswith("robocal."):
        return
    _announced = True
    # The process's own stderr, not a redirected sys.stderr (a command's captured output in tests).
    stream = sys.__stderr__ or sys.stderr
    if stream is not None:
        print(NOTICE, file=stream, flush=True)


def _watch_compiles() -> None:
    """Listen to numba's compile events (fired only on a cache miss, not when loading from cache)."""
    from numba.core import event

    class _CompileNotice(event.Listener):
        def on_start(self, ev):
            dispatcher = (ev.data or {}).get("dispatcher")
            _announce(getattr(getattr(dispatcher, "py_func", None), "__module__", "") or "")

        def on_end(self, ev):
            pass

    event.register("numba:compile", _CompileNotice())
