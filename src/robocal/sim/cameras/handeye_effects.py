"""The hand-eye refinement with joint offsets on a robot whose links are off their nominal values
(issue 25, item 4): the eye-to-hand case of ``tests/test_handeye_refine.py`` with the bias the link
errors cause derived to first order from the hidden truth. Used by that test and the documented
figures of docs/testing.md (robocal.docs.figures): same draws.

The refinement's model has joint offsets only; links 0.1 mm / 0.01 deg per parameter off (the
absolute error a geometric calibration leaves) bias them by ``J^+ e``: ``e`` the noise-free corner
displacement the link errors cause, ``J`` the corners' Jacobian (finite differences of the
projection, not the refinement's code) with respect to the identifiable offsets (theta2-5), the
camera pose and the board pose -- the refinement's variables with ``robot_pose_sigma=None``.

Lengths mm, angles rad, pixels px.
"""

from __future__ import annotations

import numpy as np

from ...handeye import refine_hand_eye
from ...robots import load_robot
from ...transforms import invert_transforms, so3_exp, transforms_from
from ..robot import VirtualRobot
from .handeye_points import CAMERA_MODELS, board_points, look_at

__all__ = ["handeye_link_error_case"]


def handeye_link_error_case(*, seed: int = 7, robot_seed: int = 21, n_images: int = 20, pixel_sigma: float = 0.1,
                            h: float = 1e-6) -> dict:
    """An IRB 140 holding a board in front of a fixed camera 700 mm away (eye-to-hand), ``n_images``
    joint sets around (0, 20, -10, 0, 40, 0) deg +- 0.35 rad (``seed``), true offsets (0, 0.03,
    -0.04, 0.05, -0.03, 0) deg, every other parameter drawn 0.1 mm / 0.01 deg off its nominal value
    (``VirtualRobot.perturbed(robot_seed)``), ``pixel_sigma`` px corner noise; refined with
    ``joint_offsets=True``, ``pixel_sigma`` given and ``robot_pose_sigma=None``.

    Returns
    -------
    dict
        ``result`` (the :func:`refine_hand_eye` result), ``error`` (4,) [rad] (theta2-5 estimated
        minus true), ``bias`` (4,) [rad] (first order), ``sigma`` (4,) [rad] (reported),
        ``z_plain`` = error / sigma, ``z_after`` = (error - bias) / sigma.
    """
    robot = load_robot("abb_irb140")
    rng = np.random.default_rng(seed)
    q = np.radians([0.0, 20.0, -10.0, 0.0, 40.0, 0.0]) + rng.uniform(-0.35, 0.35, (n_images, 6))
    true_offsets = np.radians([0.0, 0.03, -0.04, 0.05, -0.03, 0.0])
    names = [f"theta{k}" for k in range(1, 7)]
    idx = [robot.params.index(nm) for nm in names]
    p_model = robot.params.values.copy()  # what the refinement can represent: nominal links, true offsets
    p_model[idx] += true_offsets
    p_links = VirtualRobot.perturbed(robot, robot_seed, length_sigma_mm=0.1, angle_sigma_deg=0.01,
                                     offset_sigma_deg=0.0).true_model.params.values.copy()
    p_links[idx] = p_model[idx]  # the offsets as above, every other parameter off its nominal value

    def flange(p):
        return robot.kinematics_with(q, p, T_world_base=np.eye(4), end_effectors=[0])[0][:, 0]

    X = board_points()
    T_ft = transforms_from(so3_exp(np.array([0.0, np.pi, 0.0])), np.array([-100.0, -70.0, 20.0]))
    F_model = flange(p_model)
    centre = (F_model @ T_ft)[:, :3, 3].mean(0)
    normal = -(F_model @ T_ft)[:, :3, 2].mean(0)
    T_bc = look_at(centre + 700.0 * normal / np.linalg.norm(normal), centre)
    camera = CAMERA_MODELS["brown"]

    def corners(p=p_links, Tbc=T_bc, Tft=T_ft):
        T_ct = invert_transforms(Tbc)[None] @ flange(p) @ Tft
        P = np.einsum("nij,pj->npi", T_ct[:, :3, :3], X) + T_ct[:, None, :3, 3]
        return camera.project(P.reshape(-1, 3)).pixels.reshape(n_images, len(X), 2)

    uv = corners() + rng.normal(0, pixel_sigma, (n_images, len(X), 2))
    F_nominal = robot.kinematics_with(q, T_world_base=np.eye(4), end_effectors=[0])[0][:, 0]
    res = refine_hand_eye(F_nominal, uv, X, camera, setup="eye_to_hand", joints=q, robot=robot, joint_offsets=True,
                          pixel_sigma=pixel_sigma, robot_pose_sigma=None)
    base = corners(p=p_model).ravel()
    e = corners().ravel() - base
    cols = []
    for i in idx[1:5]:
        p = p_model.copy()
        p[i] += h
        cols.append(corners(p=p).ravel())
    for k in range(6):
        w = np.zeros(6)
        w[k] = h
        step = transforms_from(so3_exp(w[:3]), w[3:])
        cols.append(corners(p=p_model, Tbc=T_bc @ step).ravel())
        cols.append(corners(p=p_model, Tft=T_ft @ step).ravel())
    J = (np.array(cols) - base).T / h
    bias = np.linalg.lstsq(J, e, rcond=None)[0][:4]
    err = res.joint_offsets_rad[1:5] - true_offsets[1:5]
    sigma = np.array([np.sqrt(res.covariance[i, i]) for i in map(res.variable_names.index, names[1:5])])
    return {"result": res, "error": err, "bias": bias, "sigma": sigma, "z_plain": err / sigma,
            "z_after": (err - bias) / sigma}
