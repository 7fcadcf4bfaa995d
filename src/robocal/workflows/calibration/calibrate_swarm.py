"""``robocal calibrate --method ipso | ipso+lm``: the improved particle swarm (issue 13) inside the
calibrate workflow, kept out of :mod:`robocal.workflows.calibration.calibrate` (which calls :func:`identify`
and :func:`swarm_record`).

The swarm starts from the baseline state (nominal geometry, fitted base frame and target points)
and searches the box ±0.01 rad / ±0.5 mm around it (the IPSO paper's), the identifiable variables
only. ``--seed`` seeds both the calibration/holdout split and the swarm.
"""

from __future__ import annotations

import numpy as np

from ...calib import solve
from ...calib.swarm import METHODS, solve_swarm

__all__ = ["identify", "swarm_record", "convergence_plots", "check_method", "SWARM_METHODS"]

SWARM_METHODS = ("ipso", "ipso+lm")


def check_method(method: str, loss: str) -> None:
    """Refuse unknown methods and robust losses with the swarm (objective (7) is plain squares)."""
    if method not in METHODS + ("svd",):
        raise ValueError(f"--method must be one of {', '.join(METHODS)}, got {method!r}")
    if method in SWARM_METHODS and loss != "linear":
        raise ValueError(f"--method {method} minimises plain squared errors (objective (7)); use --loss linear "
                         "or --method lm for a robust loss")


def identify(problem, state0, *, method, loss, max_iterations, seed=0, particles=20, generations=2000,
             progress=None):
    """The calibration result: LM (or SVD) from ``state0``, or the swarm (then LM for ipso+lm).
    progress(generation, best_f): the swarm's, per generation."""
    if method not in SWARM_METHODS:
        return solve(problem, loss=loss, method=method, state0=state0, max_iterations=max_iterations)
    return solve_swarm(problem, method=method, particles=particles, generations=generations, seed=seed,
                       state0=state0, progress=progress, lm_options={"max_iterations": max_iterations})


def swarm_record(rdict: dict, result, method: str) -> None:
    """Record ``method``, ``generations`` and the final ``objective`` in the result dict (top level
    and ``solver``), with the swarm's history, box and notes for ipso / ipso+lm."""
    rdict["method"] = method
    rdict["generations"] = int(getattr(result, "generations", 0))
    obj = getattr(result, "objective", None)
    if obj is None:
        problem = result.problem
        r = result.residuals_after
        obj = float(problem.residual_scale**2 * (r @ r) / max(problem.n_poses, 1))
    rdict["objective"] = float(obj)
    solver = rdict.setdefault("solver", {})
    solver.update(method=method, generations=rdict["generations"], objective=rdict["objective"],
                  objective_unit="mm^2 (objective (7): mean over poses of |dp|^2 + k |d delta|^2)")
    if method in SWARM_METHODS:
        solver["swarm"] = {
            "particles": result.particles, "seed": result.seed, "searched": list(result.search),
            "box_lower": [float(v) for v in result.lower], "box_upper": [float(v) for v in result.upper],
            "objective_before": float(result.objective_before), "swarm_objective": float(result.swarm_objective),
            "history": [float(v) for v in np.asarray(result.history)], "non_finite": int(result.non_finite),
            "notes": list(result.notes)}


def convergence_plots(result) -> dict:
    """{section title: SVG text} with the swarm's convergence curve (empty for LM)."""
    history = getattr(result, "history", None)
    if history is None or len(history) < 2:
        return {}
    from ...report.convergence import plot_convergence

    svg = plot_convergence(history)
    return {"IPSO convergence (best objective per generation)": svg} if svg else {}
