"""The calibration engine: parameter blocks, measurement models, solvers, identifiability."""

from .identifiability import IdentifiabilityReport, analyse_identifiability, observability_indices
from .initial import rigid_fit
from .problem import CalibrationProblem, ProblemError, State, Target
from .solve import CalibrationResult, solve

__all__ = ["CalibrationProblem", "CalibrationResult", "IdentifiabilityReport", "ProblemError", "State", "Target",
           "analyse_identifiability", "observability_indices", "rigid_fit", "solve"]
