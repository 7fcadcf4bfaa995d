"""Issue 30 item 4: the board's shape estimated with the intrinsics. Rendered images of a
checkerboard bent into a cylinder (the self-calibration simulator's `board_surface`: its middle 1 mm
out of the plane of the printed pattern's ends), through `robocal camera calibrate --board-shape`:
the sag comes back at the value the bend gives over the detected corners, and the focal length,
biased by tens of pixels by a flat-board model, is recovered."""

from __future__ import annotations

import json
import tempfile

import cv2
import numpy as np
import pytest
from click.testing import CliRunner

from robocal.calib.residuals.board_shape import sag_bases
from robocal.cli.main import main
from robocal.io.boards import board_image, parse_board
from robocal.sim.cameras.camera_cell import simulate_hand_eye_poses
from robocal.sim.cameras.camera_render import BoardRenderer
from robocal.sim.cameras.self_calibration import board_surface
from robocal.workflows.cameras.camera_simulate import _texel_mm

SPEC = "checkerboard:9x6:25mm"
BOW_MM = 1.0


@pytest.fixture(scope="module")
def bent(tmp_path_factory):
    folder = tmp_path_factory.mktemp("bent")
    b = parse_board(SPEC)
    X = b.object_points()
    cell = simulate_hand_eye_poses(X, setup="eye_in_hand", n_images=10, front_z=b.front_z, seed=3)
    texture, affine = board_image(b, _texel_mm(b))
    surface = board_surface(b, BOW_MM)
    renderer = BoardRenderer(cell.camera, texture, affine, surface=surface)
    rng = np.random.default_rng(3)
    for k, T in enumerate(cell.T_camera_target):
        cv2.imwrite(str(folder / f"{k:02d}.png"), renderer.render(T, rng))
    # the true sag over the corners: the surface's middle-to-outermost-corner height along x (analytic)
    z = surface(X[:, 0], X[:, 1])
    true_sag_x = float(z.max() - z[np.argmin(X[:, 0])])
    return folder, cell.camera, true_sag_x


def _calibrate(folder, *extra):
    with tempfile.TemporaryDirectory() as out:  # --out is required; the test reads the printed result
        r = CliRunner().invoke(main, ["camera", "calibrate", str(folder), "--board", SPEC, "--distortion", "5",
                                      "--fix", "k3", "--json", "--out", out, *extra])
    assert r.exit_code == 0, r.output
    return json.loads(r.stdout[r.stdout.index("{"):])


def test_board_sag_recovered_with_the_intrinsics(bent):
    folder, truth, true_sag_x = bent
    flat = _calibrate(folder)
    shaped = _calibrate(folder, "--board-shape")
    sag = shaped["board_sag_mm"]
    print("sag", sag, "true", true_sag_x, "fx flat", flat["camera"]["parameters"]["fx"] - truth.fx,
          "fx shaped", shaped["camera"]["parameters"]["fx"] - truth.fx, flat["reprojection_rms_px"],
          shaped["reprojection_rms_px"])
    # measured: 0.6399 +- 0.0038 mm against the true 0.6400, y 0.0006; fx off 25.5 px flat, -0.12 px shaped;
    # RMS 0.220 px flat, 0.040 px shaped
    assert abs(sag["x"] - true_sag_x) < max(3 * sag["sigma_x"], 0.03), (sag, true_sag_x)
    assert abs(sag["y"]) < max(3 * sag["sigma_y"], 0.03)
    fx_flat = flat["camera"]["parameters"]["fx"] - truth.fx
    p, s = shaped["camera"]["parameters"], shaped["camera"]["sigma"]
    assert abs(fx_flat) > 10.0
    for name in ("fx", "fy", "cx", "cy"):
        assert abs(p[name] - getattr(truth, name)) < 3 * s[name] + 0.5, name
    assert shaped["reprojection_rms_px"] < 0.5 * flat["reprojection_rms_px"]
    assert flat["board_sag_mm"] is None


def test_sag_bases_are_zero_at_the_outermost_points_and_one_in_the_middle():
    X = parse_board(SPEC).object_points()
    B = sag_bases(X)
    assert np.allclose(B[np.isclose(X[:, 0], X[:, 0].min()), 0], 0.0)
    assert np.allclose(B[np.isclose(X[:, 1], X[:, 1].max()), 1], 0.0)
    assert B.max() <= 1.0 and np.isclose(B[:, 0].max(), 1.0)  # 9 corners along x: the middle one is at 0
