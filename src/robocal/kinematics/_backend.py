"""Which implementation runs a kinematics kernel: plain numpy unless compiled (numba) code saves
enough time to pay for loading it.

The first compiled kernel a process runs costs ~0.4 s of CPU and ~105 MiB resident (importing numba
and llvmlite, LLVM's initialisation and numba's typing context; measured 2026-11-27: +56 MiB for the
imports, +65 MiB at the first cached kernel), each further one ~5 ms and ~1 MiB (its machine code from
numba's on-disk cache; the first run after installing compiles instead, 1-2 s of CPU per kernel). The
numpy kernels (:mod:`robocal.kinematics._numpy_kernels`) cost nothing to load; per call they take
~0.1-0.3 ms of Python overhead, so on small calls they are 5-50x slower than compiled code, while on
big batches (thousands of poses, vectorised) they come within 1.1-2x of it (target points with their
Jacobian ~1.7x, without ~1.1x; the forward kinematics stays ~7x).

So each call's numpy and compiled times are estimated from its kernel, call count and work (poses x
points: :data:`COST_S`; deterministic, a run takes the same path on any machine and load), and the
estimated time compiled code would have saved is added up, ski-rental style:

* before any compiled kernel ran in this process, a call counts only when compiled code would run
  it at least :data:`MIN_SPEEDUP` times faster; the kernel switches to its compiled form (for the
  rest of the process) when the savings counted over all kernels reach :data:`LOAD_S`, the first
  load's time. A process of big batches (a 100 000-pose calibration: blocks of 4 096 poses, where
  numpy is within 2x) therefore never trades ~105 MiB for less than half its kernels' time, and a
  process of many small calls (the demo's thermal simulation) loads compiled code once that has
  paid for itself: at most ~0.4 s later than ideal;
* once one has, every call counts and a kernel switches when its savings reach the price of one
  more kernel: :data:`KERNEL_LOAD_S` when numba's on-disk cache holds it, else
  :data:`KERNEL_COMPILE_S` (the first run after installing compiles only the kernels that pay).

Results agree to rounding (~1e-12 mm; ``tests/test_kernel_backends.py``). ``ROBOCAL_KERNELS=compiled``
(or :func:`set_kernels`) always uses the compiled kernels (benchmarks of kernel speed),
``ROBOCAL_KERNELS=numpy`` never does.
"""

from __future__ import annotations

import os

from . import _numpy_kernels
from ._kernel_loader import kernels as _compiled

#: Estimated seconds of one call of each kernel, ``((numpy per call, numpy per unit of work),
#: (compiled per call, compiled per unit))``, a unit being a pose x point: medians on the 2-core VM
#: (UR10 and IRB 140, 80 and 4 096 poses, the numpy kernels reusing their working arrays as in a
#: calibration's loop; target points with the Jacobian of every parameter; 2026-11-27).
COST_S = {
    "target_points": ((2.5e-4, 8.0e-7), (5.0e-6, 4.7e-7)),
    "op_twists": ((2.5e-4, 1.8e-6), (5.0e-6, 4.2e-7)),
    "fk_fused_into": ((8.0e-5, 2.6e-7), (4.0e-6, 3.5e-8)),
    "fk_fused_single_checked": ((8.0e-5, 0.0), (1.2e-6, 0.0)),
}
#: Seconds the first compiled kernel of a process costs to load (with ~105 MiB resident).
LOAD_S = 0.4
#: Seconds each further compiled kernel costs to load (from numba's cache, ~1 MiB).
KERNEL_LOAD_S = 0.005
#: Seconds a further compiled kernel costs when numba's cache does not hold it (a compile, 1-2 s of CPU).
KERNEL_COMPILE_S = 1.5
#: Before the first load, a call counts toward it only if compiled code would run it this many times
#: faster: big batches, where numpy is within 2x, do not buy ~105 MiB.
MIN_SPEEDUP = 2.0

_MODES = ("auto", "compiled", "numpy")
_mode = os.environ.get("ROBOCAL_KERNELS", "auto").strip().lower() or "auto"
if _mode not in _MODES:
    _mode = "auto"
_saved = dict.fromkeys(COST_S, 0.0)
_switched: set = set()
_price: dict = {}


def set_kernels(mode: str) -> None:
    """``"auto"`` (numpy until compiled code pays for its load), ``"compiled"`` or ``"numpy"``."""
    global _mode
    if mode not in _MODES:
        raise ValueError(f"kernels must be one of {_MODES}, got {mode!r}")
    _mode = mode


def estimate(name: str, work: int = 1) -> tuple[float, float]:
    """Estimated seconds (numpy, compiled) of one call of kernel ``name`` over ``work`` poses x points."""
    (nc, nu), (cc, cu) = COST_S[name]
    return nc + nu * work, cc + cu * work


def use_compiled(name: str, work: int = 1) -> bool:
    """True when a call of kernel ``name`` over ``work`` poses x points runs compiled (this counts the
    call; see the module docstring). A compiled caller of the kernel (a loop around it) asks this
    first, so that a problem the numpy kernels suit loads nothing."""
    if _mode != "auto":  # a mode set by the user or a benchmark wins over what auto decided so far
        return _mode == "compiled"
    if name in _switched:
        return True
    (nc, nu), (cc, cu) = COST_S[name]
    t_numpy, t_compiled = nc + nu * work, cc + cu * work
    saving = t_numpy - t_compiled
    if _switched:  # compiled code is loaded: one more kernel costs only its own load (or compile)
        if _saved[name] + saving >= _kernel_price(name):
            _switched.add(name)
            return True
        _saved[name] += saving
    elif t_numpy >= MIN_SPEEDUP * t_compiled:
        if sum(_saved.values()) + saving >= LOAD_S:
            _switched.add(name)
            return True
        _saved[name] += saving
    return False


def _kernel_price(name: str) -> float:
    """Seconds compiled kernel ``name`` costs once compiled code is loaded: :data:`KERNEL_LOAD_S` when
    numba's on-disk cache has an index for it, else :data:`KERNEL_COMPILE_S` (looked up once)."""
    price = _price.get(name)
    if price is None:
        try:
            cached = os.path.exists(getattr(_compiled, name)._cache._cache_file._index_path)
        except Exception:  # pragma: no cover - a numba without these internals: assume a compile
            cached = False
        price = _price[name] = KERNEL_LOAD_S if cached else KERNEL_COMPILE_S
    return price


def kernel(name: str, work: int = 1):
    """The implementation of kernel ``name`` to run for a call of ``work`` poses x points."""
    return getattr(_compiled if use_compiled(name, work) else _numpy_kernels, name)


def compiled_kernels() -> frozenset:
    """Names of the kernels this process has switched to their compiled form."""
    return frozenset(_switched)
