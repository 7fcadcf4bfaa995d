"""A tracker calibration on a campaign with the effects the model lacks (issue 25, item 4), with the
bias they cause derived to first order from the hidden truth: the set-up of
``tests/test_calibration.py``'s realistic case, shared with the documented figures of docs/testing.md
(robocal.docs.figures): same draws.

With ``e`` the effect in the training measurements (measured minus the true robot's geometric
points, noise-free) and ``J`` the fit's Jacobian, the estimate is biased by ``delta = J^+ e``; the
hold-out error against where the robot really was is then ``J_h delta - e_h`` plus the noise part,
whose mean square is the noise-limited optimum ``sigma^2 tr(J_h (J^T J)^-1 J_h^T) / N_h``.

Lengths mm, angles rad.
"""

from __future__ import annotations

import numpy as np

from ..calib import CalibrationProblem, Target, solve
from ..robots import load_robot
from .campaign_effects import CampaignEffects, measure_with_effects
from .robot import VirtualRobot
from .tracker import LaserTracker

__all__ = ["effects_campaign_fit", "noise_limited_holdout_mse"]


def noise_limited_holdout_mse(prob, res, q_hold, sigma: float) -> float:
    """The noise-limited hold-out optimum [mm^2] of a point calibration ``prob`` / ``res`` at joints
    ``q_hold`` (N_h, n) [rad]: ``sigma^2 tr(J_h (J^T J)^-1 J_h^T) / N_h`` over the identifiable set
    (``sigma`` [mm] the point noise per coordinate)."""
    active = np.isfinite(np.diag(res.covariance))
    _, J, _ = prob.evaluate(res.state)
    _, Jh = prob.predict_points(res.state, q=q_hold, jacobian=True)
    Jh = Jh.reshape(-1, prob.n_variables)[:, active] / sigma
    cov = np.linalg.inv(J[:, active].T @ J[:, active])
    return float(np.einsum("ij,jk,ik->", Jh, cov, Jh)) * sigma**2 / len(q_hold)


def effects_campaign_fit(name: str, seed: int, effects: CampaignEffects | None = None, *, n_train: int = 100,
                         n_total: int = 300, tool_mm=(30.0, 40.0, 100.0), sigma_mm: float = 0.02) -> dict:
    """One campaign: robot ``name`` perturbed with ``seed`` (no encoder noise), a tracker placed with
    ``seed + 100`` measuring one reflector at ``tool_mm`` with ``sigma_mm``, ``n_total`` joint sets
    (``seed + 200``, margin 0.1 rad), measured with ``effects`` (default: the ``realistic`` preset;
    noise and phases from ``seed + 300``); the first ``n_train`` calibrated (every identifiable DH
    (+beta) parameter and joint offset, base fitted), the rest held out.

    Returns
    -------
    dict
        ``problem``, ``result`` (the fit), ``z_naive`` (error / sigma of the compared parameters:
        identifiable and free of trade-offs), ``z_bias`` ((error - delta) / sigma), ``holdout_mse``
        (mean squared hold-out error against where the robot really was [mm^2]), ``predicted_mse``
        (first-order miss plus the noise floor), ``floor_mse`` (the noise floor).
    """
    effects = CampaignEffects.realistic() if effects is None else effects
    nominal = load_robot(name)
    robot = VirtualRobot.perturbed(nominal, seed, joint_noise_deg=0.0)
    tracker = LaserTracker.placed(seed + 100, reflectors=np.atleast_2d(np.asarray(tool_mm, dtype=float)), sigma_mm=sigma_mm)
    q = robot.random_configurations(n_total, np.random.default_rng(seed + 200), margin=0.1)
    m = measure_with_effects(robot, tracker, q, effects, seed + 300)
    n = n_train
    prob = CalibrationProblem(nominal, q[:n], [Target("r1", None, (0.0, 0.0, 50.0))], m["points"][:n],
                              point_sigma_mm=sigma_mm, base_initial="fit")
    res = solve(prob)
    # first-order bias from the hidden truth: the noise-free measurement minus the model's point
    seen = m["reached"] * (1.0 + effects.tracker_scale_ppm * 1e-6)
    e_train = (seen[:n] - m["model"][:n]).reshape(-1)
    active = np.isfinite(np.diag(res.covariance))
    _, Jt = prob.predict_points(res.state, q=q[:n], jacobian=True)
    delta = np.zeros(prob.n_variables)
    delta[active] = np.linalg.lstsq(Jt.reshape(-1, prob.n_variables)[:, active], e_train, rcond=None)[0]
    true_vals = robot.true_model.params.values
    partners = {p for d in res.identifiability.dropped for p, _ in d["trades_off_with"]}
    z_naive, z_bias = [], []
    for i, nm in enumerate(prob.free_params):
        if nm in res.identifiability.identifiable and nm not in partners:
            err = res.values[i] - true_vals[nominal.params.index(nm)]
            z_naive.append(err / res.std[i])
            z_bias.append((err - delta[prob.names.index(nm)]) / res.std[i])
    pred = prob.predict_points(res.state, q=q[n:])
    holdout = float(np.mean(np.sum((pred - m["reached"][n:]) ** 2, axis=-1)))
    _, Jh = prob.predict_points(res.state, q=q[n:], jacobian=True)
    miss = Jh.reshape(-1, prob.n_variables) @ delta - (m["reached"][n:] - m["model"][n:]).reshape(-1)
    floor = noise_limited_holdout_mse(prob, res, q[n:], sigma_mm)
    return {"problem": prob, "result": res, "z_naive": np.array(z_naive), "z_bias": np.array(z_bias),
            "holdout_mse": holdout, "predicted_mse": float(np.sum(miss**2) / (len(q) - n) + floor), "floor_mse": floor}
