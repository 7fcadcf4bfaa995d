"""The calibration engine: parameter blocks, measurement models, solvers, identifiability."""

from .identifiability import IdentifiabilityReport, analyse_identifiability, observability_indices
from .problem import CalibrationProblem, ProblemError, State, Target
from .solve import CalibrationResult, solve

__all__ = ["CalibrationProblem", "CalibrationResult", "IdentifiabilityReport", "ProblemError", "State", "Target",
           "analyse_identifiability", "observability_indices", "solve"]
