"""The calibration core's error type (shared by blocks, residuals, problems and builders)."""

from __future__ import annotations
from ..errors import InputError

__all__ = ["ProblemError"]


class ProblemError(InputError):
    """A calibration problem is set up inconsistently (the message names what and where)."""
