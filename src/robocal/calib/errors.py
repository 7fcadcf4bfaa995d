"""The calibration core's error type (shared by blocks, residuals, problems and builders)."""

from __future__ import annotations

__all__ = ["ProblemError"]


class ProblemError(ValueError):
    """A calibration problem is set up inconsistently (the message names what and where)."""
