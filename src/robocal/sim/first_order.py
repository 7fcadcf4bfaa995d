"""The miss a tracker calibration leaves when its campaign carries effects the model lacks, to
first order (issue 25, item 4), derived from a ``robocal simulate tracker`` truth file.

A least-squares fit of data that carry a small effect ``e`` the model cannot represent lands, to
first order, at ``truth + J^+ e`` (``J``: the Jacobian of the model's predictions with respect to
the fitted variables at the solution). With ``e`` taken from the simulator's hidden truth
(noise-free predictions with the effect minus without), a test (or a documented figure,
:mod:`robocal.docs.figures`) can state "within k sigma of truth plus that bias" -- a claim the
simulator does not make true by construction. Jacobians here are finite differences of the
simulator's geometry, not the solver's code.
"""

from __future__ import annotations

import numpy as np

from ..transforms import so3_exp, transforms_from

__all__ = ["NO_EFFECTS", "STEP", "campaign_effect_points", "first_order_bias", "tracker_campaign_bias", "twist"]

STEP = 1e-6
NO_EFFECTS = {"transmission_deg": [0.0, 0.0], "transmission_phases_rad": [[0.0], [0.0]], "growth_ppm": 0.0,
              "tracker_scale_ppm": 0.0}
"""The campaign effects of an ideal ``simulate tracker`` campaign (its truth file has no entry)."""


def first_order_bias(columns, base, e, h: float = STEP) -> np.ndarray:
    """``J^+ e`` with ``J = (columns - base) / h`` (columns: (k, m) predictions with variable i
    moved by ``h``; base (m,); e (m,) the effect's displacement of the predictions)."""
    J = (np.asarray(columns, dtype=float) - np.asarray(base, dtype=float)).T / h
    return np.linalg.lstsq(J, np.asarray(e, dtype=float).ravel(), rcond=None)[0]


def twist(k: int, h: float = STEP) -> np.ndarray:
    """(4, 4) a step ``h`` along one of the six twist coordinates (rotation vector 0-2, mm 3-5)."""
    w = np.zeros(6)
    w[k] = h
    return transforms_from(so3_exp(w[:3]), w[3:])


def campaign_effect_points(truth: dict, q, growth) -> tuple:
    """Reflector points (N, k, 3) [mm, tracker frame] of the hidden true robot of a truth file of
    ``robocal simulate tracker --effects ...`` at commanded joints ``q`` (N, n) [rad]: ``(model,
    reached)``, without and with the transmission error (its definition in
    :mod:`robocal.sim.campaign_effects`, written out here) and a relative ``growth`` (N,) of the
    arm about the true base origin."""
    from ..robots import load_robot

    nominal = load_robot(truth["robot"])
    true = nominal.with_params(**{k: float(v) for k, v in truth["true_parameters"].items()})
    eff = truth.get("campaign_effects") or NO_EFFECTS  # an ideal campaign's truth file has none
    a1, a2 = np.radians(eff["transmission_deg"])
    ph = np.asarray(eff["transmission_phases_rad"])
    q = np.atleast_2d(q)
    q_real = q + a1 * np.sin(q + ph[0]) + a2 * np.sin(2 * q + ph[1])
    T_tb = np.asarray(truth["T_tracker_base"])
    refl = np.asarray(truth["reflectors_mm"])
    T_bw = np.linalg.inv(true.T_world_base)

    def points(qq, g):
        T = T_bw @ true.fk(qq)  # base frame
        p = np.einsum("nij,kj->nki", T[:, :3, :3], refl) + T[:, None, :3, 3]
        p = p * (1.0 + np.asarray(g, dtype=float))[:, None, None]
        return p @ T_tb[:3, :3].T + T_tb[:3, 3]

    return points(q, np.zeros(len(q))), points(q_real, growth)


def tracker_campaign_bias(truth: dict, free, q_train, q_at, *, point=None) -> np.ndarray:
    """First-order miss (M, 3) [mm, tracker frame] of the first reflector at joints ``q_at`` (M, n)
    [rad] after a point calibration (positions of every reflector, unweighted) on ``q_train``
    (N, n) [rad], the campaign's effects from the truth file: the fit's variables (the ``free``
    parameters, a base twist, every reflector offset) are biased by ``delta = J^+ e_train`` and the
    true robot, which carries the effects at ``q_at`` (the arm grown as at the last pose), lands at
    ``e_at - J_at delta`` from where the calibrated model says. Jacobians by finite differences of
    the true geometry (:data:`STEP`). ``free``: the parameters the calibration estimated (not the
    ones it reported as not identified: their columns make ``J`` singular up to finite-difference
    noise, and ``J^+`` would then follow that noise).

    ``point`` (3,) [mm, true flange frame]: the miss of that flange point instead (a tool the campaign
    never saw, not a fit variable). The parameters the calibration did not estimate are then held at
    their nominal values in the fit and in the calibrated model, as robocal holds them: their
    errors enter the fit's data as ``g = F(held nominal) - F(true)`` (the fit moves by ``J^+ (e -
    g)``) and the point's prediction by the same difference at ``q_at``, so the miss includes the
    part robocal reports as unknown (``unknown_mm``), here derived from the hidden truth."""
    from ..robots import load_robot

    nominal = load_robot(truth["robot"])
    true = nominal.with_params(**{k: float(v) for k, v in truth["true_parameters"].items()})
    T_tb = np.asarray(truth["T_tracker_base"])
    refl = np.asarray(truth["reflectors_mm"], dtype=float)
    T_bw = np.linalg.inv(true.T_world_base)
    vals = true.params.values

    def predict(q, values=vals, T=T_tb, r=refl):
        Tq = T @ T_bw @ true.with_params(values).fk(np.atleast_2d(q))
        return (np.einsum("nij,kj->nki", Tq[:, :3, :3], r) + Tq[:, None, :3, 3]).ravel()

    def columns(q):
        cols = []
        for n in free:
            v = vals.copy()
            v[true.params.index(n)] += STEP
            cols.append(predict(q, values=v))
        cols += [predict(q, T=T_tb @ twist(k)) for k in range(6)]
        for i in range(refl.size):
            r = refl.copy().ravel()
            r[i] += STEP
            cols.append(predict(q, r=r.reshape(refl.shape)))
        return np.array(cols)

    eff = truth.get("campaign_effects") or NO_EFFECTS
    g = float(eff["growth_ppm"]) * 1e-6
    scale = 1.0 + float(eff["tracker_scale_ppm"]) * 1e-6
    model, reached = campaign_effect_points(truth, q_train, np.linspace(0.0, g, len(q_train)))
    J = (columns(q_train) - predict(q_train)).T / STEP
    if point is None:
        delta = np.linalg.lstsq(J, (reached * scale - model).ravel(), rcond=None)[0]
        model_at, reached_at = campaign_effect_points(truth, q_at, np.full(len(np.atleast_2d(q_at)), g))
        J_at = (columns(q_at) - predict(q_at)).T / STEP
        miss = (reached_at - model_at).ravel() - J_at @ delta
        return miss.reshape(len(np.atleast_2d(q_at)), len(refl), 3)[:, 0]
    held = vals.copy()  # the parameters not estimated, at their nominal values
    for i, n in enumerate(true.params.names):
        if n not in free:
            held[i] = nominal.params.values[i]
    g_train = predict(q_train, values=held) - predict(q_train)
    delta = np.linalg.lstsq(J, (reached * scale - model).ravel() - g_train, rcond=None)[0]
    x = np.asarray(point, dtype=float)[None]
    at = {**truth, "reflectors_mm": x.tolist()}
    model_at, reached_at = campaign_effect_points(at, q_at, np.full(len(np.atleast_2d(q_at)), g))
    cols_at = []  # the point's columns: the free parameters and the base twist (no reflector variable)
    for n in free:
        v = vals.copy()
        v[true.params.index(n)] += STEP
        cols_at.append(predict(q_at, values=v, r=x))
    cols_at += [predict(q_at, T=T_tb @ twist(k), r=x) for k in range(6)]
    J_at = (np.array(cols_at) - predict(q_at, r=x)).T / STEP
    g_at = predict(q_at, values=held, r=x) - predict(q_at, r=x)
    miss = (reached_at - model_at).ravel() - J_at @ delta[: len(cols_at)] - g_at
    return miss.reshape(len(np.atleast_2d(q_at)), 3)
