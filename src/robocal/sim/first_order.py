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

__all__ = ["NO_EFFECTS", "REALISTIC", "STEP", "campaign_effect_points", "first_order_bias", "poses_with_effects",
           "six_d_fit_bias", "tracker_campaign_bias", "twist"]

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


REALISTIC = {"transmission_deg": (0.005, 0.003), "growth_ppm": 20.0, "tracker_scale_ppm": 5.0}
"""The ``realistic`` preset of :class:`robocal.sim.campaign_effects.CampaignEffects`, written out."""


def poses_with_effects(model, q, T_inst, T_tool, phases, effects=REALISTIC, *, after_campaign: bool = False) -> tuple:
    """A 6-D campaign's probe poses (N, 4, 4) [mm] in the instrument frame, the robot ``model``
    (the hidden truth) at commanded ``q`` (N, n) [rad] in this measuring order: ``(model_poses,
    measured_poses)``, noise-free, without and with ``effects`` (the definitions of
    :mod:`robocal.sim.campaign_effects`, written out): the transmission error with ``phases``
    (2, n) [rad], the arm grown from 0 to ``growth_ppm`` about the base origin over the campaign,
    the instrument's distances from its origin scaled by ``tracker_scale_ppm``. ``after_campaign``:
    where the robot really is after the campaign (every pose grown by ``growth_ppm``, no
    instrument scale: a robot executing a program)."""
    q = np.atleast_2d(q)
    a1, a2 = np.radians(effects["transmission_deg"])
    q_real = q + a1 * np.sin(q + phases[0]) + a2 * np.sin(2 * q + phases[1])
    T_model = T_inst @ model.fk(q) @ T_tool
    T_wb = model.T_world_base
    T_base = np.linalg.inv(T_wb) @ model.fk(q_real) @ T_tool
    growth = np.ones(len(q)) if after_campaign else np.linspace(0.0, 1.0, len(q))
    T_base[:, :3, 3] *= 1.0 + effects["growth_ppm"] * 1e-6 * growth[:, None]
    T_meas = T_inst @ T_wb @ T_base
    if not after_campaign:
        T_meas[:, :3, 3] *= 1.0 + effects["tracker_scale_ppm"] * 1e-6
    return T_model, T_meas


def six_d_fit_bias(model, free, q, T_inst, T_tool, T_meas, weight_mm_per_rad: float, *, q_at=None,
                   T_at=None, noise_mm: float | None = None) -> dict:
    """First-order bias of a 6-D calibration (positions [mm] and rotations weighted by
    ``weight_mm_per_rad``, unweighted otherwise) of ``model``'s ``free`` parameters (the ones the
    calibration estimated), the instrument-to-base frame and the tool frame, from noise-free
    measured poses ``T_meas`` (N, 4, 4) that carry an effect the model lacks.

    Returns ``{"params": {name: bias}, "tool_rotvec": (3,) [rad] (the tool rotation's error
    ``log(R_fit R_true^T)``), "tool_xyz": (3,) [mm], "residual_rms_mm": the RMS position misfit the
    effect leaves after the fit, ``|(I - J J^+) e|`` over the poses}``. With ``q_at`` (M, n) [rad]
    and ``T_at`` (M, 4, 4) [mm] (where the true robot with the effects really takes the tool at
    ``q_at``, noise-free) also ``"miss_at"`` (M, 6): where it lands minus where the biased fit
    says, ``e_at - J_at delta``, position [mm] and rotation vector [rad] in the instrument frame;
    with ``noise_mm`` (per coordinate; rotations ``noise_mm / weight`` rad) also ``"sigma_at_mm"``
    (M,): the RMS length of the noise part of the landing error, ``noise sqrt(tr(J_p (J^T J)^-1 J_p^T))``,
    and ``"sigma_at_rad"`` (M,): the same for the landing rotation's error (its rotation vector, rad)."""
    from ..transforms import so3_log

    vals = model.params.values

    def predict(values=vals, Ti=T_inst, Tt=T_tool, qq=q, R_ref=T_meas[:, :3, :3], w=weight_mm_per_rad):
        T = Ti @ model.with_params(values).fk(np.atleast_2d(qq)) @ Tt
        rot = so3_log(T[:, :3, :3] @ np.swapaxes(R_ref, 1, 2)) * w
        return np.concatenate([T[:, :3, 3], rot], axis=1).ravel()

    def columns(**kw):
        cols = []
        for n in free:
            v = vals.copy()
            v[model.params.index(n)] += STEP
            cols.append(predict(values=v, **kw))
        cols += [predict(Ti=T_inst @ twist(k), **kw) for k in range(6)]
        for k in range(3):  # the tool rotation, turned in the flange frame: R -> exp(w) R
            Tt = T_tool.copy()
            Tt[:3, :3] = twist(k)[:3, :3] @ T_tool[:3, :3]
            cols.append(predict(Tt=Tt, **kw))
        for k in range(3):
            Tt = T_tool.copy()
            Tt[k, 3] += STEP
            cols.append(predict(Tt=Tt, **kw))
        return cols

    cols = columns()
    base = predict()
    e = np.concatenate([T_meas[:, :3, 3], np.zeros((len(T_meas), 3))], axis=1).ravel() - base
    delta = first_order_bias(cols, base, e)
    misfit = (e - (np.asarray(cols) - base).T / STEP @ delta).reshape(len(T_meas), 6)[:, :3]
    k = len(free) + 6
    out = {"params": dict(zip(free, delta[: len(free)])), "tool_rotvec": delta[k:k + 3],
           "tool_xyz": delta[k + 3:k + 6], "residual_rms_mm": float(np.sqrt(np.mean(np.sum(misfit**2, axis=1))))}
    if q_at is not None:
        T_model = T_inst @ model.fk(np.atleast_2d(q_at)) @ T_tool
        at = {"qq": q_at, "R_ref": T_model[:, :3, :3], "w": 1.0}
        base_at = predict(**at)
        J_at = (np.asarray(columns(**at)) - base_at).T / STEP
        e_at = np.concatenate([T_at[:, :3, 3] - T_model[:, :3, 3],
                               so3_log(T_at[:, :3, :3] @ np.swapaxes(T_model[:, :3, :3], 1, 2))], axis=1)
        out["miss_at"] = e_at - (J_at @ delta).reshape(-1, 6)
        if noise_mm is not None:
            J_pinv = np.linalg.pinv((np.asarray(cols) - base).T / STEP)
            cov = J_pinv @ J_pinv.T * noise_mm**2
            J_6 = J_at.reshape(-1, 6, J_at.shape[1])
            out["sigma_at_mm"] = np.sqrt(np.einsum("mij,jk,mik->m", J_6[:, :3], cov, J_6[:, :3]))
            out["sigma_at_rad"] = np.sqrt(np.einsum("mij,jk,mik->m", J_6[:, 3:], cov, J_6[:, 3:]))
    return out
