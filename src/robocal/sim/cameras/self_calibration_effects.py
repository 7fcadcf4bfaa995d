"""Camera self-calibration on robots with effects the joint-offset model lacks (issue 25, item 4):
link-length errors and a bent board, on the NAO and on DLR Justin, with the bias they cause derived
to first order from the hidden truth. Used by ``tests/test_self_calibration_nao.py``,
``tests/test_self_calibration.py`` and the documented figures of docs/testing.md
(robocal.docs.figures): same draws.

The tolerance the effects allow: with ``e`` the pixel displacement the effects cause (true corners
minus those of the true offsets on the nominal lengths and a flat board, noise-free) and ``J`` the
Jacobian of the corners with respect to the identifiable offsets, the camera mount and the board
mounts at the solution (finite differences of the simulator's geometry, not the solver's code),
the estimate is biased by ``delta = J^+ e`` (:func:`robocal.sim.first_order.first_order_bias`).

Lengths mm, angles rad, pixels px.
"""

from __future__ import annotations

import numpy as np

from ...camera import Camera
from ...handeye.refine import joint_offset_names
from ...handeye.self_calibration import solve_self_calibration
from ...io.boards import parse_board
from ...robots import load_robot
from ...transforms import so3_exp, transforms_from
from ..first_order import STEP, first_order_bias, twist
from ..robot import parameter_kinds
from .self_calibration_views import camera_board_poses, simulate_corner_views

__all__ = ["JUSTIN_BOARDS", "JUSTIN_CAMERA", "JUSTIN_MOUNT", "corner_views", "justin_effects_case", "nao_effects_case",
           "self_calibration_offset_bias"]

#: DLR Justin's head camera, board mounts on the hands and camera mount (tests/test_self_calibration.py)
JUSTIN_CAMERA = Camera(800.0, 800.0, 319.5, 239.5, (-0.1, 0.05, 0.0, 0.0, 0.0), "brown", (640, 480))
JUSTIN_BOARDS = {"left": transforms_from(so3_exp(np.array([0.1, -0.2, 0.3])), np.array([10.0, 20.0, 120.0])),
                 "right": transforms_from(so3_exp(np.array([-0.2, 0.1, 2.0])), np.array([-15.0, 5.0, 110.0]))}
JUSTIN_MOUNT = transforms_from(so3_exp(np.array([0.01, -0.02, 0.015])), np.array([3.0, -2.0, 5.0]))


def corner_views(model, q, carriers, camera_ee: str, T_ee_camera, boards: dict, X, camera) -> np.ndarray:
    """Corner pixels (N, P, 2) of the boards ``{carrier: T_carrier_board}`` seen by the camera at
    ``T_ee_camera`` on ``camera_ee`` through ``model`` at joints ``q`` (N, n) [rad]; ``X`` (P, 3)
    the board's points [mm]."""
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


def _z_scores(res, truth: dict, delta: dict, names) -> tuple:
    """(z against the reported sigma, z of error - delta against the corner-noise sigma (reported
    / variance factor)) for ``names``."""
    est = dict(zip(res.joint_offset_names, res.joint_offsets))
    sig = dict(zip(res.joint_offset_names, res.joint_offset_sigma))
    z_naive = np.array([(est[n] - truth[n]) / sig[n] for n in names])
    z_noise = np.array([(est[n] - truth[n] - delta[n]) / sig[n] for n in names]) * res.variance_factor
    return z_naive, z_noise


def nao_effects_case(*, n_per_arm: int = 40, pixel_noise: float = 0.3, seed: int = 5) -> dict:
    """The NAO's top camera seeing boards on both hands (``simulate_self_calibration("nao_h25")``,
    readings exact, joints at capture known) with link-length errors of 0.2 mm per length on the
    chains (assumed: machined frames) and a board bent by 0.4 mm (a printed card), solved with the
    corner noise given.

    Returns
    -------
    dict
        ``result`` (the :func:`solve_self_calibration` result), ``effect_rms_px`` (RMS of ``e``),
        ``names`` (the identifiable offsets compared), ``z_naive`` (error / reported sigma),
        ``z_noise`` ((error - delta) / corner-noise sigma), ``delta`` {name: rad},
        ``has_length_errors`` (whether a length parameter was perturbed).
    """
    from .self_calibration import simulate_self_calibration

    run = simulate_self_calibration("nao_h25", n_images_per_chain=n_per_arm, pixel_noise=pixel_noise, joint_noise_deg=0.0,
                                    length_sigma_mm=0.2, board_bow_mm=0.4, partial_fraction=0.0, seed=seed)
    m, X, cam, on, q = run.robot, run.board.object_points(), run.camera, np.array(run.chain_of_image), run.q_true
    res = solve_self_calibration(m, q, run.image_points, X, cam, on, camera_end_effector="camera_top",
                                 pixel_sigma=pixel_noise)
    # the truth without the effects: true offsets on the nominal lengths, a flat board
    lengths = parameter_kinds(m) == "length"
    geo = m.params.values.copy()
    for n, v in run.parameter_errors.items():
        if not lengths[m.params.index(n)]:
            geo[m.params.index(n)] += v
    e = run.image_points_true - corner_views(m.with_params(geo), q, on, "camera_top", run.T_ee_camera, run.T_ee_board,
                                             X, cam)
    delta = self_calibration_offset_bias(res, q, on, "camera_top", X, cam, e)
    names = list(delta)
    truth = {r["name"]: run.joint_offsets_rad[r["joint"]] for r in res.joint_report}
    z_naive, z_noise = _z_scores(res, truth, delta, names)
    return {"result": res, "effect_rms_px": float(np.sqrt(np.mean(e**2))), "names": names, "z_naive": z_naive,
            "z_noise": z_noise, "delta": delta,
            "has_length_errors": any(lengths[m.params.index(n)] for n in run.parameter_errors)}


def justin_effects_case(*, pixel_noise: float = 0.3, seed: int = 16) -> dict:
    """DLR Justin's head camera seeing boards on both hands (25 views each), offsets of the head and
    arm joints drawn in +-3 deg, 0.2 mm errors on every free length parameter of those chains
    (assumed) and a board bent by 0.4 mm (``board_surface``), solved with the corner noise given.

    Returns
    -------
    dict
        As :func:`nao_effects_case` (without ``has_length_errors``), ``names``: the offsets of the
        head and arm joints that are identifiable.
    """
    from .self_calibration import board_surface

    m = load_robot("dlr_justin19")
    rng = np.random.default_rng(seed)
    pn = list(m.params.names)
    geo = m.params.values.copy()
    offsets = {}
    for n in joint_offset_names(m):
        if m.links[int(n[5:]) - 1].name.startswith(("head", "left", "right")):
            offsets[n] = np.radians(rng.uniform(-3.0, 3.0))
            geo[pn.index(n)] += offsets[n]
    on_chains = np.array([m.links[int(k)].name.startswith(("head", "left", "right")) for k in m.params.link_of])
    lengths = (parameter_kinds(m) == "length") & m.params.free & on_chains
    true = geo.copy()
    true[lengths] += rng.normal(0.0, 0.2, int(lengths.sum()))
    board = parse_board("checkerboard:7x4:25mm")
    X = board.object_points()
    X_bent = X.copy()
    X_bent[:, 2] += board_surface(board, 0.4)(X[:, 0], X[:, 1])
    cam, boards, mount = JUSTIN_CAMERA, JUSTIN_BOARDS, JUSTIN_MOUNT
    q, carriers, uv = simulate_corner_views(m.with_params(true), cam, X_bent, camera_end_effector="head",
                                            T_ee_camera=mount, boards=boards, n_per_carrier=25, rng=rng,
                                            pixel_noise=pixel_noise, front_z=board.front_z, pitch_mm=board.pitch_mm)
    res = solve_self_calibration(m, q, uv, X, cam, list(carriers), camera_end_effector="head", pixel_sigma=pixel_noise)
    e = (corner_views(m.with_params(true), q, carriers, "head", mount, boards, X_bent, cam)
         - corner_views(m.with_params(geo), q, carriers, "head", mount, boards, X, cam))
    delta = self_calibration_offset_bias(res, q, carriers, "head", X, cam, e)
    names = [n for n in delta if n in offsets]
    z_naive, z_noise = _z_scores(res, offsets, delta, names)
    return {"result": res, "effect_rms_px": float(np.sqrt(np.mean(e**2))), "names": names, "z_naive": z_naive,
            "z_noise": z_noise, "delta": delta}
