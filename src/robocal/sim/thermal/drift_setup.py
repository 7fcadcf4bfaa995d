"""The thermal-core test cell (tests/test_thermal_core.py and docs/thermal.md's measured
identification and compensation figures): a KR150 R3100, a sensor 700 mm below a measurement volume,
a sphere off the joint-6 axis, and a screened-like subset of eight parameters with known warm deltas."""

from __future__ import annotations

import math

import numpy as np

from ...transforms import invert_transforms, rot_x, so3_exp

__all__ = ["CENTRE_MM", "DELTA", "FOV_MM", "P_E_MM", "SUBSET", "noisy_six_pose_fits", "off_model_system_calibration",
           "sensor_frame", "taught_program",
           "warm_params"]

P_E_MM = np.array([25.0, -40.0, 160.0])          # sphere on a stem, off the joint-6 axis [mm]
CENTRE_MM = np.array([1900.0, 300.0, 700.0])     # measurement volume centre, base frame [mm]
FOV_MM = (250.0, 200.0, 150.0)                   # half sizes of the volume (570 x 430 mm field of view)
#: the screened-like subset: lengths and angles (thesis table 5-1 style) and their true deltas [mm | rad]
SUBSET = ["a1", "a2", "a3", "d4", "d6", "beta2", "theta3", "alpha4"]
DELTA = np.array([0.10, 0.20, -0.15, 0.05, 0.12, math.radians(0.005), math.radians(-0.004), math.radians(0.005)])


def sensor_frame(rng) -> np.ndarray:
    """``T_sensor_base`` (4, 4) [mm]: a sensor 700 mm below the measurement volume looking up, with a
    random roll and tilt drawn from ``rng``."""
    T_bs = np.eye(4)
    T_bs[:3, :3] = so3_exp(np.array([0.0, 0.0, rng.uniform(-3, 3)])) @ rot_x(np.pi) @ so3_exp(rng.normal(0, 0.2, 3))
    T_bs[:3, 3] = CENTRE_MM + [0.0, 0.0, -700.0]
    return invert_transforms(T_bs)


def warm_params(model, names=SUBSET, delta=DELTA) -> np.ndarray:
    """The model's parameter vector with ``delta`` added to the parameters ``names``."""
    X = model.params.values.copy()
    for n, d in zip(names, delta):
        X[model.params.index(n)] += d
    return X


def taught_program(model, n: int, rng) -> np.ndarray:
    """``n`` taught joints (n, n_joints) [rad] well inside the limits and away from the wrist
    singularity (|q5| > 10 deg)."""
    lo, hi = model.limits[:, 0], model.limits[:, 1]
    q = rng.uniform(lo + 0.15 * (hi - lo), hi - 0.15 * (hi - lo), (4 * n, model.n_joints))
    q = q[np.abs(q[:, 4]) > math.radians(10)]
    return q[:n]


def noisy_six_pose_fits(model, seeds=range(10), noise_mm: float = 0.02) -> list:
    """The drift identification from 6 sphere poses (18 equations for the 8 deltas of ``SUBSET``) at
    ``noise_mm`` per coordinate, one fit per seed (``default_rng(100 + seed)``: the sensor frame, the
    poses, the noise): a list of :class:`~robocal.thermal.DriftResult` whose truth is ``DELTA``."""
    from ...thermal import design_sphere_poses, identify_drift, predict_sphere

    out = []
    for seed in seeds:
        rng = np.random.default_rng(100 + seed)
        T_sb = sensor_frame(rng)
        q = design_sphere_poses(model, CENTRE_MM, P_E_MM, 6, rng, spread_mm=FOV_MM, tilt_deg=60)
        Pw = predict_sphere(model, T_sb, P_E_MM, q, params=warm_params(model)) + rng.normal(0, noise_mm, (6, 3))
        out.append(identify_drift(model, T_sb, P_E_MM, q, Pw, subset=SUBSET, point_sigma_mm=noise_mm))
    return out


def off_model_system_calibration(model, seed: int, noise_mm: float = 0.02):
    """The system calibration (9 poses, ``noise_mm`` per coordinate) on a true robot 0.1 mm / 0.01 deg
    per parameter off ``model`` (``VirtualRobot.perturbed(model, 500 + seed)``; ``default_rng(seed)``
    draws the sensor, the poses and the noise), and the first-order bias of its ``P_e`` from the hidden
    truth: the last three components of ``J^+ e``, ``e`` the true robot's noise-free sphere centres
    minus the model's, ``J`` their Jacobian w.r.t. ``T_sensor_base`` and ``P_e`` at the solution
    (finite differences of ``predict_sphere``). Returns ``(result, bias (3,) [mm])``."""
    from ...thermal import calibrate_system, design_sphere_poses, predict_sphere
    from ..robot import VirtualRobot

    rng = np.random.default_rng(seed)
    T_sb = sensor_frame(rng)
    q = design_sphere_poses(model, CENTRE_MM, P_E_MM, 9, rng, spread_mm=FOV_MM, tilt_deg=60)
    true = VirtualRobot.perturbed(model, 500 + seed, length_sigma_mm=0.1, angle_sigma_deg=0.01,
                                  offset_sigma_deg=0.01).true_model
    P_true = predict_sphere(true, T_sb, P_E_MM, q)
    e = P_true - predict_sphere(model, T_sb, P_E_MM, q)
    r = calibrate_system(model, q, P_true + rng.normal(0, noise_mm, (9, 3)), point_sigma_mm=noise_mm)
    h = 1e-6
    base, cols = predict_sphere(model, r.T_sensor_base, r.P_e, q).ravel(), []
    for k in range(6):
        D = np.eye(4)
        D[:3, :3], D[:3, 3] = so3_exp(h * np.eye(6)[k, :3]), h * np.eye(6)[k, 3:]
        cols.append(predict_sphere(model, D @ r.T_sensor_base, r.P_e, q).ravel())
    cols += [predict_sphere(model, r.T_sensor_base, r.P_e + h * np.eye(3)[k], q).ravel() for k in range(3)]
    bias = np.linalg.lstsq((np.array(cols) - base).T / h, e.ravel(), rcond=None)[0][6:]
    return r, bias
