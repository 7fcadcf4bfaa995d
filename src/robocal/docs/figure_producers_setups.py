"""Producers of documented figures measured on a test's own set-up (no workflow function runs it):
the set-up rebuilt here with the library, seeded as in the test (:mod:`robocal.docs.figures`). Each
returns a flat ``{field: value}`` dict and is cached."""

from __future__ import annotations

import functools

__all__ = ["SETUP_PRODUCERS", "elastic_correct_closed_loop", "elastic_joint_round_trip", "handeye_rendered",
           "self_calibration_industrial", "thermal_system_calibration"]


@functools.lru_cache(maxsize=None)
def thermal_system_calibration() -> dict:
    """docs/thermal.md "Measured accuracy" (the set-up of ``tests/test_thermal_core.py``'s
    ``test_system_calibration_accuracy_at_0_02_mm_noise``): KR150 R3100, a sensor 700 mm below a
    500 x 400 x 300 mm volume centred at (1900, 300, 700) mm with a random roll and tilt, the sphere
    at (25, -40, 160) mm on the flange, 9 designed poses (tilts up to 60 deg), 0.02 mm noise, seeds
    0-19; both methods of ``compare_system_calibrations``.

    Fields ``{ls|thesis}.{seeds8_mean|seeds8_max|seeds20_mean}.{measure}`` and
    ``wins.{measure}`` (seeds of 20 where least squares is better), measures ``rotation_deg``,
    ``at_point_mm``, ``sensor_origin_mm``, ``translation_mm``, ``P_e_mm``."""
    import numpy as np

    keys = SYSTEM_MEASURES
    runs = {"ls": [], "thesis": []}
    for seed in range(20):
        c = system_calibration_seed(seed)
        runs["ls"].append([c.errors["least-squares"][k] for k in keys])
        runs["thesis"].append([c.errors["thesis-penalty"][k] for k in keys])
    out = {}
    for m, rows in runs.items():
        a = np.asarray(rows)
        for stat, v in (("seeds8_mean", a[:8].mean(axis=0)), ("seeds8_max", a[:8].max(axis=0)),
                        ("seeds20_mean", a.mean(axis=0))):
            out.update({f"{m}.{stat}.{k}": float(x) for k, x in zip(keys, v)})
    wins = (np.asarray(runs["ls"]) < np.asarray(runs["thesis"])).sum(axis=0)
    out.update({f"wins.{k}": float(w) for k, w in zip(keys, wins)})
    return out


@functools.lru_cache(maxsize=None)
def handeye_rendered() -> dict:
    """docs/handeye.md "Acceptance on rendered images" (the set-up of ``tests/test_handeye_images.py``):
    15 rendered 1280 x 1024 views of ``charuco:9x7:30mm:22mm:DICT_5X5_100`` (seed 5), detected, 0.3 px
    corner noise added, 0.05 mm / 0.01 deg robot pose noise; robocal's refined hand-eye and OpenCV
    end to end on the same detections (``solvePnP``, then every ``calibrateHandEye`` method and
    ``calibrateRobotWorldHandEye``). Fields ``detection_rms_px`` and
    ``{eye_in_hand|eye_to_hand}.{robocal|TSAI|PARK|HORAUD|ANDREFF|DANIILIDIS|RW_SHAH|RW_LI}.{rot_deg|trans_mm}``."""
    import numpy as np

    from ..handeye import refine_hand_eye
    from ..io.boards import board_image, parse_board
    from ..io.detection import detect_board
    from ..sim.cameras.camera_cell import simulate_hand_eye_poses
    from ..sim.cameras.camera_render import BoardRenderer
    from ..transforms import rotation_angle
    from ..workflows.cameras.camera_simulate import _texel_mm
    from .opencv_reference import opencv_hand_eye_solutions

    board = parse_board("charuco:9x7:30mm:22mm:DICT_5X5_100")
    X = board.object_points()
    truths = {s: simulate_hand_eye_poses(X, setup=s, n_images=15, front_z=board.front_z, seed=5)
              for s in ("eye_in_hand", "eye_to_hand")}
    a = truths["eye_in_hand"]
    texture, affine = board_image(board, _texel_mm(board))
    renderer = BoardRenderer(a.camera, texture, affine)
    rng = np.random.default_rng(5)
    uv = np.array([detect_board(renderer.render(T, rng), board).image_points for T in a.T_camera_target])
    exact = np.einsum("nij,pj->npi", a.T_camera_target[:, :3, :3], X) + a.T_camera_target[:, None, :3, 3]
    projected = a.camera.project(exact.reshape(-1, 3)).pixels.reshape(uv.shape)
    out = {"detection_rms_px": float(np.sqrt(np.nanmean(np.sum((uv - projected) ** 2, axis=2))))}
    uv = uv + rng.normal(0.0, 0.3, uv.shape)
    for setup, truth in truths.items():
        cam, F = truth.camera, truth.T_base_flange
        found = {"robocal": refine_hand_eye(F, uv, X, cam, setup=setup).camera_pose}
        found.update(opencv_hand_eye_solutions(F, uv, X, cam, setup))
        for k, T in found.items():
            out[f"{setup}.{k}.rot_deg"] = float(np.degrees(rotation_angle(T[:3, :3].T @ truth.camera_pose[:3, :3])))
            out[f"{setup}.{k}.trans_mm"] = float(np.linalg.norm(T[:3, 3] - truth.camera_pose[:3, 3]))
    return out


@functools.lru_cache(maxsize=None)
def self_calibration_industrial() -> dict:
    """docs/self-calibration.md "Industrial variant": ``compare_with_tracker(KR 150 R3100,
    n_poses=30, seed=s)`` for s = 0-4, flattened as ``{s}.{field}``, and over the seeds ``min.`` /
    ``max.`` of ``removed_percent`` (100 (1 - self-calibration / nominal)), ``self_calibration_mm``,
    ``ratio_same_poses``, ``ratio_random_poses``; ``n_not_converged`` (all fits)."""
    from ..robots import load_robot
    from ..sim.cameras.self_calibration_study import compare_with_tracker

    rows = [compare_with_tracker(load_robot("kuka_kr150_r3100"), n_poses=30, seed=s) for s in range(5)]
    out = {}
    for r in rows:
        r = {**r, "removed_percent": 100.0 * (1.0 - r["self_calibration_mm"] / r["nominal_mm"])}
        out.update({f"{r['seed']}.{k}": float(v) for k, v in r.items() if isinstance(v, (int, float))})
    for k in ("removed_percent", "self_calibration_mm", "ratio_same_poses", "ratio_random_poses"):
        vals = [out[f"{s}.{k}"] for s in range(5)]
        out[f"min.{k}"], out[f"max.{k}"] = min(vals), max(vals)
    out["n_not_converged"] = float(sum(r["n_not_converged"] for r in rows))
    return out


@functools.lru_cache(maxsize=None)
def elastic_joint_round_trip() -> dict:
    """docs/elastic.md "Round trip" (``tests/test_elastic.py``'s
    ``test_simulated_elastic_robot_round_trip_reaches_the_noise_floor``,
    :func:`robocal.sim.elastic_campaigns.kr150_elastic_campaign`, seeds 0 and 1: 100 training + 100
    holdout poses, mass model and payload known, compliances hidden): geometry and joint compliance
    identified together, the holdout judged against the true reflector positions.

    Fields ``{truth}.{seed}.holdout_rms_mm`` and ``{truth}.{seed}.optimum_mm`` (the noise-limited
    optimum) for ``truth`` = ``realistic`` (torques at the deflected pose, 0.2 % stiffening at 10 kNm:
    effects the model lacks) and ``modelled`` (a truth without them); ``n_not_converged``."""
    import numpy as np

    from ..calib import CalibrationProblem, Target, solve
    from ..calib.elastic import ElasticModel, Payload
    from ..sim.elastic_campaigns import KR150_MASSES, KR150_PAYLOAD, SIGMA_MM, kr150_elastic_campaign, kr150_elastic_truth
    from .figure_producers_datasets import _expected_holdout_rms

    elastic = ElasticModel(masses=KR150_MASSES, payload=Payload(KR150_PAYLOAD[1], KR150_PAYLOAD[2], "flange"),
                           compliance_initial=0.0)
    out, failed = {}, 0
    for label, unmodelled in (("realistic", True), ("modelled", False)):
        for seed in (0, 1):
            c = kr150_elastic_campaign(seed, truth=kr150_elastic_truth(unmodelled=unmodelled))
            n = c.n_train
            prob = CalibrationProblem(c.nominal, c.q[:n], [Target("r1", None, (0.0, 0.0, 50.0))], c.points[:n],
                                      point_sigma_mm=SIGMA_MM, base_initial="fit", elastic=elastic)
            res = solve(prob)
            failed += not res.converged
            pred = prob.predict_points(res.state, q=c.q[n:])
            out[f"{label}.{seed}.holdout_rms_mm"] = float(np.sqrt(np.mean(np.sum((pred - c.true_points[n:]) ** 2, axis=-1))))
            out[f"{label}.{seed}.optimum_mm"] = _expected_holdout_rms(prob, res, c.q[n:], SIGMA_MM)
    out["n_not_converged"] = float(failed)
    return out


@functools.lru_cache(maxsize=None)
def elastic_correct_closed_loop() -> dict:
    """docs/elastic.md "robocal correct ... --payload" (``tests/test_elastic.py``'s
    ``test_calibrate_elastic_then_correct_puts_the_deflecting_robot_on_target``, the cell of
    :func:`robocal.sim.elastic_campaigns.kr150_correction_cell`): ``robocal calibrate --elastic joint
    --payload 120@0,50,200 --noise 0.02`` on 120 simulated poses, then ``robocal correct`` of five
    flange targets with and without ``--payload``; where the true deflecting robot lands.

    Fields ``elastic_mm`` / ``rigid_mm``: the largest distance [mm] from a target to the reached
    flange with / without the deflection compensation; ``exit_code`` (calibrate's)."""
    import tempfile
    from pathlib import Path

    from click.testing import CliRunner

    from ..cli.main import main
    from ..io.measurements import write_measurements
    from ..sim.elastic_campaigns import (kr150_correction_cell, kr150_mass_model_file, reached_error_mm,
                                         write_flange_targets)

    out = {}
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        path, _ = kr150_mass_model_file(tmp)
        robot, tracker, measurements = kr150_correction_cell(path)
        write_measurements(tmp / "m.csv", measurements)
        run = CliRunner().invoke(main, ["calibrate", str(path), str(tmp / "m.csv"), "--out", str(tmp / "cal"),
                                        "--elastic", "joint", "--payload", "120@0,50,200", "--noise", "0.02"])
        out["exit_code"] = float(run.exit_code)
        T_goal = write_flange_targets(robot, tracker, tmp / "t.csv")
        for label, extra in (("elastic", ["--payload", "120@0,50,200"]), ("rigid", [])):
            corrected = tmp / f"corr_{label}.csv"
            r = CliRunner().invoke(main, ["correct", str(tmp / "cal" / "calibrated_robot.toml"), str(tmp / "t.csv"),
                                          "--out", str(corrected)] + extra)
            out[f"{label}_mm"] = float(reached_error_mm(robot, tracker, corrected, T_goal).max()) if r.exit_code == 0 \
                else float("nan")
    return out


SETUP_PRODUCERS = {"self_calibration/industrial": self_calibration_industrial,
                   "system_calibration/thermal": thermal_system_calibration, "handeye/rendered": handeye_rendered,
                   "elastic/joint_round_trip": elastic_joint_round_trip,
                   "elastic/correct_closed_loop": elastic_correct_closed_loop}


#: the measures of :func:`system_calibration_seed`
SYSTEM_MEASURES = ("rotation_deg", "at_point_mm", "sensor_origin_mm", "translation_mm", "P_e_mm")


def system_calibration_seed(seed: int, true_model=None):
    """One seed of the thermal system-calibration set-up (``tests/test_thermal_core.py``): KR150 R3100,
    a sensor 700 mm below a volume centred at (1900, 300, 700) mm with a random roll and tilt, the
    sphere at (25, -40, 160) mm on the flange, 9 designed poses (tilts up to 60 deg), 0.02 mm noise;
    ``true_model``: the robot that moves (default: the nominal one). Returns
    ``compare_system_calibrations``'s result (both methods)."""
    import numpy as np

    from ..robots import load_robot
    from ..thermal import compare_system_calibrations, design_sphere_poses, predict_sphere
    from ..transforms import invert_transforms, rot_x, so3_exp

    kuka = load_robot("kuka_kr150_r3100")
    P_e, centre = np.array([25.0, -40.0, 160.0]), np.array([1900.0, 300.0, 700.0])
    rng = np.random.default_rng(seed)
    T_bs = np.eye(4)
    T_bs[:3, :3] = so3_exp(np.array([0.0, 0.0, rng.uniform(-3, 3)])) @ rot_x(np.pi) @ so3_exp(rng.normal(0, 0.2, 3))
    T_bs[:3, 3] = centre + [0.0, 0.0, -700.0]
    T_sb = invert_transforms(T_bs)
    q = design_sphere_poses(kuka, centre, P_e, 9, rng, spread_mm=(250.0, 200.0, 150.0), tilt_deg=60)
    P = predict_sphere(kuka if true_model is None else true_model, T_sb, P_e, q) + rng.normal(0, 0.02, (9, 3))
    return compare_system_calibrations(kuka, q, P, T_sensor_base_true=T_sb, P_e_true=P_e, point_sigma_mm=0.02)
