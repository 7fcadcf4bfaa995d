"""Planning a measurement campaign: which poses to measure, and what the plan will deliver.

:func:`plan_campaign` picks ``count`` candidate poses by greedy D-optimal selection
(:func:`robocal.calib.poses.select_poses`) and predicts, to first order, the standard deviation of
every identifiable variable and the accuracy on the other candidates (the held-out error to expect).
Which variables are identifiable is the calibration's own verdict
(:func:`calibration_identifiability`: ``solve`` on noise-free data of a typical robot, the same
tolerance), so plan and calibration agree; the covariance and every prediction Jacobian are taken
at that typical robot. :func:`predicted_workspace_accuracy` is the noise-free criterion a set of
plans is ranked by. Which poses a robot can take is the cell's business (:mod:`robocal.calib.cell`);
:func:`visible_candidates` is the older range-and-incidence test without the arm (kept for callers).
"""

from __future__ import annotations

import numpy as np

from .poses import pose_jacobians, select_poses
from .problem import CalibrationProblem, Target

__all__ = ["visible_candidates", "plan_campaign", "predicted_covariance", "predicted_model_std",
           "calibration_identifiability", "TYPICAL_DEVIATION", "predicted_workspace_accuracy"]


def visible_candidates(points, z_axes, tracker_at, *, range_mm=(1000.0, 15000.0), max_incidence_deg=60.0):
    """(N,) bool: reflector ``points`` (N, 3) [mm] within ``range_mm`` of the instrument at
    ``tracker_at`` (3,) [mm] and facing it: the angle between the reflector axis ``z_axes`` (N, 3)
    (unit) and the line of sight at most ``max_incidence_deg``. (Occlusion by the robot itself is
    not modelled.)"""
    d = np.asarray(tracker_at, dtype=float) - points
    dist = np.linalg.norm(d, axis=1)
    cos = np.einsum("ij,ij->i", d, z_axes) / np.maximum(dist, 1e-9)
    return (dist >= range_mm[0]) & (dist <= range_mm[1]) & (cos >= np.cos(np.radians(max_incidence_deg)))


def predicted_covariance(J_blocks, idx, cols, sigma_mm):
    """Covariance (c, c) of the columns ``cols`` from the rows of poses ``idx``: sigma^2 (J^T J)^-1."""
    J = J_blocks[idx][..., cols].reshape(-1, len(cols))
    return sigma_mm**2 * np.linalg.inv(J.T @ J)


def _point_problem(model, q, tool, free, sigma_mm):
    return CalibrationProblem(model.replace(T_world_base=np.eye(4)), q, [Target("reflector", point=tuple(tool))],
                              free=free, base_initial=np.eye(4), point_sigma_mm=sigma_mm)


#: The typical robot a plan is judged on: its free parameters off the nominal ones by these standard
#: deviations (length [mm], angle [deg], joint zero offset [deg]; the simulator's defaults), seed 0.
TYPICAL_DEVIATION = (0.5, 0.05, 0.05)


def _typical_robot(model):
    """The nominal model with its free parameters moved by :data:`TYPICAL_DEVIATION` (seeded draw)."""
    rng = np.random.default_rng(0)
    units = np.array(model.params.units)
    sigma = np.where(units == "mm", TYPICAL_DEVIATION[0], np.radians(TYPICAL_DEVIATION[1]))
    return model.with_params(model.params.values + rng.standard_normal(len(sigma)) * sigma * model.params.free)


def calibration_identifiability(model, q, *, tool=(0.0, 0.0, 100.0), free=None):
    """The identifiability verdict ``robocal calibrate`` gives on point measurements at the poses
    ``q`` (N, n): the same analysis (:func:`robocal.calib.solve`: at the start, then again at the
    solution), the same tolerance (:data:`~robocal.calib.identifiability.IDENTIFIABILITY_TOL`), on
    noise-free data of a typical robot (:data:`TYPICAL_DEVIATION`; a real robot's small deviations
    break symmetries the exact nominal geometry has, e.g. a reflector on the joint-6 axis).
    Returns ``(report, jacobian, at)``: the :class:`IdentifiabilityReport`, the Jacobian (3N, n) [mm
    per unit] at the solution, columns in ``problem.names`` order, and ``at = (problem, state)``
    for the Jacobian at other poses (:func:`_jacobian_at`)."""
    from .solve import solve  # solve imports this module's siblings; keep the import local

    m0 = model.replace(T_world_base=np.eye(4))
    T = _typical_robot(m0).fk(q)
    pts = (T[:, :3, 3] + T[:, :3, :3] @ np.asarray(tool, dtype=float))[:, None]
    problem = CalibrationProblem(m0, q, [Target("reflector", point=tuple(tool))], pts, free=free,
                                 base_initial="fit")
    state = problem.initial_state()
    _, J, _ = problem.evaluate(state)
    if J.shape[0] < J.shape[1]:  # fewer measurements than unknowns: calibrate refuses; judge the start
        from .identifiability import analyse_identifiability

        return analyse_identifiability(J, problem.names, problem.blocks), J, (problem, state)
    res = solve(problem, warn=False)  # not catch_warnings: it would change every thread's filters
    return res.identifiability, res.jacobian, (problem, res.state)


def _jacobian_at(at, q) -> np.ndarray:
    """Per-pose prediction Jacobian blocks (M, 3, n) at the poses ``q`` of the typical robot ``at``
    (:func:`calibration_identifiability`): where the plan's covariance was computed."""
    problem, state = at
    _, J = problem.predict_points(state, q=np.asarray(q, dtype=float), jacobian=True)
    return J.reshape(len(q), -1, J.shape[-1])


def _plan_covariance(problem, Jb, idx, sigma_mm, model=None, tool=None, free=None):
    """Identifiability at the poses ``idx`` (the calibration's verdict,
    :func:`calibration_identifiability`), the identifiable columns and their covariance, and the
    typical robot they were computed at."""
    ident, J, at = calibration_identifiability(model, problem.q[idx], tool=tool, free=free)
    cols = [problem.names.index(n) for n in ident.identifiable]
    Jc = J[:, cols]
    return ident, cols, sigma_mm**2 * np.linalg.inv(Jc.T @ Jc), at


def _rms_model_std(J_other, cols, cov) -> float:
    """RMS over poses of sqrt(trace(J C J^T)): the predicted model error [mm] at other poses."""
    Jr = J_other[..., cols]  # (R, 3, c)
    var = np.einsum("rij,jk,rik->r", Jr, cov, Jr)  # trace of J C J^T per pose
    return float(np.sqrt(np.mean(var)))


def predicted_model_std(model, q_plan, q_check, *, tool=(0.0, 0.0, 100.0), free=None, sigma_mm: float = 0.02) -> float:
    """First-order RMS model error [mm] at the poses ``q_check`` (M, n) of a calibration from all of
    ``q_plan`` (N, n) (point measurements with ``sigma_mm`` noise per coordinate, base frame and tool
    point estimated): what :func:`plan_campaign` predicts for the poses it did not choose."""
    q_plan = np.asarray(q_plan, dtype=float)
    problem = _point_problem(model, np.vstack([q_plan, np.asarray(q_check, dtype=float)]), tool, free, sigma_mm)
    Jb = pose_jacobians(problem)
    _, cols, cov, at = _plan_covariance(problem, Jb, np.arange(len(q_plan)), sigma_mm, model, tool, free)
    return _rms_model_std(_jacobian_at(at, q_check), cols, cov)


def plan_campaign(model, q_candidates, count: int, *, tool=(0.0, 0.0, 100.0), free=None, sigma_mm: float = 0.02):
    """Choose ``count`` of ``q_candidates`` (N, n) for a point-measurement calibration of ``model``
    (base frame and the tool point estimated too) and predict its outcome.

    Returns ``{indices, names, std (identifiable variables, first order), covariance,
    identifiable, dropped, holdout_model_std_mm (RMS predicted model error at the candidates not
    chosen), holdout_rms_mm (expected held-out error: model error and noise), problem}``.
    """
    problem = _point_problem(model, q_candidates, tool, free, sigma_mm)
    Jb = pose_jacobians(problem)  # (N, 3, n): prediction derivatives, mm per unit
    sel = select_poses(Jb, count, names=problem.names, blocks=problem.blocks)
    idx = np.asarray(sel["indices"])
    ident, cols, cov, at = _plan_covariance(problem, Jb, idx, sigma_mm, model, tool, free)
    rest = np.setdiff1d(np.arange(len(Jb)), idx)
    holdout = _rms_model_std(_jacobian_at(at, problem.q[rest]), cols, cov) if len(rest) else float("nan")
    return {"indices": idx, "names": list(ident.identifiable), "std": np.sqrt(np.diag(cov)), "covariance": cov,
            "units": [problem.units[c] for c in cols], "identifiable": list(ident.identifiable),
            "dropped": [(d["name"], d["why"]) for d in ident.dropped], "holdout_model_std_mm": holdout,
            "holdout_rms_mm": float(np.sqrt(holdout**2 + 3 * sigma_mm**2)) if len(rest) else float("nan"),
            "problem": problem, "typical": at}


def predicted_workspace_accuracy(model, plan: dict, q_ref, *, tool=(0.0, 0.0, 100.0)) -> dict:
    """First-order accuracy of the model calibrated by ``plan`` (:func:`plan_campaign`) over the
    reference poses ``q_ref`` (R, n) spread over the working range: a noise-free criterion (it
    scales with the instrument noise but does not add it).

    Returns ``{rms_mm, relative_spread}``: the RMS over the reference poses of sqrt(trace J C J^T)
    [mm], and the relative standard deviation of one real calibration's RMS error around it
    (e ~ N(0, C) gives the squared error e^T A e with A = mean J^T J: mean tr(AC), variance
    2 tr((AC)^2); the RMS spreads half as much, relatively). Two plans whose accuracies differ by
    less than this cannot be told apart by one campaign each.
    """
    q_ref = np.asarray(q_ref, dtype=float)
    problem = plan["typical"][0]
    cols = [problem.names.index(n) for n in plan["names"]]
    Jr = _jacobian_at(plan["typical"], q_ref)[..., cols]
    C = plan["covariance"]
    A = np.einsum("rij,rik->jk", Jr, Jr) / len(Jr)
    AC = A @ C
    tr = float(np.trace(AC))
    return {"rms_mm": float(np.sqrt(tr)), "relative_spread": float(0.5 * np.sqrt(2.0 * np.trace(AC @ AC)) / tr)}
