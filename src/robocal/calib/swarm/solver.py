"""IPSO as a solver of the calibration core: ``solve_swarm(problem, method="ipso" | "ipso+lm")``.

The swarm (:mod:`.pso`) minimises objective (7) (:mod:`.objective`, built from the problem's own
residuals) over a box around the start: by default ±0.01 rad for angles and ±0.5 mm for lengths
(the IPSO paper's box), for the variables the identifiability analysis of the start keeps (a
swarm cannot identify what the data cannot: held variables stay at their start, as in LM).
``ipso+lm`` polishes the swarm's best with the Levenberg-Marquardt :func:`~robocal.calib.solve`.

The result is a :class:`SwarmResult`: the LM :class:`~robocal.calib.solve.CalibrationResult`
(names, units, values, std and covariance at the final state, residuals before (at the start)
and after, identifiability) plus ``method``, ``generations``, the convergence ``history`` (best f
per generation, f in mm^2), ``objective_before`` / ``objective`` and ``non_finite``.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field, fields

import numpy as np

from ..identifiability import analyse_identifiability
from ..solve import CalibrationResult, NotConvergedWarning, _solve_once, solve
from .objective import SwarmObjective, objective_at
from .pso import SwarmInputError, check_box, run_pso

__all__ = ["SwarmResult", "solve_swarm", "search_box", "METHODS"]

METHODS = ("lm", "ipso", "ipso+lm")


@dataclass
class SwarmResult(CalibrationResult):
    """A :class:`CalibrationResult` with the swarm's record: method ("ipso" | "ipso+lm"),
    generations, particles, seed, history (G + 1,) best f [mm^2] after initialisation and each
    generation, search (names searched), lower / upper (steps from the start), objective_before
    (f at the start), swarm_objective (f of the swarm's best), objective (f at the final state),
    non_finite (evaluations that gave NaN / inf, treated as +inf), notes (handled cases)."""

    method: str = "ipso"
    generations: int = 0
    particles: int = 0
    seed: object = 0
    history: np.ndarray = field(default_factory=lambda: np.zeros(0))
    search: tuple = ()
    lower: np.ndarray = field(default_factory=lambda: np.zeros(0))
    upper: np.ndarray = field(default_factory=lambda: np.zeros(0))
    objective_before: float = float("nan")
    swarm_objective: float = float("nan")
    objective: float = float("nan")
    non_finite: int = 0
    notes: list = field(default_factory=list)


def search_box(units, box_rad: float = 0.01, box_mm: float = 0.5):
    """(lower, upper) steps around the start for variables of ``units``: ±box_rad for "rad",
    ±box_mm for "mm"; any other unit raises (give ``bounds`` explicitly)."""
    half = []
    for u in units:
        if u == "rad":
            half.append(box_rad)
        elif u == "mm":
            half.append(box_mm)
        else:
            raise SwarmInputError(f"no default search box for unit {u!r}: give bounds explicitly")
    half = np.array(half, dtype=float)
    return check_box(-half, half)


def _search_names(problem, J, search):
    if search == "identifiable":
        ident = analyse_identifiability(J, problem.names, problem.blocks, column_blocks=problem.column_blocks)
        return ident.identifiable, ident
    names = list(problem.names) if search == "all" else list(search)
    return names, None


def solve_swarm(problem, *, method: str = "ipso", particles: int = 20, generations: int = 2000, seed=0,
                box_rad: float = 0.01, box_mm: float = 0.5, bounds=None, search="identifiable", state0=None,
                progress=None, lm_options=None) -> SwarmResult:
    """Calibrate ``problem`` with the improved particle swarm (and an LM polish for "ipso+lm").

    particles, generations: swarm size and length (paper: 20, 2000); seed: int (Halton scrambling
    and the random coefficients; deterministic); box_rad [rad], box_mm [mm]: half-widths of the
    search box around the start; bounds: (lower, upper) steps (n_search,) overriding the box;
    search: "identifiable" (default), "all" or a list of variable names; state0: start state
    (default the problem's initial state); progress: ``progress(generation, best_f)``;
    lm_options: keyword arguments of :func:`~robocal.calib.solve` for the polish.
    """
    if method not in ("ipso", "ipso+lm"):
        raise SwarmInputError(f"method must be 'ipso' or 'ipso+lm', got {method!r}")
    start = problem.initial_state() if state0 is None else state0
    _, J, _ = problem.evaluate(start)
    names, ident = _search_names(problem, J, search)
    obj = SwarmObjective(problem, start, names)
    units = [problem.units[c] for c in obj.columns]
    lower, upper = search_box(units, box_rad, box_mm) if bounds is None else check_box(*bounds)
    if lower.size != len(names):
        raise SwarmInputError(f"bounds: {lower.size} values for {len(names)} searched variables")
    f0 = objective_at(problem, start)
    if not np.isfinite(f0):
        raise SwarmInputError(f"objective at the start is {f0} (forward kinematics or data not finite)")
    out = run_pso(obj, lower, upper, particles=particles, generations=generations, seed=seed, progress=progress)
    step = np.zeros(problem.n_variables)
    step[obj.columns] = out.best_x
    best = problem.retract(start, step)
    notes = _notes(out, lower, upper)
    if method == "ipso+lm":
        res = solve(problem, state0=best, **(lm_options or {}))
    else:
        res = _solve_once(problem, state0=best, max_iterations=0, ident=ident)
        res.converged, res.reason = _swarm_convergence(out.history)
        res.iterations = out.generations
        if not res.converged:
            warnings.warn(NotConvergedWarning(res.reason), stacklevel=2)
    return _as_swarm_result(problem, res, start, out, method, particles, seed, names, lower, upper, f0, notes)


def _swarm_convergence(history, tail: float = 0.1, rtol: float = 1e-4):
    """(converged, reason): the best f changed by less than ``rtol`` (relative) over the last
    ``tail`` of the generations."""
    G = len(history) - 1
    k = max(1, int(round(tail * G)))
    a, b = history[-1 - k], history[-1]
    rel = (a - b) / max(abs(a), 1e-300)
    ok = bool(rel < rtol)
    return ok, (f"swarm: {G} generations, best f {b:.6g} mm^2, relative change {rel:.2g} over the last {k} "
                f"generation(s) ({'stalled' if ok else 'still improving: more generations?'})")


def _notes(out, lower, upper):
    notes = []
    if out.non_finite:
        notes.append(f"{out.non_finite} of {out.evaluations} swarm evaluations were not finite and counted as +inf")
    at_wall = np.isclose(out.best_x, lower) | np.isclose(out.best_x, upper)
    if at_wall.any():
        notes.append(f"{int(at_wall.sum())} searched variable(s) ended on the search box wall: the optimum may "
                     "lie outside the box (widen it, or polish with ipso+lm)")
    return notes


def _as_swarm_result(problem, res, start, out, method, particles, seed, names, lower, upper, f0, notes):
    base = {f.name: getattr(res, f.name) for f in fields(CalibrationResult)}
    r0, _, _ = problem.evaluate(start, jacobian=False)
    base.update(residuals_before=r0, point_errors_before=problem.point_errors(r0),
                initial=problem.variable_values(start))
    return SwarmResult(**base, method=method, generations=out.generations, particles=int(particles), seed=seed,
                       history=out.history, search=tuple(names), lower=lower, upper=upper, objective_before=f0,
                       swarm_objective=out.best_f, objective=objective_at(problem, res.state),
                       non_finite=out.non_finite, notes=notes)
