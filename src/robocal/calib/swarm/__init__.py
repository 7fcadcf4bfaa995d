"""The improved particle swarm (IPSO, METHODS.md section 3) as a solver of the calibration core.

* :mod:`.pso` -- the swarm on any batched objective (Halton start, Clerc constriction);
* :mod:`.objective` -- objective (7) from a problem's residuals, for a whole swarm at once;
* :mod:`.solver` -- :func:`solve_swarm` (``ipso``, ``ipso+lm``) and :class:`SwarmResult`.
"""

from .objective import SwarmObjective, objective_at
from .pso import PSOOutcome, SwarmInputError, constriction_factor, halton_swarm, run_pso
from .solver import METHODS, SwarmResult, search_box, solve_swarm

__all__ = ["METHODS", "PSOOutcome", "SwarmInputError", "SwarmObjective", "SwarmResult", "constriction_factor",
           "halton_swarm", "objective_at", "run_pso", "search_box", "solve_swarm"]
