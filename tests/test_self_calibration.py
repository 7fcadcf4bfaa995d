"""Camera self-calibration of several chains at once (issue 15), on the DLR Justin tree (head camera,
a board in each hand): recovery of joint offsets from simulated corners, identifiability by name,
time-stamp matching and the image pipeline's per-image reasons and errors."""

from __future__ import annotations

import numpy as np
import pytest

from robocal.handeye.motions import HandEyeError
from robocal.handeye.refine import joint_offset_names
from robocal.handeye.self_calibration import solve_self_calibration
from robocal.io.boards import parse_board
from robocal.io.capture_times import match_capture_times
from robocal.robots import load_robot
from robocal.sim.cameras.self_calibration_effects import JUSTIN_BOARDS, JUSTIN_CAMERA, JUSTIN_MOUNT
from robocal.sim.cameras.self_calibration_views import simulate_corner_views

NOISE_PX = 0.3
CAM, BOARDS, MOUNT = JUSTIN_CAMERA, JUSTIN_BOARDS, JUSTIN_MOUNT  # robocal.sim.cameras.self_calibration_effects


@pytest.fixture(scope="module")
def justin():
    m = load_robot("dlr_justin19")
    rng = np.random.default_rng(15)
    pn = list(m.params.names)
    truth = m.params.values.copy()
    offsets = {}
    for n in joint_offset_names(m):
        if m.links[int(n[5:]) - 1].name.startswith(("head", "left", "right")):
            offsets[n] = np.radians(rng.uniform(-3.0, 3.0))
            truth[pn.index(n)] += offsets[n]
    true_model = m.with_params(truth)
    board = parse_board("checkerboard:7x4:25mm")
    X = board.object_points()
    q, carriers, uv = simulate_corner_views(true_model, CAM, X, camera_end_effector="head", T_ee_camera=MOUNT,
                                            boards=BOARDS, n_per_carrier=25, rng=rng, pixel_noise=NOISE_PX,
                                            front_z=board.front_z, pitch_mm=board.pitch_mm)
    return m, q, uv, X, list(carriers), offsets


def test_joint_offsets_of_head_and_both_arms_recovered_within_three_sigma(justin):
    m, q, uv, X, carriers, offsets = justin
    res = solve_self_calibration(m, q, uv, X, CAM, carriers, camera_end_effector="head", pixel_sigma=NOISE_PX)
    assert res.converged
    held = {r["name"] for r in res.joint_report if not r["identifiable"]}
    z = []
    for n, v, s in zip(res.joint_offset_names, res.joint_offsets, res.joint_offset_sigma):
        if n in offsets and n not in held:
            z.append((v - offsets[n]) / s)
    assert len(z) == 13  # 7 + 7 arm joints + 2 head joints, minus the 2 last arm joints and head_j2
    assert np.max(np.abs(z)) < 3.0
    # per-coordinate reprojection RMS within 10 % of the simulated corner noise
    assert abs(res.rms_px / np.sqrt(2) / NOISE_PX - 1.0) < 0.1


def test_identifiability_names_shared_joints_board_and_camera_trade_offs(justin):
    m, q, uv, X, carriers, _ = justin
    res = solve_self_calibration(m, q, uv, X, CAM, carriers, camera_end_effector="head", pixel_sigma=NOISE_PX)
    by_joint = {r["joint"]: r for r in res.joint_report}
    assert not by_joint["torso_0"]["identifiable"] and "cancels" in by_joint["torso_0"]["why"]
    assert not by_joint["left_j7"]["identifiable"] and "board_left" in by_joint["left_j7"]["why"]
    assert not by_joint["right_j7"]["identifiable"] and "board_right" in by_joint["right_j7"]["why"]
    assert not by_joint["head_j2"]["identifiable"] and "camera_mount" in by_joint["head_j2"]["why"]
    assert by_joint["head_j1"]["identifiable"] and by_joint["head_j1"]["loops"] == ["left", "right"]


def test_both_arms_together_determine_the_head_joint_better_than_each_arm_alone(justin):
    m, q, uv, X, carriers, offsets = justin
    c = np.array(carriers)
    both = solve_self_calibration(m, q, uv, X, CAM, carriers, camera_end_effector="head", pixel_sigma=NOISE_PX)
    k = both.joint_offset_names.index("theta23")  # head_j1
    err_both = abs(both.joint_offsets[k] - offsets["theta23"])
    for arm in ("left", "right"):
        sel = c == arm
        one = solve_self_calibration(m, q[sel], uv[sel], X, CAM, c[sel], camera_end_effector="head",
                                     pixel_sigma=NOISE_PX)
        j = one.joint_offset_names.index("theta23")
        assert both.joint_offset_sigma[k] < one.joint_offset_sigma[j]
        assert err_both <= 3 * one.joint_offset_sigma[j]


def test_too_few_images_of_a_carrier_and_unknown_end_effector_are_refused(justin):
    m, q, uv, X, carriers, _ = justin
    with pytest.raises(HandEyeError, match="board on 'right': 2 usable images"):
        solve_self_calibration(m, q[:27], uv[:27], X, CAM, carriers[:27], camera_end_effector="head")
    with pytest.raises(HandEyeError, match="no end effector 'nose'"):
        solve_self_calibration(m, q, uv, X, CAM, carriers, camera_end_effector="nose")
    with pytest.raises(HandEyeError, match="look like degrees"):
        solve_self_calibration(m, np.degrees(q) * 10, uv, X, CAM, carriers, camera_end_effector="head")


def test_capture_times_nearest_and_interpolated_with_a_tolerance():
    t_log = np.arange(0.0, 2.01, 0.1)
    q_log = np.column_stack([t_log, 2 * t_log])
    q, dt, why = match_capture_times([0.52, 1.02, 5.0], t_log, q_log, tolerance=0.03)
    assert np.allclose(q[0], [0.5, 1.0]) and np.allclose(q[1], [1.0, 2.0])
    assert np.allclose(dt[:2], [0.02, 0.02])
    assert why[0] is None and why[1] is None and np.isnan(q[2]).all()
    assert "no joint reading within 0.03 s" in why[2] and "+3.000 s" in why[2]
    q, dt, why = match_capture_times([0.52, 2.01], t_log, q_log, tolerance=0.09, mode="interpolate")
    assert np.allclose(q[0], [0.52, 1.04]) and why[0] is None
    assert "on both sides" in why[1]


def test_unmodelled_link_lengths_and_a_bent_board_bias_the_justin_offsets_to_first_order():
    """The test above on a simulator that includes what the joint-offset model lacks: 0.2 mm
    errors on every length parameter of the head and arm chains (assumed) and a board bent by
    0.4 mm (``board_surface``). The tolerance the effects allow, to first order from the hidden
    truth: every identifiable offset within 3 corner-noise sigma of
    truth + ``J^+ e`` (:func:`robocal.sim.cameras.self_calibration_effects.justin_effects_case`); the plain "within 3 sigma of truth" fails. Measured: the effects move the
    corners by 0.60 px RMS (noise 0.3 px), variance factor 1.61, naive max |z| 15.9 (reported,
    scaled sigmas), corrected max 1.88 (corner-noise sigmas)."""
    from robocal.sim.cameras.self_calibration_effects import justin_effects_case

    c = justin_effects_case(pixel_noise=NOISE_PX, seed=16)
    res, z_naive, z_noise = c["result"], c["z_naive"], c["z_noise"]
    assert res.converged and res.variance_factor > 1.5, res.message
    assert c["effect_rms_px"] > NOISE_PX  # the effects are above the corner noise
    assert len(c["names"]) == 13
    assert np.abs(z_noise).max() < 3.0, z_noise
    assert np.abs(z_naive).max() > 5.0, z_naive
