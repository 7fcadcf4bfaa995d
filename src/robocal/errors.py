"""robocal's error and warning family: one root for everything robocal raises on purpose.

A script can write ``except robocal.RobocalError`` and catch exactly robocal's own errors. Each
error class of a subpackage (``RobotFileError``, ``MeasurementFileError``, ``ProblemError``, ...)
derives from one of the meaningful subclasses below, and most also from ``ValueError`` (kept for
compatibility with code written before this family existed).

=======================  ==========================================================================
class                    raised when
=======================  ==========================================================================
``RobocalError``         root of every error robocal raises on purpose
``InputError``           an input (file, option, array) is malformed, in the wrong unit or shape
``InputFileError``       a file cannot be read: the message names the file, row and column
``NotIdentifiableError`` a quantity asked for cannot be determined from the data
``NotConvergedError``    a solver stopped without meeting its convergence criterion
``SanityGateError``      a result failed its sanity gates (its status and reasons are attached)
``OutputExistsError``    an output would replace an existing file or an input of the command
=======================  ==========================================================================

Warnings derive from ``RobocalWarning``.
"""

from __future__ import annotations

__all__ = [
    "RobocalError", "InputError", "InputFileError", "NotIdentifiableError", "NotConvergedError",
    "SanityGateError", "OutputExistsError", "RobocalWarning",
]


class RobocalError(Exception):
    """Root of every error robocal raises on purpose."""


class InputError(RobocalError, ValueError):
    """An input (option, array, setting) is malformed, in the wrong unit or of the wrong shape."""


class InputFileError(InputError):
    """A file cannot be read as what it claims to be (the message names file, row and column)."""


class NotIdentifiableError(RobocalError, ValueError):
    """A quantity cannot be determined from the data given (rank deficiency, degenerate poses)."""


class NotConvergedError(RobocalError, RuntimeError):
    """A solver stopped without meeting its stated convergence criterion."""


class SanityGateError(RobocalError):
    """A result failed its sanity gates.

    Attributes
    ----------
    reasons : list of str
        One sentence per failed gate.
    """

    def __init__(self, message: str, reasons=()):
        super().__init__(message)
        self.reasons = list(reasons)


class OutputExistsError(RobocalError, FileExistsError):
    """An output path exists (without ``overwrite``) or is one of the command's inputs."""


class RobocalWarning(UserWarning):
    """Root of robocal's warnings."""
