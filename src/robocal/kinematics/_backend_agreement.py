"""Every kinematics kernel's output for one robot at seeded random inputs, computed by both
backends (numpy, compiled): the comparison of ``tests/test_kernel_backends.py`` and of
docs/calibration.md "Kernels: numpy first" (written once, same draws)."""

from __future__ import annotations

import numpy as np

from . import _backend

__all__ = ["backend_difference", "every_kernel_output"]


def every_kernel_output(model, rng) -> list:
    """Target points and their Jacobian (half of the parameters free, points on random end
    effectors, a moved base), the same without the Jacobian, ``kinematics_with``, the twists, the FK
    of every end effector, the link frames, the one-pose FK and the geometric Jacobian, at 23 random
    configurations inside the limits (clipped to +-3 rad / mm) and parameters 1e-3 off nominal.

    Parameters
    ----------
    model : RobotModel
    rng : numpy.random.Generator

    Returns
    -------
    list of ndarray
        Each output as a float array (mm, rad, or their derivatives), in a fixed order.
    """
    n_e = len(model.end_effectors)
    lim = np.clip(np.asarray(model.limits, dtype=float), -3.0, 3.0)
    q = np.ascontiguousarray(rng.uniform(lim[:, 0], lim[:, 1], (23, model.n_joints)))
    free = np.sort(rng.choice(len(model.params), size=max(1, len(model.params) // 2), replace=False)).astype(np.int64)
    points = rng.normal(0.0, 50.0, (4, 3))
    ee = rng.integers(0, n_e, 4).astype(np.int64)
    root = np.eye(4)
    root[:3, :3] = np.linalg.qr(rng.normal(size=(3, 3)))[0]
    root[:3, 3] = (100.0, -50.0, 20.0)
    params = model.params.values + rng.normal(0.0, 1e-3, len(model.params))
    out = list(model.target_points(q, params, points, ee, free, root=root))
    out += list(model.target_points(q, params, points, ee, np.arange(len(model.params)), want_jacobian=False))
    out += list(model.kinematics_with(q, params, root))
    out += list(model.twists(q[:5]))
    out += [model.fk(q, e) for e in range(n_e)]
    out += [model.link_frames(q), model.fk(q[0]), model.jacobian(q[:3])]
    return [np.asarray(a, dtype=float) for a in out]


def backend_difference(model, seed: int = 3) -> dict:
    """:func:`every_kernel_output` by the compiled and by the numpy kernels (same draws), the mode
    restored afterwards.

    Returns
    -------
    dict
        ``compiled``, ``numpy`` (the two lists); ``max_abs`` the largest absolute difference over
        every output (mm, rad or their derivatives); ``max_relative`` the largest difference of an
        output divided by that output's largest magnitude.
    """
    old = _backend._mode
    results = {}
    try:
        for mode in ("compiled", "numpy"):
            _backend.set_kernels(mode)
            results[mode] = every_kernel_output(model, np.random.default_rng(seed))
    finally:
        _backend.set_kernels(old)
    diffs = [(float(np.max(np.abs(a - b))) if a.size else 0.0, float(np.max(np.abs(a))) if a.size else 0.0)
             for a, b in zip(results["compiled"], results["numpy"])]
    return {**results, "max_abs": max(d for d, _ in diffs),
            "max_relative": max((d / s for d, s in diffs if s > 0), default=0.0)}
