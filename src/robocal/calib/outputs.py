"""What a calibration gives the user: every number as plain data, and corrected joint targets
("program filtering").

Pure functions (no files, no plots): the workflows write what these return.

* :func:`result_to_dict` -- a JSON-ready dict of a :class:`~robocal.calib.CalibrationResult`:
  parameters with names, units, initial and final values, change, standard deviation and
  identifiability; base frame(s); target points; residual statistics before and after; solver
  state; dropped parameters with the reason; outliers.
  (Predicted position uncertainty at any configuration: :mod:`robocal.calib.uncertainty`.)
* :func:`corrected_joint_targets` -- the joints to command so that the *real* (calibrated) robot
  reaches Cartesian targets, and the "filtered" Cartesian targets a controller running the
  nominal model needs to produce those joints.

Units: lengths mm, angles rad everywhere in the returned data (each parameter carries its unit).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..kinematics.ik import ik_numeric, pose_errors
from ..kinematics.model import RobotModel
from ..metrics import error_statistics
from ..transforms import euler_from_matrix

__all__ = ["RESULT_FORMAT", "result_to_dict", "problem_result_dict", "json_ready", "CorrectedTargets", "corrected_joint_targets"]

#: ``format`` value of the dict returned by :func:`result_to_dict` (and of ``result.json``).
RESULT_FORMAT = "robocal-calibration-result/1"


def json_ready(obj):
    """``obj`` with numpy arrays / scalars turned into lists / numbers and NaN or inf into ``None``
    (strict JSON has no NaN)."""
    if isinstance(obj, dict):
        return {str(k): json_ready(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [json_ready(v) for v in obj]
    if isinstance(obj, np.ndarray):
        if obj.dtype.kind in "biu" or (obj.dtype.kind == "f" and np.isfinite(obj).all()):
            return obj.tolist()  # already plain numbers (a big campaign's per-pose arrays: no walk per element)
        return json_ready(obj.tolist())
    if isinstance(obj, (np.bool_, bool)):
        return bool(obj)
    if isinstance(obj, (np.integer, int)):
        return int(obj)
    if isinstance(obj, (np.floating, float)):
        x = float(obj)
        return x if math.isfinite(x) else None
    return obj


def _stats(e):
    return None if e is None or np.size(e) == 0 else error_statistics(np.asarray(e, dtype=float))


def result_to_dict(result, problem, *, nominal: RobotModel | None = None, pose_ids=None, validation=None,
                   metadata=None, include_covariance: bool = True) -> dict:
    """Every number of a calibration as a JSON-ready dict (``format`` = :data:`RESULT_FORMAT`).

    result: the :class:`~robocal.calib.CalibrationResult` of ``solve(problem)``.
    nominal: the model before calibration (default ``problem.model``), for the full parameter table.
    pose_ids: names of the problem's poses (default ``"0" .. "N-1"``), used for per-point residuals
        and outliers.
    validation: optional dict (e.g. held-out statistics) stored under ``validation``.
    metadata: optional dict stored under ``metadata`` (input files, options, seed).
    include_covariance: add the covariance matrix of the identified variables.

    Keys: ``format, robot, units, parameters`` (every state variable: name, unit, block,
    initial, value, change, std, identifiable), ``model_parameters`` (every kinematic parameter of
    the robot: nominal, calibrated, change, estimated, identifiable, std), ``bases`` (per station:
    ``T_instrument_base`` 4x4 and its xyz / rpy), ``targets`` (point in the end-effector frame and
    its std), ``residuals`` (statistics before / after and per measured point), ``solver``,
    ``identifiability`` (identifiable names, dropped names with ``why``), ``outliers``,
    ``covariance``, ``validation``, ``metadata``. Angles rad, lengths mm; NaN becomes ``null``.
    """
    nominal = problem.model if nominal is None else nominal
    N = problem.n_poses
    pose_ids = [str(i) for i in range(N)] if pose_ids is None else [str(p) for p in pose_ids]
    if len(pose_ids) != N:
        raise ValueError(f"pose_ids: {len(pose_ids)} names for {N} poses")
    params = [dict(row, block=str(block)) for row, block in zip(result.parameter_table(), problem.blocks)]
    outliers = [dict(o, pose_id=pose_ids[o["pose"]] if 0 <= o["pose"] < N else None) for o in result.outliers]
    out = {
        "format": RESULT_FORMAT,
        "robot": nominal.name,
        "units": {"length": "mm", "angle": "rad",
                  "frames": "T_a_b is frame b written in frame a; 'instrument' is the measurement frame"},
        "parameters": params,
        "model_parameters": _model_parameter_rows(result, nominal, result.state.params),
        "bases": _base_rows(result, problem),
        "targets": _target_rows(result, problem, nominal),
        "residuals": _residual_summary(result, problem, pose_ids),
        "solver": dict(_solver_dict(result, N), point_sigma_mm=problem.point_sigma),
        "identifiability": _identifiability_dict(result.identifiability),
        "outliers": outliers,
    }
    if include_covariance:
        out["covariance"] = _covariance_dict(result)
    if validation is not None:
        out["validation"] = validation
    if metadata is not None:
        out["metadata"] = metadata
    return json_ready(out)


def problem_result_dict(result, problem, *, nominal: RobotModel, calibrated_params, metadata=None,
                        include_covariance: bool = True) -> dict:
    """The parts of :func:`result_to_dict` that any :class:`~robocal.calib.core.Problem` with a
    robot geometry has: ``format, robot, units, parameters, model_parameters, solver,
    identifiability, outliers, covariance, metadata``. calibrated_params (P,): the model's
    parameter vector at the solution [mm | rad]. Methods add their own sections (frames,
    targets, residuals) to the returned dict."""
    params = [dict(row, block=str(block)) for row, block in zip(result.parameter_table(), problem.blocks)]
    out = {
        "format": RESULT_FORMAT, "robot": nominal.name,
        "units": {"length": "mm", "angle": "rad", "frames": "T_a_b is frame b written in frame a"},
        "parameters": params,
        "model_parameters": _model_parameter_rows(result, nominal, calibrated_params),
        "solver": _solver_dict(result, problem.n_poses),
        "identifiability": _identifiability_dict(result.identifiability),
        "outliers": list(result.outliers),
    }
    if include_covariance:
        out["covariance"] = _covariance_dict(result)
    if metadata is not None:
        out["metadata"] = metadata
    return json_ready(out)


def _solver_dict(result, n_poses) -> dict:
    return {"iterations": result.iterations, "converged": result.converged, "reason": result.reason,
            "rank": result.rank, "n_variables": len(result.names), "condition_number": result.condition_number,
            "sigma0": result.sigma0, "n_poses": n_poses, "n_residuals": int(np.size(result.residuals_after))}


def _model_parameter_rows(result, nominal, cal) -> list:
    """Every kinematic parameter of the robot, estimated or not: nominal, calibrated (``cal`` (P,)),
    change, std."""
    ident = set(result.identifiability.identifiable)
    index = {n: i for i, n in enumerate(result.names)}
    rows = []
    for i, name in enumerate(nominal.params.names):
        j = index.get(name)
        rows.append({
            "name": name, "unit": nominal.params.units[i], "nominal": float(nominal.params.values[i]),
            "calibrated": float(cal[i]), "change": float(cal[i] - nominal.params.values[i]),
            "estimated": name in ident, "free_in_problem": j is not None,
            "std": float(result.std[j]) if j is not None else None,
        })
    return rows


def _base_rows(result, problem) -> list:
    """Per station: the identified ``T_instrument_base`` (4, 4) [mm], its xyz and rpy, the start."""
    rows = []
    for g in range(problem.n_stations):
        T = result.state.bases[g]
        rows.append({
            "name": "base" if problem.n_stations == 1 else f"base{g}",
            "estimated": bool(problem.estimate_base),
            "T_instrument_base": T, "xyz_mm": T[:3, 3], "rpy_rad": euler_from_matrix(T[:3, :3], "rpy"),
            "initial_T_instrument_base": problem.base_initial[g],
            "n_poses": int(np.sum(problem.stations == g)),
        })
    return rows


def _target_rows(result, problem, nominal) -> list:
    """Per target: the point in its end-effector frame [mm], the start and the std."""
    index = {n: i for i, n in enumerate(result.names)}
    rows = []
    for k, t in enumerate(problem.targets):
        cols = [index.get(f"{t.name}.{c}") for c in "xyz"]
        rows.append({
            "name": t.name, "end_effector": nominal.end_effectors[int(problem.ee_of_target[k])].name,
            "point_mm": result.state.targets[k], "initial_mm": list(t.point), "estimated": bool(t.free),
            "std_mm": [float(result.std[c]) if c is not None else None for c in cols],
        })
    return rows


def _residual_summary(result, problem, pose_ids) -> dict:
    """Position-error statistics before/after [mm] and the error of every measured point."""
    residuals = {"unit": "mm", "before": _stats(result.point_errors_before), "after": _stats(result.point_errors_after),
                 "rms_before": result.rms_before, "rms_after": result.rms_after}
    if problem.points is not None and result.point_errors_after is not None:
        pose_idx, target_idx = np.nonzero(problem.point_mask)  # row order of the point residuals
        residuals["per_point"] = {
            "pose": [pose_ids[p] for p in pose_idx],
            "target": [problem.targets[k].name for k in target_idx],
            "before": result.point_errors_before, "after": result.point_errors_after,
        }
    return residuals


def _identifiability_dict(report) -> dict:
    dropped = [{"name": d["name"], "why": d["why"],
                "trades_off_with": [{"name": n, "coefficient": c} for n, c in d.get("trades_off_with", [])]}
               for d in report.dropped]
    return {"identifiable": list(report.identifiable), "dropped": dropped,
            "rank": report.rank, "condition_number": report.condition_number}


def _covariance_dict(result) -> dict:
    """Covariance of the identified variables with a finite variance (names, units, matrix)."""
    ident = set(result.identifiability.identifiable)
    act = [i for i, n in enumerate(result.names) if n in ident and np.isfinite(result.covariance[i, i])]
    return {"names": [result.names[i] for i in act], "units": [result.units[i] for i in act],
            "matrix": result.covariance[np.ix_(act, act)]}


# ---------------------------------------------------------------------------------------------
# corrected joint targets
# ---------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class CorrectedTargets:
    """Joint targets corrected for the calibrated kinematics.

    q: (N, n_ctrl) joints to command [rad | mm]: ``calibrated.fk(q) = T_target``.
    q_nominal: (N, n_ctrl) the nominal model's solution (what an uncorrected controller would use).
    T_target: (N, 4, 4) the targets (for position-only targets the orientation is the one the
        nominal solution has).
    T_filtered: (N, 4, 4) the nominal model's pose at ``q`` in the robot base frame: the Cartesian
        targets to send to a controller that runs the nominal model, so that it commands ``q``.
    T_filtered_world: (N, 4, 4) the same in the targets' frame (nominal model at the calibrated
        base); ``T_filtered_world - T_target`` is the correction the calibration applies.
    converged: (N,) bool; position_error_mm (N,), rotation_error_rad (N,): remaining error of
        ``calibrated.fk(q)`` against ``T_target``.
    report: one dict per target (index, converged, status, iterations, errors, nominal solver
        status, joint change, correction of the Cartesian target, within limits).
    position_only: the targets had no orientation.
    """

    q: np.ndarray
    q_nominal: np.ndarray
    T_target: np.ndarray
    T_filtered: np.ndarray
    T_filtered_world: np.ndarray
    converged: np.ndarray
    position_error_mm: np.ndarray
    rotation_error_rad: np.ndarray
    report: list
    position_only: bool

    @property
    def all_converged(self) -> bool:
        return bool(np.all(self.converged))

    def summary(self) -> str:
        n, ok = len(self.converged), int(np.sum(self.converged))
        shift = np.linalg.norm(self.T_filtered_world[:, :3, 3] - self.T_target[:, :3, 3], axis=1)
        return (f"{ok}/{n} targets corrected; worst remaining error {self.position_error_mm.max(initial=0.0):.2e} mm; "
                f"Cartesian corrections up to {shift.max(initial=0.0):.4f} mm")


def _reference_joints(model: RobotModel) -> np.ndarray:
    lo, hi = model.limits[:, 0], model.limits[:, 1]
    return np.where(np.isfinite(lo) & np.isfinite(hi), (lo + hi) / 2.0, np.where(np.isfinite(lo), lo,
                                                                                  np.where(np.isfinite(hi), hi, 0.0)))


def _nominal_seed(nominal, T, q_ref, end_effector):
    """Closest valid closed-form branch to ``q_ref`` (N, n) where the nominal model is of the OPW
    class, else NaN rows."""
    q = np.full((len(T), nominal.n_joints), np.nan)
    if end_effector not in (None, 0, nominal.end_effectors[0].name):
        return q
    try:
        from ..kinematics.ik_analytic import ik_analytic, is_analytic

        if not is_analytic(nominal):
            return q
        q_all, valid = ik_analytic(nominal, T, within_limits=True)
    except Exception:  # any model the closed form does not cover: the numeric solver seeds instead
        return q
    dist = np.where(valid, np.linalg.norm(np.nan_to_num(q_all - q_ref[:, None]), axis=-1), np.inf)
    best = np.argmin(dist, axis=1)
    ok = np.isfinite(dist[np.arange(len(T)), best])
    q[ok] = q_all[np.flatnonzero(ok), best[ok]]
    return q


def _ik(model, T, q0, **kw):
    """``ik_numeric`` over all targets: (q, converged, status, iterations, position error)."""
    res = ik_numeric(model, T, q0, **kw)
    return (np.atleast_2d(res.q), np.atleast_1d(res.converged), np.atleast_1d(res.status),
            np.atleast_1d(res.iterations), np.atleast_1d(res.position_error_mm))


def _ik_with_restarts(model, T, q0, n_restarts, **kw):
    """:func:`_ik` from ``q0``; targets that do not converge are tried again from deterministic
    (seeded) starting points spread over the joint ranges, keeping the best outcome."""
    q, conv, status, iters, err = _ik(model, T, q0, **kw)
    if n_restarts and not np.all(conv):
        rng = np.random.default_rng(0)  # fixed: the same targets always give the same joints
        lo, hi = model.limits[:, 0], model.limits[:, 1]
        lo = np.where(np.isfinite(lo), lo, -np.pi)
        hi = np.where(np.isfinite(hi), hi, np.pi)
        for _ in range(n_restarts):
            todo = np.flatnonzero(~conv)
            if todo.size == 0:
                break
            start = rng.uniform(lo, hi, (todo.size, model.n_joints))
            q2, c2, s2, i2, e2 = _ik(model, T[todo], start, **kw)
            better = c2 | (e2 < err[todo])
            sel = todo[better]
            q[sel], conv[sel], status[sel], iters[sel], err[sel] = q2[better], c2[better], s2[better], \
                i2[better], e2[better]
    return q, conv, status, iters, err


def corrected_joint_targets(calibrated: RobotModel, nominal: RobotModel, targets, rotations=None, *,
                            q_seed=None, end_effector=None, frame: str = "world", tol_mm: float = 1e-7,
                            tol_rad: float = 1e-10, max_iterations: int = 200,
                            n_restarts: int = 16, reach=None) -> CorrectedTargets:
    """Joints that put the calibrated robot exactly on Cartesian targets ("program filtering").

    calibrated: the identified model (how the robot really moves); nominal: the model its
        controller runs. Both must have the same controller joints.
    frame: ``"world"``: targets are in the calibrated model's world frame (``calibrated.fk``; for
        a model written by ``robocal calibrate`` that is the measurement instrument's frame) and
        the nominal model is placed at the calibrated base (a controller knows no instrument
        frame); ``"base"``: targets are in the robot base frame (both models with identity base).
    targets: (N, 4, 4) poses, or (N, 3) positions [mm] with optional ``rotations`` (N, 3, 3).
        Positions without rotations are position-only targets: the orientation becomes the one the
        nominal solution has (the tool keeps the orientation the nominal program would give it).
    q_seed: optional (N, n_ctrl) or (n_ctrl,) starting joints (e.g. the taught joints) for the
        nominal IK; otherwise the closed-form branch nearest the middle of the joint ranges
        (OPW-class nominal models) or a numeric solve from there.

    The nominal solution seeds ``ik_numeric`` on the calibrated model (so the corrected joints stay
    on the same branch). reach: optional ``reach(model, q) -> (N, 4, 4)``, the poses a deflecting
    robot really reaches at the commanded joints (gravity and payload;
    :meth:`robocal.calib.elastic.ElasticDescription.reached_poses`): the targets given to the rigid
    solution are then moved by the remaining error until the deflected robot lands on the true
    targets (a few fixed-point passes). Returns :class:`CorrectedTargets`.
    """
    if tuple(calibrated.controller_joints) != tuple(nominal.controller_joints):
        raise ValueError(f"calibrated and nominal models have different controller joints: "
                         f"{calibrated.controller_joints} vs {nominal.controller_joints}")
    if frame not in ("world", "base"):
        raise ValueError(f"frame: expected 'world' or 'base', got {frame!r}")
    nominal_base = nominal.replace(T_world_base=np.eye(4))  # the controller's own frame
    if frame == "base":
        calibrated = calibrated.replace(T_world_base=np.eye(4))
    nominal = nominal.replace(T_world_base=calibrated.T_world_base)
    T, position_only = _target_poses(targets, rotations)
    N, n = len(T), nominal.n_joints
    if q_seed is not None:
        q_ref = np.array(np.broadcast_to(np.asarray(q_seed, dtype=float), (N, n)), copy=True)
    else:
        q_ref = np.tile(_reference_joints(nominal), (N, 1))

    # 1. nominal solution (what the uncorrected controller would command)
    q0 = q_ref.copy()
    if q_seed is None and not position_only:
        seed = _nominal_seed(nominal, T, q_ref, end_effector)
        have = np.all(np.isfinite(seed), axis=1)
        q0[have] = seed[have]
    kw = dict(end_effector=end_effector, tol_mm=tol_mm, tol_rad=tol_rad, max_iterations=max_iterations)
    q_nom, nom_conv, nom_status, _, nom_err = _ik_with_restarts(nominal, T, q0, n_restarts,
                                                                position_only=position_only, **kw)
    if position_only:
        T[:, :3, :3] = nominal.fk(q_nom, end_effector)[:, :3, :3]

    # 2. the calibrated model from there (same branch)
    q, conv, status, iters = _calibrated_solution(calibrated, T, q_nom, n_restarts, position_only, kw)
    if reach is None:
        T_reached = calibrated.fk(q, end_effector)
    else:  # aim the rigid solution so that the deflected robot lands on the target
        T_aim = T.copy()
        for _ in range(5):
            T_reached = reach(calibrated, q)
            T_aim[:, :3, 3] += T[:, :3, 3] - T_reached[:, :3, 3]
            T_aim[:, :3, :3] = T[:, :3, :3] @ np.swapaxes(T_reached[:, :3, :3], 1, 2) @ T_aim[:, :3, :3]
            q, conv, status, iters = _calibrated_solution(calibrated, T_aim, q, n_restarts, position_only, kw)
        T_reached = reach(calibrated, q)
    dp, dr = pose_errors(T_reached, T)
    pos_err, rot_err = np.linalg.norm(dp, axis=1), np.linalg.norm(dr, axis=1)
    T_filtered_world = nominal.fk(q, end_effector)
    T_filtered = nominal_base.fk(q, end_effector)
    dT, dR = pose_errors(T, T_filtered_world)
    within = calibrated.within_limits(q)
    report = _correction_rows(conv, status, iters, pos_err, rot_err, nom_conv, nom_status, nom_err, q, q_nom, dT, dR,
                              within)
    return CorrectedTargets(q=q, q_nominal=q_nom, T_target=T, T_filtered=T_filtered,
                            T_filtered_world=T_filtered_world, converged=conv,
                            position_error_mm=pos_err, rotation_error_rad=rot_err, report=report,
                            position_only=position_only)


def _target_poses(targets, rotations):
    """(N, 4, 4) target poses [mm] and whether they are position-only, from (N, 4, 4) poses or
    (N, 3) positions with optional (N, 3, 3) rotations."""
    t = np.asarray(targets, dtype=float)
    if t.ndim == 2 and t.shape == (4, 4) and rotations is None:
        t = t[None]
    if t.ndim == 3 and t.shape[1:] == (4, 4):
        if rotations is not None:
            raise ValueError("rotations: give orientations either in the 4x4 targets or as rotations, not both")
        T = t.copy()
        position_only = False
    elif t.ndim == 2 and t.shape[1] == 3:
        T = np.tile(np.eye(4), (len(t), 1, 1))
        T[:, :3, 3] = t
        position_only = rotations is None
        if not position_only:
            R = np.asarray(rotations, dtype=float)
            if R.shape != (len(t), 3, 3):
                raise ValueError(f"rotations: expected shape ({len(t)}, 3, 3), got {R.shape}")
            T[:, :3, :3] = R
    else:
        raise ValueError(f"targets: expected (N, 4, 4) poses or (N, 3) positions [mm], got shape {t.shape}")
    if not np.all(np.isfinite(T)):
        raise ValueError("targets: contain NaN or infinite values")
    return T, position_only


def _calibrated_solution(calibrated, T, q_nom, n_restarts, position_only, kw):
    """Joints (N, n) on the calibrated model from the nominal solution (same branch); position-only
    and restarted solves for the targets the first pass misses. Returns (q, conv, status, iters)."""
    q, conv, status, iters, _ = _ik(calibrated, T, q_nom, **kw)
    if position_only and not np.all(conv):
        # near a singularity the nominal orientation may be out of the calibrated robot's reach:
        # then the position alone is met (the orientation stays as close as the solver leaves it)
        todo = np.flatnonzero(~conv)
        q2, c2, s2, i2, _ = _ik(calibrated, T[todo], q_nom[todo], position_only=True, **kw)
        sel = todo[c2]
        q[sel], conv[sel], iters[sel] = q2[c2], True, i2[c2]
        status = status.astype(object)
        status[sel] = "converged (position only)"
    if not np.all(conv):  # last resort: other starting points (may land on another branch)
        todo = np.flatnonzero(~conv)
        q2, c2, s2, i2, _ = _ik_with_restarts(calibrated, T[todo], q_nom[todo], n_restarts, **kw)
        q[todo], conv[todo], iters[todo] = q2, c2, i2
        status = status.astype(object)
        status[todo] = s2
    return q, conv, status, iters


def _correction_rows(conv, status, iters, pos_err, rot_err, nom_conv, nom_status, nom_err, q, q_nom, dT, dR,
                     within) -> list:
    """One dict per target: convergence, remaining error, joint change and Cartesian correction."""
    report = []
    for i in range(len(q)):
        report.append({
            "index": i, "converged": bool(conv[i]), "status": str(status[i]), "iterations": int(iters[i]),
            "position_error_mm": float(pos_err[i]), "rotation_error_rad": float(rot_err[i]),
            "nominal_converged": bool(nom_conv[i]), "nominal_status": str(nom_status[i]),
            "nominal_position_error_mm": float(nom_err[i]),
            "joint_change": (q[i] - q_nom[i]).tolist(),
            "max_joint_change": float(np.max(np.abs(q[i] - q_nom[i]))),
            "cartesian_correction_mm": float(np.linalg.norm(dT[i])),
            "orientation_correction_rad": float(np.linalg.norm(dR[i])),
            "within_limits": bool(within[i]),
        })
    return report
