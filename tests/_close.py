"""Comparison of nested results (JSON documents, parsed TOML) at a stated tolerance.

Floating-point results from different code paths, processes or machines (vectorized against scalar
loops, fused multiply-add or not, another BLAS) agree to rounding, not bit for bit; tests compare them
with :func:`assert_tree_close`, which still fails on any change of structure, text or count.
"""

from __future__ import annotations

import math


def assert_tree_close(a, b, *, rtol: float = 1e-9, atol: float = 1e-12, path: str = "") -> None:
    """Assert that two nested dict/list/str/number trees are equal, floats within ``atol + rtol*|b|``.

    Parameters
    ----------
    a, b : nested dicts, lists, tuples, strings, bools, ints, floats or None
        The two results; ``b`` is the reference.
    rtol, atol : float
        Relative and absolute tolerance of every float (the unit is the float's own).
    path : str
        Where in the tree (for the failure message).
    """
    where = path or "<root>"
    if isinstance(b, dict):
        assert isinstance(a, dict), f"{where}: {type(a).__name__} instead of a table"
        assert sorted(a) == sorted(b), f"{where}: keys {sorted(a)} != {sorted(b)}"
        for k in b:
            assert_tree_close(a[k], b[k], rtol=rtol, atol=atol, path=f"{path}.{k}")
    elif isinstance(b, (list, tuple)):
        assert isinstance(a, (list, tuple)) and len(a) == len(b), f"{where}: length {len(a)} != {len(b)}"
        for i, (x, y) in enumerate(zip(a, b)):
            assert_tree_close(x, y, rtol=rtol, atol=atol, path=f"{path}[{i}]")
    elif isinstance(b, float) or (isinstance(a, float) and isinstance(b, int) and not isinstance(b, bool)):
        assert isinstance(a, (int, float)) and not isinstance(a, bool), f"{where}: {a!r} is not a number"
        if math.isnan(b):
            assert math.isnan(a), f"{where}: {a!r} != nan"
        else:
            assert abs(a - b) <= atol + rtol * abs(b), f"{where}: {a!r} != {b!r} (rtol {rtol:g}, atol {atol:g})"
    else:
        assert a == b, f"{where}: {a!r} != {b!r}"
