"""Which implementation runs a kinematics kernel: plain numpy for a small problem, compiled (numba)
once the work pays for the compile.

A compiled kernel costs ~1-2 s of CPU the first time after installing (numba compiles it) and
~0.1-0.4 s in every later process (importing numba, loading it from the cache); per call it is then
10-100x faster than numpy. A small command (a 100-pose calibration: a few dozen evaluations of
~1 ms in numpy) is done before a compile would have finished, so each kernel starts in numpy and
switches to its compiled form, for the rest of the process, as soon as

* one call is large (its estimated numpy time exceeds :data:`CALL_MAX_S`), or
* the estimated numpy time spent in it so far exceeds :data:`BUDGET_S`.

The estimate counts calls and poses (deterministic: a run takes the same path on any machine and
load). Results agree to rounding (~1e-13 mm; ``tests/test_kernel_backends.py``).
``ROBOCAL_KERNELS=compiled`` (or :func:`set_kernels`) always uses the compiled kernels (benchmarks of
kernel speed), ``ROBOCAL_KERNELS=numpy`` never does.
"""

from __future__ import annotations

import os

from . import _numpy_kernels
from ._kernel_loader import kernels as _compiled

#: numpy seconds per call and per unit of work (poses x points) of each kernel, measured on the
#: 2-core VM (IRB 140 / UR10, 80 and 2048 poses, 2026-11-27): an estimate that decides the switch.
NUMPY_COST_S = {
    "target_points": (1.0e-3, 8.0e-6),
    "op_twists": (1.0e-3, 6.0e-6),
    "fk_fused_into": (1.0e-4, 1.1e-6),
    "fk_fused_single_checked": (1.7e-4, 0.0),
}
#: A call estimated to take longer than this in numpy runs compiled (and the kernel stays compiled).
CALL_MAX_S = 0.01
#: Estimated numpy seconds a kernel may take in one process before it is compiled (or loaded).
BUDGET_S = 0.15

_MODES = ("auto", "compiled", "numpy")
_mode = os.environ.get("ROBOCAL_KERNELS", "auto").strip().lower() or "auto"
if _mode not in _MODES:
    _mode = "auto"
_spent = dict.fromkeys(NUMPY_COST_S, 0.0)
_switched: set = set()


def set_kernels(mode: str) -> None:
    """``"auto"`` (numpy until the work pays for a compile), ``"compiled"`` or ``"numpy"``."""
    global _mode
    if mode not in _MODES:
        raise ValueError(f"kernels must be one of {_MODES}, got {mode!r}")
    _mode = mode


def use_compiled(name: str, work: int = 1) -> bool:
    """True when a call of kernel ``name`` over ``work`` poses x points runs compiled (this counts the
    call). A compiled caller of the kernel (a loop around it) asks this first, so that a small
    problem compiles nothing."""
    if _mode == "compiled" or name in _switched:
        return True
    if _mode == "auto":
        per_call, per_unit = NUMPY_COST_S[name]
        cost = per_call + per_unit * work
        if cost > CALL_MAX_S or _spent[name] + cost > BUDGET_S:
            _switched.add(name)
            return True
        _spent[name] += cost
    return False


def kernel(name: str, work: int = 1):
    """The implementation of kernel ``name`` to run for a call of ``work`` poses x points."""
    return getattr(_compiled if use_compiled(name, work) else _numpy_kernels, name)


def compiled_kernels() -> frozenset:
    """Names of the kernels this process has switched to their compiled form."""
    return frozenset(_switched)
