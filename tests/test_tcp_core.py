"""The touch-up TCP fit (4-4) on the calibration core: the exact least-squares solution, a
covariance that matches the closed form and the Monte-Carlo spread, identifiability reports."""

import math

import numpy as np

from robocal.tcp import four_point_tcp
from robocal.tcp.touchup_fit import fit_touchup, touchup_problem
from robocal.transforms import rot_x, rot_y, rot_z

TCP_TRUE = np.array([12.0, -7.0, 180.0])
P_REF = np.array([900.0, 100.0, 300.0])


def _poses(n, rng, noise=0.0, tilt=(25.0, 45.0)):
    T = np.tile(np.eye(4), (n, 1, 1))
    for i in range(n):
        R = rot_z(2 * math.pi * i / n) @ rot_x(math.radians(rng.uniform(*tilt))) @ rot_y(math.pi) @ \
            rot_z(rng.uniform(-math.pi, math.pi))
        T[i, :3, :3] = R
        T[i, :3, 3] = P_REF - R @ TCP_TRUE + rng.normal(0.0, noise, 3)
    return T


def test_core_fit_is_the_linear_least_squares_solution():
    T = _poses(10, np.random.default_rng(0), noise=0.05)
    R, p = T[:, :3, :3], T[:, :3, 3]
    # closed form with P_ref eliminated, independent of the core
    D = (R - R.mean(axis=0)).reshape(-1, 3)
    t = np.linalg.lstsq(D, (p.mean(axis=0) - p).reshape(-1), rcond=None)[0]
    res = four_point_tcp(T)
    assert np.abs(res.tcp_mm - t).max() < 1e-9
    assert np.abs(res.reference_point_mm - (R.mean(axis=0) @ t + p.mean(axis=0))).max() < 1e-9
    r = np.einsum("nij,j->ni", R, t) + p - (R.mean(axis=0) @ t + p.mean(axis=0))
    cov_t = np.sum(r**2) / (3 * len(T) - 6) * np.linalg.inv(D.T @ D)
    assert np.allclose(res.covariance_mm2[:3, :3], cov_t, rtol=1e-8, atol=0)
    assert np.allclose(res.tcp_std_mm, np.sqrt(np.diag(cov_t)), rtol=1e-8)
    assert res.fit.problem.names == ("tcp.x", "tcp.y", "tcp.z", "P_ref.x", "P_ref.y", "P_ref.z")
    assert res.identifiability.dropped == [] and res.fit.converged


def test_reported_tcp_std_matches_the_monte_carlo_spread():
    rng = np.random.default_rng(1)
    T0 = _poses(8, rng)
    est, std = [], []
    for _ in range(300):
        T = T0.copy()
        T[:, :3, 3] += rng.normal(0.0, 0.05, (8, 3))
        f = fit_touchup(T, sigma_mm=0.05)  # known noise: absolute covariance
        est.append(f.value("tcp"))
        std.append(f.std[:3])
    spread = np.std(est, axis=0)
    assert np.all(np.abs(spread / np.mean(std, axis=0) - 1.0) < 0.15), (spread, np.mean(std, axis=0))
    assert np.allclose(np.mean(est, axis=0), TCP_TRUE, atol=3 * spread.max() / math.sqrt(300) + 1e-3)


def test_rotations_about_one_axis_are_explained_by_the_identifiability_report():
    # the threshold switched off: the core reports what the poses cannot determine
    a = np.radians([0.0, 60.0, 120.0, 200.0])
    T = np.tile(np.eye(4), (4, 1, 1))
    T[:, :3, :3] = np.array([rot_z(x) @ rot_y(math.pi) for x in a])
    T[:, :3, 3] = P_REF - T[:, :3, :3] @ TCP_TRUE
    res = four_point_tcp(T, min_spread_deg=0.0)
    (d,) = res.identifiability.dropped
    assert d["name"] == "P_ref.z" and d["trades_off_with"][0][0] == "tcp.z"
    assert np.isnan(res.covariance_mm2[5, 5])
    assert np.allclose(res.tcp_mm[:2], TCP_TRUE[:2], atol=1e-9)


def test_touchup_problem_starts_where_asked():
    T = _poses(5, np.random.default_rng(2))
    prob = touchup_problem(T, tcp0=[1.0, 2.0, 3.0])
    s0 = prob.initial_state()
    assert np.array_equal(prob.value(s0, "tcp"), [1.0, 2.0, 3.0])
    assert np.allclose(prob.value(s0, "P_ref"), T[:, :3, 3].mean(axis=0))
    assert prob.kinds == ("fixed_point",) and prob.n_residuals == 15
