"""The tolerance an effect the model lacks allows, to first order (issue 25, item 4).

A least-squares fit of data that carry a small effect ``e`` the model cannot represent lands, to
first order, at ``truth + J^+ e`` (``J``: the Jacobian of the model's predictions with respect to
the fitted variables at the solution). With ``e`` taken from the simulator's hidden truth
(noise-free predictions with the effect minus without), a test can state "within k sigma of truth
plus that bias" -- a claim the simulator does not make true by construction.

Jacobians here are finite differences of the simulator's geometry, not the solver's code. The
tracker campaign's helpers (``tracker_campaign_bias`` and what it uses) live in
:mod:`robocal.sim.first_order`, where the documented figures (robocal.docs.figures) use them too.
"""

from __future__ import annotations

import numpy as np

from robocal.sim.cameras.self_calibration_views import camera_board_poses
from robocal.sim.first_order import (  # noqa: F401 (the tracker helpers moved to the library; re-exported)
    NO_EFFECTS,
    STEP,
    campaign_effect_points,
    first_order_bias,
    tracker_campaign_bias,
    twist,
)


def corner_views(model, q, carriers, camera_ee: str, T_ee_camera, boards: dict, X, camera) -> np.ndarray:
    """Corner pixels (N, P, 2) of the boards ``{carrier: T_carrier_board}`` seen by the camera at
    ``T_ee_camera`` on ``camera_ee`` through ``model`` at joints ``q`` (N, n) [rad]."""
    carriers = np.asarray(carriers)
    out = np.empty((len(q), len(X), 2))
    for c in dict.fromkeys(carriers.tolist()):
        i = carriers == c
        T = camera_board_poses(model, q[i], camera_ee, T_ee_camera, c, boards[c])
        p = np.einsum("nij,pj->npi", T[:, :3, :3], X) + T[:, None, :3, 3]
        out[i] = camera.project(p.reshape(-1, 3)).pixels.reshape(int(i.sum()), -1, 2)
    return out


def self_calibration_offset_bias(res, q, carriers, camera_ee: str, X, camera, e) -> dict:
    """First-order bias {offset name: rad} of a :func:`solve_self_calibration` result ``res`` from
    the corner displacement ``e`` (N, P, 2) [px] of an effect its model lacks; the variables are
    the identifiable offsets, the camera mount and every board mount (intrinsics as given)."""
    held = {r["name"] for r in res.joint_report if not r["identifiable"]}
    names = [n for n in res.joint_offset_names if n not in held]
    model, vals, boards = res.model, res.model.params.values, res.boards

    def corners(values=vals, mount=res.camera_mount, b=boards):
        return corner_views(model.with_params(values), q, carriers, camera_ee, mount, b, X, camera).ravel()

    cols = []
    for n in names:
        v = vals.copy()
        v[model.params.index(n)] += STEP
        cols.append(corners(values=v))
    cols += [corners(mount=res.camera_mount @ twist(k)) for k in range(6)]
    cols += [corners(b={**boards, c: boards[c] @ twist(k)}) for c in boards for k in range(6)]
    return dict(zip(names, first_order_bias(cols, corners(), e)))


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
    from robocal.transforms import so3_log

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
