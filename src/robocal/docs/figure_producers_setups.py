"""Producers of documented figures measured on a test's own set-up (no workflow function runs it):
the set-up rebuilt here with the library, seeded as in the test (:mod:`robocal.docs.figures`). Each
returns a flat ``{field: value}`` dict and is cached."""

from __future__ import annotations

import functools

__all__ = ["SETUP_PRODUCERS", "thermal_system_calibration"]


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

    from ..robots import load_robot
    from ..thermal import compare_system_calibrations, design_sphere_poses, predict_sphere
    from ..transforms import invert_transforms, rot_x, so3_exp

    kuka = load_robot("kuka_kr150_r3100")
    P_e = np.array([25.0, -40.0, 160.0])
    centre = np.array([1900.0, 300.0, 700.0])
    keys = ("rotation_deg", "at_point_mm", "sensor_origin_mm", "translation_mm", "P_e_mm")
    runs = {"ls": [], "thesis": []}
    for seed in range(20):
        rng = np.random.default_rng(seed)
        T_bs = np.eye(4)
        T_bs[:3, :3] = so3_exp(np.array([0.0, 0.0, rng.uniform(-3, 3)])) @ rot_x(np.pi) @ so3_exp(rng.normal(0, 0.2, 3))
        T_bs[:3, 3] = centre + [0.0, 0.0, -700.0]
        T_sb = invert_transforms(T_bs)
        q = design_sphere_poses(kuka, centre, P_e, 9, rng, spread_mm=(250.0, 200.0, 150.0), tilt_deg=60)
        P = predict_sphere(kuka, T_sb, P_e, q) + rng.normal(0, 0.02, (9, 3))
        c = compare_system_calibrations(kuka, q, P, T_sensor_base_true=T_sb, P_e_true=P_e, point_sigma_mm=0.02)
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


SETUP_PRODUCERS = {"system_calibration/thermal": thermal_system_calibration}
