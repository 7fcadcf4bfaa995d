"""The tolerance an effect the model lacks allows, to first order (issue 25, item 4).

A least-squares fit of data that carry a small effect ``e`` the model cannot represent lands, to
first order, at ``truth + J^+ e`` (``J``: the Jacobian of the model's predictions with respect to
the fitted variables at the solution). With ``e`` taken from the simulator's hidden truth
(noise-free predictions with the effect minus without), a test can state "within k sigma of truth
plus that bias" -- a claim the simulator does not make true by construction.

Jacobians here are finite differences of the simulator's geometry, not the solver's code. The
tracker and 6-D campaigns' helpers (``tracker_campaign_bias``, ``six_d_fit_bias``,
``poses_with_effects`` and what they use) live in
:mod:`robocal.sim.first_order`, where the documented figures (robocal.docs.figures) use them too.
"""

from __future__ import annotations

import numpy as np

from robocal.sim.cameras.self_calibration_views import camera_board_poses
from robocal.sim.first_order import (  # noqa: F401 (the tracker helpers moved to the library; re-exported)
    NO_EFFECTS,
    REALISTIC,
    STEP,
    campaign_effect_points,
    first_order_bias,
    poses_with_effects,
    six_d_fit_bias,
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
