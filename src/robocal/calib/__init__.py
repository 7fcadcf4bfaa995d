"""The calibration engine: parameter blocks, residual blocks (measurement models), the problem that
stacks them, solvers, identifiability and covariance (see docs/calibration.md)."""

from . import blocks, residuals
from .core import Problem
from .errors import ProblemError
from .identifiability import IdentifiabilityReport, analyse_identifiability, observability_indices
from .initial import rigid_fit
from .problem import CalibrationProblem, State, Target
from .solve import CalibrationResult, solve

__all__ = ["CalibrationProblem", "CalibrationResult", "IdentifiabilityReport", "Problem", "ProblemError", "State",
           "Target", "analyse_identifiability", "blocks", "observability_indices", "residuals", "rigid_fit", "solve"]
