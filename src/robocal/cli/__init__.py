"""The ``robocal`` command line: one small module per command group, thin over the library.

Every user error ends in one line ``Error: ...`` and a non-zero exit code.
"""

from .._blas_threads import single_thread_blas

single_thread_blas()  # before numpy loads its BLAS (see robocal/_blas_threads.py)

from .main import main  # noqa: E402

__all__ = ["main"]
