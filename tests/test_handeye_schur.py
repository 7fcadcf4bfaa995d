"""The hand-eye refinement with the per-image flange corrections eliminated by a Schur complement
(issue 34 item 1): the same solution, covariance, iterations and variance components as the dense
solve it replaces (the structured solve only changes the linear algebra, so both take the same
steps up to rounding)."""

from __future__ import annotations

import numpy as np
import pytest

from robocal.calib import Problem, solve
from robocal.calib.blocks import FramesBlock
from robocal.calib.residuals import FlangeReprojectionResidual
from robocal.calib.schur import StructureError, solve_schur
from robocal.handeye import refine as refine_module
from robocal.handeye.refine import _flange_corrections, _intrinsics_block, refine_hand_eye
from robocal.handeye.solve import solve_robot_world_hand_eye
from robocal.handeye.pnp import solve_pnp
from robocal.sim.cameras.handeye_points import simulate_hand_eye


def _problem(sim, compact, setup="eye_in_hand", refine_intrinsics=False):
    F, uv, X, cam = sim.T_base_flange, sim.image_points, sim.target_points, sim.camera
    C = solve_pnp(cam, X, uv)[0]
    cp, tp = solve_robot_world_hand_eye(F, C, setup=setup)
    camb = _intrinsics_block(cam, refine_intrinsics)
    cb, tb = FramesBlock("camera_pose", cp, group="base"), FramesBlock("target_pose", tp, group="targets")
    corrections, prior = _flange_corrections((0.05, 0.01), np.arange(len(F)))
    res = FlangeReprojectionResidual(camb, cb, tb, uv, X, invert=setup == "eye_in_hand", flange_poses=F, sigma=0.3,
                                     corrections=corrections, compact_corrections=compact)
    return Problem([camb, cb, tb, corrections], [res, prior], n_poses=len(F)), corrections


@pytest.mark.parametrize("refine_intrinsics", [False, True])
def test_schur_solve_equals_the_dense_solve(refine_intrinsics):
    sim = simulate_hand_eye(3, n_images=10)
    dense_problem, _ = _problem(sim, False, refine_intrinsics=refine_intrinsics)
    schur_problem, corrections = _problem(sim, True, refine_intrinsics=refine_intrinsics)
    dense = solve(dense_problem)
    fast = solve_schur(schur_problem, corrections, frames_last=True)
    assert fast.names == dense.names and fast.iterations == dense.iterations and fast.converged
    sigma = dense.std
    assert np.all(np.isfinite(sigma))
    # the same estimate to a tiny fraction of its 1-sigma, the same covariance
    assert np.max(np.abs(fast.values - dense.values) / sigma) < 1e-6
    assert np.max(np.abs(fast.covariance - dense.covariance) / np.outer(sigma, sigma)) < 1e-6
    assert fast.identifiability.identifiable == dense.identifiability.identifiable
    # the leverage (hat-matrix diagonal) the variance components read, against J Cov J^T of the dense J
    J = dense.jacobian
    h = np.einsum("ij,jk,ik->i", J, dense.covariance, J)
    np.testing.assert_allclose(fast.leverage, h, rtol=1e-6, atol=1e-9)
    assert abs(h.sum() - len(dense.names)) < 1e-6  # trace of the hat matrix = the unknowns


@pytest.mark.parametrize("setup", ["eye_in_hand", "eye_to_hand"])
def test_refinement_and_noise_estimate_unchanged_by_the_structured_solve(setup, monkeypatch):
    """``robot_pose_sigma="estimate"`` (the variance-component rounds) through the Schur solve and
    through the dense solve (the structured solve made to refuse the problem): same camera pose,
    sigmas and estimated noise levels."""
    sim = simulate_hand_eye(5, n_images=12, setup=setup)
    args = (sim.T_base_flange, sim.image_points, sim.target_points, sim.camera)
    fast = refine_hand_eye(*args, setup=setup, robot_pose_sigma="estimate")

    def refuse(*_a, **_k):
        raise StructureError("forced dense")

    monkeypatch.setattr(refine_module, "solve_schur", refuse)
    dense = refine_hand_eye(*args, setup=setup, robot_pose_sigma="estimate")
    assert np.max(np.abs(fast.camera_pose - dense.camera_pose)) < 1e-7
    np.testing.assert_allclose(fast.sigma_translation_mm, dense.sigma_translation_mm, rtol=1e-6)
    np.testing.assert_allclose(fast.sigma_rotation_deg, dense.sigma_rotation_deg, rtol=1e-6)
    np.testing.assert_allclose(fast.noise_estimate["robot_pose_sigma"], dense.noise_estimate["robot_pose_sigma"],
                               rtol=1e-6)
    assert fast.noise_estimate["pixel_sigma_px"] == pytest.approx(dense.noise_estimate["pixel_sigma_px"], rel=1e-6)
    assert fast.message == dense.message


def test_linear_starts_are_solved_on_first_access_with_the_same_values():
    sim = simulate_hand_eye(2, n_images=8)
    res = refine_hand_eye(sim.T_base_flange, sim.image_points, sim.target_points, sim.camera, robot_pose_sigma=None)
    assert list(res.linear) == ["tsai", "park", "daniilidis", "shah"]
    C = res.T_camera_target
    X_park, Z_park = res.linear["park"]
    from robocal.handeye.solve import solve_hand_eye

    np.testing.assert_allclose(X_park, solve_hand_eye(sim.T_base_flange, C, method="park"), atol=1e-12)
    np.testing.assert_allclose(res.linear["shah"][0], solve_robot_world_hand_eye(sim.T_base_flange, C)[0], atol=1e-12)


@pytest.mark.parametrize("loss", ["huber", "cauchy"])
def test_a_rejected_image_is_handled_as_by_the_dense_solve(loss, monkeypatch):
    """A robust loss drops an image with a wrong flange pose (its corner rows and its correction's
    prior rows get weight 0: a frame with no information): same outlier, camera pose and sigmas."""
    from robocal.transforms import so3_exp

    sim = simulate_hand_eye(4, n_images=14)
    F = sim.T_base_flange.copy()
    F[3, :3, 3] += [5.0, -3.0, 2.0]  # a wrong robot reading: 6 mm and 1.1 deg
    F[3, :3, :3] = so3_exp(np.array([[0.02, 0.0, 0.0]]))[0] @ F[3, :3, :3]
    args = (F, sim.image_points, sim.target_points, sim.camera)
    fast = refine_hand_eye(*args, loss=loss)

    def refuse(*_a, **_k):
        raise StructureError("forced dense")

    monkeypatch.setattr(refine_module, "solve_schur", refuse)
    dense = refine_hand_eye(*args, loss=loss)
    assert set(fast.outliers) == set(dense.outliers) == {3}
    assert np.max(np.abs(fast.camera_pose - dense.camera_pose)) < 1e-8
    np.testing.assert_allclose(fast.sigma_translation_mm, dense.sigma_translation_mm, rtol=1e-6)
    assert fast.message == dense.message
