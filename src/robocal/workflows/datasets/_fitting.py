"""What the real-data protocols share: the seeded split, the fit, held-out error statistics."""

from __future__ import annotations

import numpy as np

from ...calib import CalibrationProblem, Target, solve
from ...calib.elastic import ElasticModel
from ..convergence import record_fit, recording_fits

__all__ = ["MODELS", "PROTOCOL_MAX_ITERATIONS", "recording_fits", "elastic_model", "random_split", "error_stats", "points_in_base", "param_names", "fit", "with_state_targets",
           "holdout_stats"]


#: Iteration cap of every protocol fit: far above what any shipped protocol needs (measured in
#: docs/datasets.md), so a fit that stops there is reported as not converged, not cut short.
PROTOCOL_MAX_ITERATIONS = 1000

#: the model choices of every protocol (``robocal datasets run NAME --model ...``)
MODELS = ("geometric", "elastic-joint", "elastic-full")


def elastic_model(name: str, **kw):
    """The :class:`~robocal.calib.elastic.ElasticModel` of a model choice (None for ``geometric``):
    ``elastic-joint`` = a torsional compliance per joint carrying the targets, lumped gravity
    parameters identified from the data (the data sets come without a mass model);
    ``elastic-full`` = the same plus two lateral (bending) compliances per joint."""
    if name not in MODELS:
        raise ValueError(f"unknown model {name!r}; expected one of {', '.join(MODELS)}")
    if name == "geometric":
        return None
    return ElasticModel(compliance_initial=kw.get("compliance_initial", 100.0), joints=kw.get("joints"),
                        lateral=name == "elastic-full")


def random_split(n: int, n_train: int, seed: int) -> tuple:
    """Seeded random split of ``n`` poses: (``n_train`` training indices, the rest), both sorted."""
    perm = np.random.default_rng(seed).permutation(n)
    return np.sort(perm[:n_train]), np.sort(perm[n_train:])


def error_stats(predicted, measured) -> dict:
    """Position errors |measured - predicted| over all measured points: rms, mean, max [mm], n;
    plus p95_xy and p95_z (95th percentiles of the xy norm and of |z|, the Hilti metric).
    ``predicted``, ``measured``: (..., 3) [mm]; NaN marks a point not measured."""
    d = (np.asarray(measured, dtype=float) - np.asarray(predicted, dtype=float)).reshape(-1, 3)
    d = d[np.all(np.isfinite(d), axis=1)]
    e = np.linalg.norm(d, axis=1)
    return {"rms": float(np.sqrt(np.mean(e**2))), "mean": float(e.mean()), "max": float(e.max()), "n": int(len(e)),
            "p95_xy": float(np.percentile(np.linalg.norm(d[:, :2], axis=1), 95)),
            "p95_z": float(np.percentile(np.abs(d[:, 2]), 95))}


def points_in_base(model, q, targets) -> np.ndarray:
    """Target positions (N, K, 3) [mm] in the robot base frame (the model's ``T_world_base`` ignored)
    at joints ``q`` (N, n) for the :class:`~robocal.calib.Target` s ``targets``."""
    m = model.replace(T_world_base=np.eye(4))
    T = m.fk_all(np.asarray(q, dtype=float))  # (N, E, 4, 4)
    out = np.empty((len(T), len(targets), 3))
    for k, t in enumerate(targets):
        e = model.end_effector_index(t.end_effector)
        out[:, k] = (T[:, e, :3, :3] @ np.asarray(t.point, dtype=float)) + T[:, e, :3, 3]
    return out


def param_names(model, link_names, kinds) -> list:
    """Model parameter names ``<kind><k+1>`` of the named links (those that exist)."""
    by_name = {L.name: k for k, L in enumerate(model.links)}
    out = []
    for ln in link_names:
        k = by_name[ln]
        for p in kinds:
            if p in model.links[k].params:
                out.append(f"{p}{k + 1}")
    return out


def fit(model, q, targets, points, free, stations=None, base_initial=None, prior=0.0, elastic=None, start=None,
        damping=None, **kw):
    """``(problem, result)`` of a calibration of ``free`` parameters plus base frame(s) and targets
    (and the joint compliances of ``elastic``, an :class:`~robocal.calib.elastic.ElasticModel`;
    ``start``: {state field: value} overriding the initial state, e.g. the compliances of a
    previous level; ``damping``: the LM damping rule, ``"tenfold"`` (default) or ``"gain"``
    (:class:`~robocal.calib.core.Problem`));
    the base starts from a rigid fit of the initial model's predictions, per station."""
    if base_initial is None:
        base_initial = "fit"
    prob = CalibrationProblem(model, q, targets, points, free=free, stations=stations, base_initial=base_initial,
                              elastic=elastic)
    if damping is not None:
        prob.damping = damping
    if start:
        kw["state0"] = prob.initial_state()._replace(**start)
    kw.setdefault("max_iterations", PROTOCOL_MAX_ITERATIONS)
    return prob, record_fit(solve(prob, prior_weight=prior, **kw))


def with_state_targets(targets, state) -> list:
    """``targets`` with their points replaced by those of the solver ``state``."""
    return [Target(t.name, t.end_effector, tuple(state.targets[k]), t.free) for k, t in enumerate(targets)]


def holdout_stats(problem, result, ds, test) -> dict:
    """:func:`error_stats` of ``problem`` at ``result`` on the held-out poses ``test`` of ``ds``."""
    predicted = problem.predict_points(result.state, q=ds.joints[test], stations=np.zeros(len(test), int))
    return error_stats(predicted, ds.points[test])
