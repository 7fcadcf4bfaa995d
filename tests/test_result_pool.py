"""The reused memory of large FK results (robocal.kinematics._result_pool): reused only once dropped."""

from __future__ import annotations

import gc
import threading

import numpy as np
import pytest

from robocal.kinematics import _result_pool
from robocal.kinematics._threads import PARALLEL_MIN
from robocal.robots import load_robot

N = PARALLEL_MIN + 1000  # a "big" batch (its check runs in the threads), kept small for speed


@pytest.fixture
def pool(monkeypatch):
    """The pool from a few hundred kB on (its real threshold is 32 MiB), emptied before and after."""
    monkeypatch.setattr(_result_pool, "MIN_BYTES", 16 * PARALLEL_MIN)
    _result_pool.clear()
    yield _result_pool
    _result_pool.clear()


def _address(a: np.ndarray) -> int:
    return a.__array_interface__["data"][0]


def _q(seed: int, n: int = N) -> np.ndarray:
    return np.random.default_rng(seed).uniform(-3, 3, (n, 6))


def test_fresh_result_from_reused_memory_equals_out(pool):
    m = load_robot("ur10")
    q = _q(1)
    expected = m.fk(q, out=np.empty((N, 4, 4)))
    first = m.fk(q)
    address = _address(first)
    np.testing.assert_allclose(first, expected, rtol=0, atol=1e-12)  # mm
    first[:] = np.nan  # what the next result would see if its memory were not fully written
    del first
    second = m.fk(q)
    assert _address(second) == address  # the dropped result's memory served again
    np.testing.assert_allclose(second, expected, rtol=0, atol=1e-12)
    assert second.flags.c_contiguous and second.flags.writeable and second.dtype == np.float64


@pytest.mark.parametrize("keep", ["slice", "memoryview", "reshape", "asarray"])
def test_memory_a_live_view_uses_is_never_reused(pool, keep):
    m = load_robot("ur10")
    q1, q2 = _q(2), _q(3)
    first = m.fk(q1)
    expected = first[100:110].copy()
    address = _address(first)
    held = {"slice": lambda a: a[100:110], "memoryview": memoryview,
            "reshape": lambda a: a.reshape(-1, 16), "asarray": np.asarray}[keep](first)
    del first
    gc.collect()
    second = m.fk(q2)
    assert _address(second) != address
    view = np.asarray(held)
    if keep != "slice":
        view = view.reshape(-1, 4, 4)[100:110]
    np.testing.assert_array_equal(view, expected)  # untouched by the second call, bit for bit: no FK ran on it
    assert not np.shares_memory(view, second)
    del held, view
    third = m.fk(q2)  # now the first block is free again
    assert _address(third) == address


def test_other_sizes_and_clear_get_new_memory(pool):
    m = load_robot("ur10")
    first = m.fk(_q(4))
    del first
    assert pool._kept is not None
    other = m.fk(_q(5, N + 8))  # another size: the kept block is let go before new memory is asked for
    assert pool._kept is None  # (the allocator may then hand out the same addresses again)
    np.testing.assert_allclose(other, m.fk(_q(5, N + 8), out=np.empty((N + 8, 4, 4))), rtol=0, atol=1e-12)
    del other
    assert pool._kept is not None
    pool.clear()
    assert pool._kept is None
    again = m.fk(_q(4))
    np.testing.assert_allclose(again, m.fk(_q(4), out=np.empty((N, 4, 4))), rtol=0, atol=1e-12)


def test_concurrent_calls_never_share_memory(pool):
    m = load_robot("ur10")
    qs = [_q(10 + k) for k in range(4)]
    expected = [m.fk(q, out=np.empty((N, 4, 4))) for q in qs]
    results = [[] for _ in qs]
    barrier = threading.Barrier(len(qs))

    def work(k):
        barrier.wait()
        for _ in range(5):
            results[k].append(m.fk(qs[k]))  # every result is kept: all must live in distinct memory

    threads = [threading.Thread(target=work, args=(k,)) for k in range(len(qs))]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    everything = [r for rs in results for r in rs]
    assert len({_address(r) for r in everything}) == len(everything)
    for k, rs in enumerate(results):
        for r in rs:
            np.testing.assert_allclose(r, expected[k], rtol=0, atol=1e-12)


def test_small_results_are_plain_numpy_arrays():
    assert _result_pool.empty((10, 4, 4)).flags.owndata
