"""Probing a controller's hidden model from (joints, pose it computes) pairs, and model diffs.

:func:`probe_fit` fits the well-conditioned MDH + beta form of a nominal robot
(:func:`robocal.kinematics.remodel.well_conditioned_mdh`) to the flange poses a controller
computed for known joint values (no instrument: :mod:`robocal.io.controller_pairs`). The base is
the controller's own base frame, so nothing but the chain is free. The parameters held are the
convention's: ``d`` of a frame on an axis parallel to the next (Hayati) and ``beta`` after a pair
of non-parallel axes (common normal) -- the same convention ``controller import ur`` writes, so
the two robot files compare parameter by parameter. :func:`model_diff` compares two models' TCP
over the working range.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from ...calib.sanity import Verdict
from ...io.controller_pairs import CONTROLLERS, read_probe_pairs
from ...kinematics.links import Link, frame_from_xyz_rpy
from ...kinematics.model import EndEffector, RobotModel
from ...kinematics.remodel import PARALLEL_SIN, RemodelError, model_axes, well_conditioned_mdh
from ...metrics import error_statistics
from ...transforms import euler_from_matrix, rotvec_from_matrix
from .models import ControllerInputError, load_nominal, random_joints

__all__ = ["probe_fit", "model_diff", "probe_start_model", "LEVER_MM"]

#: Lever arm [mm] that turns a rotation residual [rad] into a length for the joint least squares.
LEVER_MM = 1000.0


def probe_start_model(nominal: RobotModel) -> RobotModel:
    """The nominal robot in the well-conditioned MDH + beta form (identical FK), the fit's start."""
    try:
        P, U, T = model_axes(nominal)
        return well_conditioned_mdh(P, U, T, nominal, name=f"{nominal.name}_probed", title=nominal.title,
                                    source=nominal.source)
    except RemodelError as exc:
        raise ControllerInputError(f"{nominal.name}: {exc}") from None


def _constant_offset(model, q, T_meas) -> np.ndarray:
    """The mean constant transform (4, 4) from the model's flange to the reported one."""
    T = np.linalg.inv(model.T_world_base)[None] @ model.fk(q)
    D = np.linalg.inv(T) @ T_meas
    U, _, Vt = np.linalg.svd(D[:, :3, :3].sum(axis=0))
    R = U @ np.diag([1.0, 1.0, np.sign(np.linalg.det(U @ Vt))]) @ Vt
    out = np.eye(4)
    out[:3, :3], out[:3, 3] = R, D[:, :3, 3].mean(axis=0)
    return out


def _with_flange_frame(model: RobotModel, T_ee) -> RobotModel:
    """The chain with the flange frame as a fixed ``frame`` link (its xyz/rpy become parameters)."""
    xyz = np.asarray(T_ee, float)[:3, 3]
    rpy = euler_from_matrix(np.asarray(T_ee, float)[:3, :3], "rpy")
    p = {"x": xyz[0], "y": xyz[1], "z": xyz[2], "roll": rpy[0], "pitch": rpy[1], "yaw": rpy[2]}
    link = Link("flange_frame", "fixed", "frame", {k: float(v) for k, v in p.items()}, len(model.links) - 1)
    return model.replace(links=list(model.links) + [link],
                         end_effectors=[EndEffector("flange", len(model.links), np.eye(4))])


def _convention_free(model: RobotModel) -> np.ndarray:
    """Free mask (P,) of the convention: hold d of frames before a parallel axis, beta after a
    non-parallel pair, and a flange frame's z and yaw (they repeat the last joint's d and theta)."""
    z = [np.asarray(F[:3, 2], float) for F in model.link_frames(np.zeros(model.n_joints))]
    n = len(z)
    parallel = [np.linalg.norm(np.cross(z[i], z[i + 1])) < PARALLEL_SIN for i in range(n - 1)]
    free = np.ones(len(model.params), dtype=bool)
    for k, link in enumerate(model.links):
        if link.joint_type == "fixed":
            for pname in ("z", "yaw"):
                free[model.params.index(f"{pname}{k + 1}")] = False
    for i in range(n):
        if i + 1 < n and parallel[i]:
            free[model.params.index(f"d{i + 1}")] = False
        if i == 0 or not parallel[i - 1]:
            free[model.params.index(f"beta{i + 1}")] = False
    return free


def _residuals(model, params, q, T_meas, sp, sr):
    T = model.kinematics_with(q, params, T_world_base=np.eye(4), end_effectors=[0])[0][:, 0]
    dp = T[:, :3, 3] - T_meas[:, :3, 3]
    dr = rotvec_from_matrix(T[:, :3, :3] @ np.swapaxes(T_meas[:, :3, :3], 1, 2))
    return dp, dr, np.concatenate([dp / sp, dr / sr], axis=1).ravel()


def _jacobian(model, params, q, free_idx, sp, sr):
    m = model.with_params(params)
    J = m.identification_jacobian(q)[:, :, free_idx]  # (N, 6, F): point rows mm, rotation rows rad
    J[:, :3] /= sp
    J[:, 3:] /= sr
    return J.reshape(-1, len(free_idx))


def _identifiable(J, names, rcond=1e-9):
    """Columns kept by pivoted QR of the column-scaled Jacobian; the others are held."""
    from scipy.linalg import qr

    scale = np.linalg.norm(J, axis=0)
    scale[scale == 0] = 1.0
    _, R, piv = qr(J / scale, mode="economic", pivoting=True)
    d = np.abs(np.diag(R))
    keep = d > rcond * d[0]
    return np.sort(piv[keep]), [names[k] for k in piv[~keep]]


def _pose_error_stats(dp, dr) -> dict:
    return {"position_mm": error_statistics(dp), "rotation_deg": error_statistics(np.degrees(np.linalg.norm(dr, axis=1)))}


def probe_fit(nominal_name, pairs_path, *, controller=None, noise_mm=0.01, noise_deg=0.001, flange="auto",
              max_iterations=50, max_pairs=2000) -> dict:
    """Fit the controller's model to probe pairs; see the module docstring.

    ``flange``: ``fixed`` keeps ROBOT's flange frame on joint 6 (UR: the flange is on the axis);
    ``free`` also fits the flange frame's offset and tilt from joint 6's axis (a controller whose
    flange convention differs from the robot file's, e.g. KUKA's x-forward flange); ``auto`` frees
    it when the pairs differ from ROBOT by a constant flange transform of more than 2 mm / 0.5 deg.

    ``noise_mm`` / ``noise_deg``: the resolution of the reported poses (position [mm], orientation
    [deg]); they weight the residuals and set the tolerances of the verdicts.
    Returns a dict: ``model`` (fitted, kind mdh), ``start`` (nominal in the same form),
    ``pairs``, ``nominal_residual`` / ``fit_residual`` (statistics, mm and deg), ``runs_nominal``
    (bool), ``changes`` (per free parameter: value, change, sigma, unit, significant), ``held``
    (names), ``verdict``, ``iterations``.
    """
    from scipy.optimize import least_squares

    nominal = load_nominal(nominal_name)
    pairs = read_probe_pairs(pairs_path, controller, nominal.n_joints)
    if len(pairs.q) > max_pairs:  # a long recording: evenly spaced rows are enough
        keep_rows = np.unique(np.linspace(0, len(pairs.q) - 1, max_pairs).round().astype(int))
        pairs = type(pairs)(pairs.q[keep_rows], pairs.T[keep_rows], pairs.index[keep_rows], pairs.controller,
                            pairs.origin)
    if len(pairs.q) < 10:
        raise ControllerInputError(f"{pairs_path}: {len(pairs.q)} pairs; probing needs at least 10 (50+ recommended)")
    if flange not in ("auto", "fixed", "free"):
        raise ControllerInputError(f"flange: {flange!r}, expected auto, fixed or free")
    start = probe_start_model(nominal)
    sp = max(noise_mm, 1e-6) / math.sqrt(12.0)
    sr = math.radians(max(noise_deg, 1e-9)) / math.sqrt(12.0)
    q, T_meas = pairs.q, pairs.T
    dp0, dr0, _ = _residuals(start, start.params.values, q, T_meas, sp, sr)
    offset = _constant_offset(start, q, T_meas)
    off_mm = float(np.linalg.norm(offset[:3, 3]))
    off_deg = float(np.degrees(np.linalg.norm(rotvec_from_matrix(offset[:3, :3]))))
    flange_free = flange == "free" or (flange == "auto" and (off_mm > 2.0 or off_deg > 0.5))
    fit_model = _with_flange_frame(start, start.end_effectors[0].T_link_ee @ offset) if flange_free else start
    conv = _convention_free(fit_model)
    idx0 = np.flatnonzero(conv)
    names = list(fit_model.params.names)
    J0 = _jacobian(fit_model, fit_model.params.values, q, idx0, sp, sr)
    keep, dropped = _identifiable(J0, [names[k] for k in idx0])
    free_idx = idx0[keep]
    x0 = fit_model.params.values.copy()
    x_nominal = np.concatenate([start.params.values, x0[len(start.params):]])

    def fun(x):
        p = x0.copy()
        p[free_idx] = x
        return _residuals(fit_model, p, q, T_meas, sp, sr)[2]

    def jac(x):
        p = x0.copy()
        p[free_idx] = x
        return _jacobian(fit_model, p, q, free_idx, sp, sr)

    res = least_squares(fun, x0[free_idx], jac=jac, method="lm", xtol=1e-15, ftol=1e-15, gtol=1e-15,
                        max_nfev=max_iterations * (len(free_idx) + 1))
    params = x0.copy()
    params[free_idx] = res.x
    fitted = start.with_params(params[:len(start.params)])
    if flange_free:
        p7 = dict(zip(fit_model.params.names[len(start.params):], params[len(start.params):]))
        n7 = len(fit_model.links)
        T_ee = frame_from_xyz_rpy([p7[f"x{n7}"], p7[f"y{n7}"], p7[f"z{n7}"]],
                                  [p7[f"roll{n7}"], p7[f"pitch{n7}"], p7[f"yaw{n7}"]])
        fitted = fitted.replace(end_effectors=[EndEffector("flange", len(start.links) - 1, T_ee)])
    fitted = fitted.replace(
        name=f"{nominal.name}_probed", title=f"{nominal.title or nominal.name} (controller model from probing)",
        source=f"robocal controller probe of {Path(str(pairs_path)).name} ({len(q)} {pairs.controller} pairs, "
               f"{CONTROLLERS[pairs.controller]['function']}) on the nominal {nominal.name}")
    dp1, dr1, r1 = _residuals(fit_model, params, q, T_meas, sp, sr)
    dof = max(len(r1) - len(free_idx), 1)
    s2 = max(float(r1 @ r1) / dof, 1.0)  # residual variance in units of the rounding sigma (at least 1)
    J = jac(res.x)
    try:
        cov = np.linalg.inv(J.T @ J) * s2
        sig = np.sqrt(np.clip(np.diag(cov), 0, None))
    except np.linalg.LinAlgError:
        sig = np.full(len(free_idx), np.nan)
    changes = {}
    n_chain = len(start.params)
    for k, col in enumerate(free_idx):
        unit = fit_model.params.units[col]
        name = names[col] if col < n_chain else "flange." + names[col].rstrip("0123456789")
        delta = float(params[col] - x_nominal[col])
        if unit == "rad":
            delta = (delta + math.pi) % (2 * math.pi) - math.pi
        tiny = 1e-4 if unit == "mm" else 1e-7
        sigma = float(sig[k]) if np.isfinite(sig[k]) else None
        changes[name] = {"value": float(params[col]), "change": delta, "sigma": sigma, "unit": unit,
                         "significant": bool(abs(delta) > max(3 * (sigma if sigma is not None else 0.0), tiny))}
    nominal_res = _pose_error_stats(dp0, dr0)
    fit_res = _pose_error_stats(dp1, dr1)
    # a reported pose rounded to the resolution is off by at most half a step per coordinate
    tol_mm = noise_mm * math.sqrt(3) / 2 * 1.05 + 1e-9
    tol_deg = noise_deg * math.sqrt(3) / 2 * 1.05 * 2 + 1e-12
    runs_nominal = nominal_res["position_mm"]["max"] <= tol_mm and nominal_res["rotation_deg"]["max"] <= tol_deg
    checks, reasons = {}, []

    def gate(name, value, limit, unit, reason):
        ok = bool(math.isfinite(value) and value <= limit)
        checks[name] = {"value": float(value), "limit": float(limit), "unit": unit, "passed": ok}
        if not ok:
            reasons.append(reason)

    gate("fit_position_max", fit_res["position_mm"]["max"], 5 * tol_mm, "mm",
         f"after the fit the controller's poses still differ by up to {fit_res['position_mm']['max']:.4f} mm (the "
         f"pose resolution allows {tol_mm:.4f} mm): the controller's model is not a rigid chain of this robot "
         "(a non-geometric compensation, another robot type, or pairs whose joints and poses do not belong together)")
    gate("fit_rotation_max", fit_res["rotation_deg"]["max"], 5 * tol_deg, "deg",
         f"after the fit the orientations still differ by up to {fit_res['rotation_deg']['max']:.5f} deg")
    verdict = Verdict(tuple(reasons), checks)
    return {"model": fitted, "start": start, "nominal": nominal, "pairs": pairs, "nominal_residual": nominal_res,
            "fit_residual": fit_res, "runs_nominal": bool(runs_nominal), "changes": changes, "held": dropped,
            "held_by_convention": [names[k] for k in np.flatnonzero(~conv) if k < n_chain], "verdict": verdict,
            "flange": {"free": bool(flange_free), "constant_offset_mm": off_mm, "constant_offset_deg": off_deg},
            "iterations": int(res.nfev), "converged": bool(res.status > 0), "tolerance": {"mm": tol_mm,
                                                                                          "deg": tol_deg}}


# ------------------------------------------------------------------------------------------ diff
def _bins(values, edges):
    return np.clip(np.searchsorted(edges, values, side="right") - 1, 0, len(edges) - 2)


def _best_fit_rigid(src, dst):
    """Rotation R (3, 3) and shift t (3,) minimising |R src + t - dst| over points (N, 3) (Kabsch)."""
    cs, cd = src.mean(axis=0), dst.mean(axis=0)
    U, _, Vt = np.linalg.svd((src - cs).T @ (dst - cd))
    D = np.diag([1.0, 1.0, np.sign(np.linalg.det(Vt.T @ U.T))])
    R = Vt.T @ D @ U.T
    return R, cd - R @ cs


def model_diff(model_a, model_b, *, n_poses=2000, seed=0, tool=None, cell=None) -> dict:
    """TCP difference of two robot models over the working range (each in its own base frame).

    ``cell``: a :class:`robocal.calib.cell.Cell` (docs/cells.md): the joint sets are drawn among
    the poses model A can take in it (its mounting, obstacles and joint ranges); default: the
    whole common joint range.

    ``tool``: (3,) TCP in the flange frame [mm] (default the flange origin). Joint sets are drawn
    uniformly within both models' limits. Returns ``position_mm`` / ``rotation_deg`` statistics, an
    accuracy map (``by_reach``: horizontal distance of the TCP from joint 1's axis; ``by_height``),
    per-parameter differences when both models share parameter names, and the joint sets with
    their errors (``q`` (N, n) rad, ``error_mm`` (N,)), and ``base_aligned``: the same statistics
    after the best-fit rigid transform of B's base onto A's (the part of the difference a re-taught
    base frame removes is the rest).
    """
    A = load_nominal(model_a) if not isinstance(model_a, RobotModel) else model_a
    B = load_nominal(model_b) if not isinstance(model_b, RobotModel) else model_b
    if A.n_joints != B.n_joints:
        raise ControllerInputError(f"{A.name} has {A.n_joints} joints, {B.name} {B.n_joints}")
    lo = np.maximum(A.limits[:, 0], B.limits[:, 0])
    hi = np.minimum(A.limits[:, 1], B.limits[:, 1])
    if np.any(lo >= hi):
        raise ControllerInputError(f"{A.name} and {B.name} have no joint range in common")
    if cell is None:
        q = random_joints(A.replace(limits=np.stack([lo, hi], axis=1)), n_poses, seed)
    else:
        from ...calib.cell import sample_feasible

        q, _ = sample_feasible(cell, A.replace(limits=np.stack([lo, hi], axis=1)), n_poses,
                               np.random.default_rng(seed))
    tcp = np.zeros(3) if tool is None else np.asarray(tool, float)
    Ta = np.linalg.inv(A.T_world_base)[None] @ A.fk(q)
    Tb = np.linalg.inv(B.T_world_base)[None] @ B.fk(q)
    pa = (Ta[:, :3, :3] @ tcp) + Ta[:, :3, 3]
    pb = (Tb[:, :3, :3] @ tcp) + Tb[:, :3, 3]
    e = np.linalg.norm(pb - pa, axis=1)
    rot = np.degrees(np.linalg.norm(rotvec_from_matrix(np.swapaxes(Ta[:, :3, :3], 1, 2) @ Tb[:, :3, :3]), axis=1))
    # the same after the best-fit rigid base transform (what re-teaching the robot's base removes)
    R, t = _best_fit_rigid(pb, pa)
    pb_al = pb @ R.T + t
    e_al = np.linalg.norm(pb_al - pa, axis=1)
    rot_al = np.degrees(np.linalg.norm(rotvec_from_matrix(np.swapaxes(Ta[:, :3, :3], 1, 2) @ (R @ Tb[:, :3, :3])),
                                       axis=1))
    reach = np.hypot(pa[:, 0], pa[:, 1])
    maps = {}
    for label, v in (("by_reach", reach), ("by_height", pa[:, 2])):
        edges = np.linspace(v.min(), v.max() + 1e-9, 6)
        b = _bins(v, edges)
        rows = []
        for k in range(len(edges) - 1):
            sel = b == k
            if sel.any():
                st = error_statistics(e[sel])
                rows.append({"range_mm": [float(edges[k]), float(edges[k + 1])], **st})
        maps[label] = rows
    params = None
    if A.params.names == B.params.names and A.kind == B.kind:
        d = B.params.values - A.params.values
        params = {n: (float((x + math.pi) % (2 * math.pi) - math.pi) if u == "rad" else float(x))
                  for n, x, u in zip(A.params.names, d, A.params.units)}
    return {"a": A, "b": B, "n": int(n_poses), "tool_mm": tcp.tolist(), "position_mm": error_statistics(e),
            "rotation_deg": error_statistics(rot), "accuracy_map": maps,
            "base_aligned": {"position_mm": error_statistics(e_al), "rotation_deg": error_statistics(rot_al),
                             "rotation_of_base_deg": float(np.degrees(np.linalg.norm(rotvec_from_matrix(R)))),
                             "shift_of_base_mm": float(np.linalg.norm(t))}, "parameter_differences": params,
            "bases_differ": not np.allclose(A.T_world_base, B.T_world_base), "q": q, "error_mm": e,
            "positions_mm": pa,
            "rotation_error_deg": rot}
