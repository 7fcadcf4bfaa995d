"""The command line asks for one BLAS thread unless the user chose a number (robocal/_blas_threads.py)."""

import os
import subprocess
import sys

import numpy  # noqa: F401  (loaded: the variables can no longer change this process's BLAS)

from robocal._blas_threads import VARIABLES, single_thread_blas


def test_one_thread_unless_the_user_chose(monkeypatch):
    for var in VARIABLES:
        monkeypatch.delenv(var, raising=False)
    monkeypatch.setenv("OPENBLAS_NUM_THREADS", "3")
    assert single_thread_blas() is False  # numpy is imported in the test process: too late to matter
    assert os.environ["OPENBLAS_NUM_THREADS"] == "3"  # the user's choice is kept
    assert all(os.environ[v] == "1" for v in VARIABLES if v != "OPENBLAS_NUM_THREADS")


def test_the_cli_sets_it_before_numpy_loads():
    env = {k: v for k, v in os.environ.items() if k not in VARIABLES}
    code = ("import sys, os; import robocal.cli; "
            "print(os.environ['OPENBLAS_NUM_THREADS'], 'numpy' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True).stdout
    assert out.split() == ["1", "False"]  # set while numpy's BLAS is not loaded yet: it takes effect
