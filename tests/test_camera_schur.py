"""robocal.calib.schur (issue 34 item 1): the camera calibration with the per-image poses eliminated
by a Schur complement reaches the dense solve's optimum, iteration count, 1-sigma and
identifiability verdicts (the same problem solved both ways; the dense solve is the reference
algorithm), with a robust loss and an outlier image too, and with a board shape block after the
poses; a problem without the structure is refused (the caller then solves densely)."""

import numpy as np
import pytest

from robocal.calib import Problem, solve
from robocal.calib.blocks import CameraIntrinsics, FramesBlock
from robocal.calib.residuals import BoardShapeReprojectionResidual, ReprojectionResidual
from robocal.calib.residuals.board_shape import board_shape_block
from robocal.calib.schur import StructureError, solve_schur
from robocal.handeye.pnp import solve_pnp
from robocal.sim.cameras.handeye_points import simulate_hand_eye


def _problems(uv, sim, board=False):
    cam0 = sim.camera
    T0, _, _ = solve_pnp(cam0, sim.target_points, uv)
    out = []
    for compact in (True, False):
        start = np.array(cam0.intrinsics) * [1.01, 0.99, 1.0, 1.0]
        cam = CameraIntrinsics(start, np.zeros(5), model="brown", name="cam")
        fixed = FramesBlock("camera", np.eye(4), free=False)
        poses = FramesBlock("target", T0, group="targets")
        if board:
            shape = board_shape_block()
            res = BoardShapeReprojectionResidual(cam, fixed, poses, uv, sim.target_points, shape,
                                                 compact_targets=compact)
            out.append((Problem([cam, fixed, poses, shape], [res]), poses))
        else:
            res = ReprojectionResidual(cam, fixed, poses, uv, sim.target_points, compact_targets=compact)
            out.append((Problem([cam, fixed, poses], [res]), poses))
    return out


def _compare(a, b, loss):
    assert a.converged and b.converged and a.iterations == b.iterations
    cam = [i for i, n in enumerate(a.names) if n.startswith(("cam.", "board."))]
    # the same optimum: differences far below the 1-sigma (rounding of two factorisations)
    assert np.max(np.abs(a.values[cam] - b.values[cam]) / b.std[cam]) < 1e-4
    kept = np.isfinite(a.std)  # NaN: the poses of an image dropped as an outlier (the dense solve: 0)
    assert kept.sum() >= len(a.std) - 6
    np.testing.assert_allclose(a.std[kept], b.std[kept], rtol=1e-5)  # every variable, poses included
    np.testing.assert_allclose(a.residuals_after, b.residuals_after, atol=1e-6)
    assert a.identifiability.identifiable == b.identifiability.identifiable
    assert [o["pose"] for o in a.outliers] == [o["pose"] for o in b.outliers]
    if loss != "linear":
        assert len(a.outliers) >= 1


@pytest.mark.parametrize("loss", ["linear", "huber"])
def test_schur_solve_equals_the_dense_solve(loss):
    sim = simulate_hand_eye(5, n_images=10, pose_noise_mm=0.0, pose_noise_deg=0.0)
    uv = sim.image_points.copy()
    uv[3, :5] = np.nan  # missing corners: frames with different row counts
    if loss == "huber":
        uv[6] += np.random.default_rng(1).normal(0, 20.0, uv[6].shape)  # one bad image
    (ps, poses), (pd, _) = _problems(uv, sim)
    _compare(solve_schur(ps, poses, loss=loss), solve(pd, loss=loss), loss)


def test_schur_solve_with_a_board_shape_block_after_the_poses():
    sim = simulate_hand_eye(7, n_images=8, bend_mm=0.3, pose_noise_mm=0.0, pose_noise_deg=0.0)
    (ps, poses), (pd, _) = _problems(sim.image_points, sim, board=True)
    _compare(solve_schur(ps, poses), solve(pd), "linear")


def test_a_problem_without_the_structure_is_refused():
    sim = simulate_hand_eye(5, n_images=4, pose_noise_mm=0.0, pose_noise_deg=0.0)
    _, (pd, poses) = _problems(sim.image_points, sim)
    with pytest.raises(StructureError):
        solve_schur(pd, poses)  # not built with compact_targets
