"""Issue 15 acceptance on the NAO H25 (head camera ``camera_top``, a board in each hand): 40 images
per arm, joint offsets up to +-3 deg on head and both arms, 0.3 px corner noise; every identifiable
joint offset within 3 reported sigma, reprojection RMS within 10 % of the noise, and both arms
together at least as accurate as each arm alone. Corners from :mod:`robocal.sim.cameras.self_calibration_views`
(projection + noise; the rendered path is covered by test_self_calibration_pipeline.py)."""

from __future__ import annotations

import numpy as np
import pytest

from robocal.camera import Camera
from robocal.handeye.refine import joint_offset_names
from robocal.handeye.self_calibration import solve_self_calibration
from robocal.io.boards import parse_board
from robocal.robots import load_robot
from robocal.sim.cameras.self_calibration_views import simulate_corner_views
from robocal.transforms import so3_exp, transforms_from

NOISE_PX = 0.3
N_PER_ARM = 40
# NAO top camera (VGA, 60.9 deg horizontal field of view: fx = 320 / tan(30.45 deg) = 556.8 px)
CAM = Camera(556.8, 556.8, 319.5, 239.5, (0.0, 0.0, 0.0, 0.0, 0.0), "brown", (640, 480))
HANDS = ("left_hand", "right_hand")


@pytest.fixture(scope="module")
def nao():
    m = load_robot("nao_h25")
    rng = np.random.default_rng(25)
    pn = list(m.params.names)
    truth = m.params.values.copy()
    offsets = {n: np.radians(rng.uniform(-3.0, 3.0)) for n in joint_offset_names(m)}
    for n, v in offsets.items():
        truth[pn.index(n)] += v
    true_model = m.with_params(truth)
    board = parse_board("checkerboard:5x4:12mm")
    X = board.object_points()
    # the board 20 mm beyond the hand, printed side towards the body; a small camera mount error
    mounts = {h: transforms_from(so3_exp(np.array([0.02, np.pi / 2, -0.03])), np.array([20.0, 2.0, -1.0]))
              for h in HANDS}
    T_ee_camera = transforms_from(so3_exp(np.array([0.005, -0.01, 0.008])), np.array([1.0, -0.5, 0.8]))
    q, on, uv = simulate_corner_views(true_model, CAM, X, camera_end_effector="camera_top", T_ee_camera=T_ee_camera,
                                      boards=mounts, n_per_carrier=N_PER_ARM, rng=rng, pixel_noise=NOISE_PX,
                                      front_z=board.front_z, pitch_mm=board.pitch_mm)
    both = solve_self_calibration(m, q, uv, X, CAM, on, camera_end_effector="camera_top", pixel_sigma=NOISE_PX)
    alone = {h: solve_self_calibration(m, q[on == h], uv[on == h], X, CAM, on[on == h],
                                       camera_end_effector="camera_top", pixel_sigma=NOISE_PX) for h in HANDS}
    return offsets, both, alone


def _z(res, offsets):
    held = {r["name"] for r in res.joint_report if not r["identifiable"]}
    return {n: (v - offsets[n]) / s for n, v, s in zip(res.joint_offset_names, res.joint_offsets,
                                                       res.joint_offset_sigma) if n not in held}


def test_every_identifiable_nao_joint_offset_within_three_sigma(nao):
    offsets, both, alone = nao
    assert both.converged and all(a.converged for a in alone.values()), both.message  # figures at an optimum
    z = _z(both, offsets)
    assert len(z) == 9  # 12 joints; HeadPitch (camera mount) and both WristYaw (board transforms) held
    assert max(abs(v) for v in z.values()) < 3.0
    assert abs(both.rms_px / np.sqrt(2) / NOISE_PX - 1.0) < 0.1


def test_held_nao_joints_are_named_with_what_they_trade_against(nao):
    _, both, _ = nao
    by_joint = {r["joint"]: r for r in both.joint_report}
    assert "camera_mount" in by_joint["HeadPitch"]["why"]
    assert "board_left_hand" in by_joint["LWristYaw"]["why"]
    assert "board_right_hand" in by_joint["RWristYaw"]["why"]
    assert by_joint["HeadYaw"]["identifiable"] and by_joint["HeadYaw"]["loops"] == list(HANDS)


def test_both_arms_together_at_least_as_accurate_as_each_arm_alone(nao):
    offsets, both, alone = nao
    s_both = dict(zip(both.joint_offset_names, both.joint_offset_sigma))
    for h, res in alone.items():
        for n, s in zip(res.joint_offset_names, res.joint_offset_sigma):
            if np.isfinite(s):
                assert s_both[n] <= s * 1.0001, (h, n)
    # the shared head joint: error with both arms below 3 sigma of either arm alone
    k = both.joint_offset_names.index("theta1")
    for res in alone.values():
        j = res.joint_offset_names.index("theta1")
        assert abs(both.joint_offsets[k] - offsets["theta1"]) < 3 * res.joint_offset_sigma[j]


@pytest.fixture(scope="module")
def simulated_run():
    from robocal.sim.cameras.self_calibration import simulate_self_calibration

    return simulate_self_calibration("nao_h25", n_images_per_chain=N_PER_ARM, pixel_noise=NOISE_PX,
                                     joint_noise_deg=0.0, seed=3)


def test_nao_model_simulator_run_end_to_end_without_rendering(simulated_run):
    """nao-model's simulator (offsets +-3 deg, mount errors, clock offset 35 ms and jitter, partial
    views): frames matched to the 20 Hz log by time stamp, partial views rejected, each view
    assigned to the hand that holds the board, then the joint solve."""
    from robocal.handeye.self_calibration import assign_carriers
    from robocal.io.capture_times import match_capture_times

    run = simulated_run
    q, dt, why = match_capture_times(run.frame_times, run.log_times, run.log_joints, tolerance=0.06)
    assert all(w is None for w in why)
    uv = run.image_points.copy()
    w, h = run.camera.image_size
    uv[~((uv[..., 0] >= 0) & (uv[..., 0] <= w - 1) & (uv[..., 1] >= 0) & (uv[..., 1] <= h - 1))] = np.nan
    full = np.all(np.isfinite(uv[..., 0]), axis=1)
    assert np.array_equal(full, run.fully_visible)
    idx = np.flatnonzero(full)
    X = run.board.object_points()
    on, _, reasons = assign_carriers(run.robot, q[idx], uv[idx], X, run.camera, HANDS,
                                     camera_end_effector="camera_top")
    assert list(on) == [run.chain_of_image[i] for i in idx] and not any(reasons)
    res = solve_self_calibration(run.robot, q[idx], uv[idx], X, run.camera, on, camera_end_effector="camera_top",
                                 pixel_sigma=NOISE_PX)
    z = []
    for r, v, s in zip(res.joint_report, res.joint_offsets, res.joint_offset_sigma):
        if r["identifiable"]:
            z.append((v - run.joint_offsets_rad[r["joint"]]) / s)
    assert res.converged, res.message
    assert len(z) == 9 and max(abs(x) for x in z) < 3.0  # measured 1.59 (docs figure, robocal.docs.figures)
    assert abs(res.rms_px / np.sqrt(2) / NOISE_PX - 1.0) < 0.1  # measured 0.304 px


def test_joint_reading_noise_needs_the_per_image_joint_corrections():
    """nao-model's default 0.05 deg reading noise per log row: without per-image joint corrections
    the sigmas claim far too much (measured max |error / sigma| 7.4, errors up to 0.133 deg, even
    with the sigmas scaled by the variance factor 5.4); with them (errors in variables, prior
    0.05 deg) max |error / sigma| 1.1 and errors up to 0.028 deg (docs/self-calibration.md, checked by
    ``python -m robocal.docs.figures --all --only "nao joint noise"``)."""
    from robocal.io.capture_times import match_capture_times
    from robocal.sim.cameras.self_calibration import simulate_self_calibration

    run = simulate_self_calibration("nao_h25", n_images_per_chain=N_PER_ARM, pixel_noise=NOISE_PX,
                                    joint_noise_deg=0.05, partial_fraction=0.0, seed=3)
    q, _, why = match_capture_times(run.frame_times, run.log_times, run.log_joints, tolerance=0.06)
    assert all(w is None for w in why)
    X = run.board.object_points()
    worst = {}
    for noise in (None, 0.05):
        res = solve_self_calibration(run.robot, q, run.image_points, X, run.camera, run.chain_of_image,
                                     camera_end_effector="camera_top", pixel_sigma=NOISE_PX, joint_noise_deg=noise)
        worst[noise] = max(abs(v - run.joint_offsets_rad[r["joint"]]) / s for r, v, s in
                           zip(res.joint_report, res.joint_offsets, res.joint_offset_sigma) if r["identifiable"])
    assert worst[None] > 5.0
    assert worst[0.05] < 3.0


# ------------------------------------------------------------------------------------------ effects the model lacks
def test_link_length_errors_and_a_bent_board_bias_the_offsets_as_first_order_theory_predicts():
    """The "within 3 sigma" tests above use a simulator equal to the model. Here the simulator's
    realistic options add what the joint-offset model lacks: link-length errors (0.2 mm per length
    on the chains, assumed: machined NAO frames) and a board bent by 0.4 mm (a printed card; the
    model assumes it flat). Readings exact and the joints at capture known (the time matching is
    tested above), so the effect is isolated.

    The tolerance the effects allow, from the hidden truth to first order: with ``e`` the pixel
    displacement the effects cause (true corners minus those of the true offsets on the nominal
    lengths and a flat board, noise-free) and ``J`` the Jacobian of the corners with respect to the
    identifiable offsets, the camera mount and the board mounts at the solution (finite
    differences of the simulator's geometry), the estimate is biased by ``delta = J^+ e``
    (:func:`robocal.sim.cameras.self_calibration_effects.nao_effects_case`).

    Asserted: every identifiable offset within 3 sigma of truth + delta, with the sigma of the
    corner noise alone (the reported one divided by the variance factor); the plain claim
    "within 3 sigma of truth" fails although robocal scales its sigmas by the variance factor (the
    effects are biases, not noise: the message says "still optimistic"); the variance factor
    flags the misfit. Measured: effects 2.75 px RMS before the fit, variance factor 2.9, bias up to
    0.12 deg, naive max |z| 25 (scaled sigmas), corrected max 1.04 (noise sigmas)."""
    from robocal.sim.cameras.self_calibration_effects import nao_effects_case

    c = nao_effects_case(n_per_arm=N_PER_ARM, pixel_noise=NOISE_PX, seed=5)
    res, z_naive, z_noise = c["result"], c["z_naive"], c["z_noise"]
    assert res.converged and res.variance_factor > 1.5, res.message
    assert "effects the model lacks" in res.message
    assert c["has_length_errors"]
    assert c["effect_rms_px"] > 3 * NOISE_PX  # the effects are far above the corner noise
    assert len(c["names"]) == 9
    # against the corner-noise sigma (the reported one divided by the variance factor): the
    # tighter test; the reported, scaled sigma passes a fortiori
    assert np.abs(z_noise).max() < 3.0, z_noise
    assert np.abs(z_naive).max() > 5.0, z_naive
