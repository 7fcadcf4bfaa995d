"""The ``robocal`` command line: one small module per command group, thin over the library.

Every user error ends in one line ``Error: ...`` and a non-zero exit code.
"""

from .main import main

__all__ = ["main"]
