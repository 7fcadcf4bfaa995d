"""Tool-frame formulas of thesis ch. 4 against independent computations (simulated truth or
hand-derived cases): touch-up 4/7-point, parallel barriers, sensor calibration, beta, tool data, CLI."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from click.testing import CliRunner

from robocal.cli.tcp import tcp as tcp_cli
from robocal.io.tcp_files import TcpFileError, read_flange_poses_csv, read_sensor_points_csv, write_sensor_points_csv
from robocal.tcp import (
    DegenerateToolPosesError,
    R_FLANGE_STEP3,
    R_FLANGE_STEP12,
    SENSOR_POINT_LABELS,
    beam_distances_from_center,
    beam_point,
    beta_error_mm,
    beta_error_threshold_deg,
    calibrate_sensor,
    center_from_beam_distances,
    common_perpendicular,
    flange_rotation_for_vertical_tool,
    four_point_tcp,
    four_point_tcp_from_poses,
    orthogonal_to_skew,
    parallel_barriers_tool,
    seven_point_tool_frame,
    skew_to_orthogonal,
    sphere_center,
    tool_axis_from_barriers,
    tool_data,
    tool_data_all,
    tool_rotation_5d,
)
from robocal.sim.tool.touch_poses import P_REF_MM, TCP_TRUE_MM, touch_poses
from robocal.tcp.tool_data import CONTROLLERS
from robocal.transforms import pose_from_transform, rot_axis, rot_x, rot_y, rot_z, transform_from_pose


def _angle_deg(a, b) -> float:
    a = np.asarray(a) / np.linalg.norm(a)
    b = np.asarray(b) / np.linalg.norm(b)
    return math.degrees(math.atan2(np.linalg.norm(np.cross(a, b)), float(a @ b)))


def _transform(R, p):
    T = np.eye(4)
    T[:3, :3], T[:3, 3] = R, p
    return T


# ---------------------------------------------------------------------------------------------
# 4-point
# ---------------------------------------------------------------------------------------------

TCP_TRUE = TCP_TRUE_MM
P_REF = P_REF_MM
_touch_poses = touch_poses  # written once in robocal.sim.tool.touch_poses (also docs/reliability.md's producer)


def test_sphere_center_hand_case():
    c0 = np.array([1.0, -2.0, 3.0])
    pts = c0 + 5.0 * np.array([[1, 0, 0], [0, 1, 0], [0, 0, 1], [-1, 0, 0], [0, 0.6, 0.8]])
    c, r = sphere_center(pts)
    assert np.allclose(c, c0, atol=1e-12) and r == pytest.approx(5.0)
    # coplanar points: the linear system (4-2) has rank 2
    assert sphere_center(pts[:, :] * [1, 1, 0])[0] is None


def test_four_point_exact_n4():
    rng = np.random.default_rng(1)
    T = _touch_poses(4, rng)
    res = four_point_tcp(T)
    assert np.allclose(res.tcp_mm, TCP_TRUE, atol=1e-8)
    assert np.allclose(res.reference_point_mm, P_REF, atol=1e-8)
    assert res.residuals_mm.shape == (4,) and res.residuals_mm.max() < 1e-8
    # the sphere fit (4-2) finds P_ref with radius |t|
    assert np.allclose(res.sphere_center_mm, P_REF, atol=1e-6)
    assert res.sphere_radius_mm == pytest.approx(np.linalg.norm(TCP_TRUE), abs=1e-6)
    # independent check: the thesis's route, t from R_i t = P_ref - p_i with the sphere centre
    R, p = T[:, :3, :3], T[:, :3, 3]
    t_thesis = np.linalg.lstsq(R.reshape(-1, 3), (res.sphere_center_mm - p).reshape(-1), rcond=None)[0]
    assert np.allclose(t_thesis, TCP_TRUE, atol=1e-6)


def test_four_point_n12_noise_and_residuals():
    rng = np.random.default_rng(2)
    T = _touch_poses(12, rng, noise=0.05)
    res = four_point_tcp(T)
    err = np.linalg.norm(res.tcp_mm - TCP_TRUE)
    assert err < 0.1, err                          # within the pose noise
    assert np.all(np.abs(res.tcp_mm - TCP_TRUE) < 4 * res.tcp_std_mm + 1e-3)
    # residuals: 3N - 6 dof -> rms ~ 0.05 sqrt(3 (N-2)/N)
    assert 0.02 < res.rms_mm < 0.12
    # residual vectors are R_i t + p_i - P_ref, recomputed independently
    r = np.einsum("nij,j->ni", T[:, :3, :3], res.tcp_mm) + T[:, :3, 3] - res.reference_point_mm
    assert np.allclose(r, res.residual_vectors_mm) and np.allclose(np.linalg.norm(r, axis=1), res.residuals_mm)
    # a pose that missed the point by 2 mm stands out
    T2 = _touch_poses(12, np.random.default_rng(2), noise=0.0)
    T2[5, :3, 3] += [2.0, 0.0, 0.0]
    assert int(np.argmax(four_point_tcp(T2).residuals_mm)) == 5


def test_four_point_from_controller_conventions():
    rng = np.random.default_rng(3)
    T = _touch_poses(6, rng)
    for conv, lu, au in (("kuka_abc", "mm", "deg"), ("fanuc_wpr", "mm", "deg"), ("zxz", "mm", "deg"),
                         ("quaternion", "mm", "deg"), ("rotvec", "m", "rad")):
        values = pose_from_transform(T, conv, lu, au)
        res = four_point_tcp_from_poses(values, conv, lu, au)
        assert np.allclose(res.tcp_mm, TCP_TRUE, atol=1e-6), conv


def test_thesis_4_3_is_zxz():
    A, B, C = np.radians([30.0, 40.0, 50.0])
    cA, sA, cB, sB, cC, sC = np.cos(A), np.sin(A), np.cos(B), np.sin(B), np.cos(C), np.sin(C)
    T43 = np.array([[cA * cC - sA * cB * sC, -cA * sC - sA * cB * cC, sA * sB],
                    [sA * cC + cA * cB * sC, -sA * sC + cA * cB * cC, -cA * sB],
                    [sB * sC, sB * cC, cB]])
    assert np.allclose(transform_from_pose([0, 0, 0, 30, 40, 50], "zxz")[:3, :3], T43)


def test_four_point_degenerate_orientations_raise():
    rng = np.random.default_rng(4)
    # rotations about one axis only (the base vertical through P_ref): TCP undetermined along it
    T = np.array([_transform(rot_z(a) @ rot_y(math.pi), P_REF - rot_z(a) @ rot_y(math.pi) @ TCP_TRUE)
                  for a in np.radians([0.0, 60.0, 120.0, 200.0])])
    with pytest.raises(DegenerateToolPosesError, match="orientation spread"):
        four_point_tcp(T)
    # nearly identical orientations
    with pytest.raises(ValueError, match=r"need >= 20 deg"):
        four_point_tcp(_touch_poses(6, rng, tilt_deg=(2.0, 4.0)))
    # the threshold is the caller's
    assert four_point_tcp(_touch_poses(6, rng, tilt_deg=(8.0, 10.0)), min_spread_deg=5.0).rms_mm < 1e-6
    with pytest.raises(ValueError, match="at least 4"):
        four_point_tcp(_touch_poses(3, rng))


# ---------------------------------------------------------------------------------------------
# 7-point (4-5)
# ---------------------------------------------------------------------------------------------


def test_seven_point_recovers_tool_orientation():
    R_ft = rot_z(math.radians(15.0)) @ rot_y(math.radians(-7.0)) @ rot_x(math.radians(4.0))
    t = np.array([3.0, -2.0, 150.0])
    # the operator turns the tool roughly base-aligned, then moves along the tool X and Z axes
    R_bt = rot_z(math.radians(2.0)) @ rot_x(math.radians(-1.5))
    R_bf = R_bt @ R_ft.T
    p5 = np.array([800.0, 0.0, 400.0])
    p6 = p5 + 60.0 * R_bt[:, 0]
    p7 = p6 + 45.0 * R_bt[:, 2]
    T567 = np.array([_transform(R_bf, p) for p in (p5, p6, p7)])
    res = seven_point_tool_frame(T567, t)
    assert np.allclose(res.T_flange_tool[:3, :3], R_ft, atol=1e-12)
    assert np.allclose(res.T_flange_tool[:3, 3], t)
    assert abs(res.orthogonality_error_deg) < 1e-9
    R = res.T_flange_tool[:3, :3]
    assert np.linalg.det(R) == pytest.approx(1.0) and np.allclose(R.T @ R, np.eye(3))
    # TCP points (4-5) computed independently
    assert np.allclose(res.tcp_points_mm[0], R_bf @ t + p5)
    # a Z move 1 deg off orthogonal: reported, Z kept, X corrected by 1 deg
    z_off = rot_axis(R_bt[:, 1], math.radians(1.0)) @ R_bt[:, 2]
    T567[2, :3, 3] = p6 + 45.0 * z_off
    res2 = seven_point_tool_frame(T567, t)
    assert res2.orthogonality_error_deg == pytest.approx(-1.0, abs=1e-9)
    assert np.allclose(R_bf @ res2.T_flange_tool[:3, 2], z_off)
    assert res2.x_correction_deg == pytest.approx(1.0, abs=1e-9)
    # moves must keep the flange orientation
    T567[1, :3, :3] = rot_z(math.radians(3.0)) @ R_bf
    with pytest.raises(ValueError, match="keep the flange orientation"):
        seven_point_tool_frame(T567, t)


def test_seven_point_cross_product_order_is_right_handed():
    # x = e_x, z = e_z  ->  Y = Z x X = e_y (X x Z would give -e_y, a left-handed frame)
    T = np.array([_transform(np.eye(3), p) for p in ([0, 0, 0], [10, 0, 0], [10, 0, 10])])
    res = seven_point_tool_frame(T, np.zeros(3))
    assert np.allclose(res.T_flange_tool[:3, :3], np.eye(3))


# ---------------------------------------------------------------------------------------------
# parallel light barriers (4-6, 4-7)
# ---------------------------------------------------------------------------------------------

H_UP, H_DOWN, BEAM_X = 500.0, 480.0, 700.0


def _barrier_events(R_bf, axis_f, offset_f, radius, y0=0.0, z_flange=None):
    """x of the flange origin where each beam (parallel to Y_b at x = BEAM_X) is blocked / freed
    while the flange moves along +X_b: the tool is the cylinder {offset + s axis, radius}."""
    a = R_bf @ axis_f
    out = {}
    for name, h in (("up", H_UP), ("down", H_DOWN)):
        nrm = np.cross([0.0, 1.0, 0.0], a)
        nrm /= np.linalg.norm(nrm)
        F0 = np.array([0.0, y0, z_flange])
        d0 = (F0 + R_bf @ offset_f - np.array([BEAM_X, 0.0, h])) @ nrm   # signed line distance at x_f = 0
        xs = sorted(((sgn * radius - d0) / nrm[0]) for sgn in (-1.0, 1.0))
        out[name] = xs
    return out


def test_parallel_barriers_axis_and_length():
    rng = np.random.default_rng(5)
    axis_f = np.array([0.09, -0.05, 1.0])
    axis_f /= np.linalg.norm(axis_f)
    L, r = 160.0, 3.0
    zf = H_UP + 100.0
    # steps 1-3 with a tool whose axis misses the flange origin (offset cancels in the midpoints)
    off = np.array([0.7, -0.4, 0.0])
    e12 = _barrier_events(R_FLANGE_STEP12, axis_f, off, r, z_flange=zf)
    e3 = _barrier_events(R_FLANGE_STEP3, axis_f, off, r, z_flange=zf)
    x_up = [*e12["up"], *e3["up"]]
    x_down = [*e12["down"], *e3["down"]]
    a = tool_axis_from_barriers(x_up, x_down, H_UP - H_DOWN)
    assert np.allclose(a / np.linalg.norm(a), axis_f, atol=1e-12)
    # the sign note after (4-6): without the minus the x component flips
    assert a[0] * axis_f[0] > 0
    # length (4-7): tool through the flange origin, turned vertical, tip descending onto the upper beam
    Rv = flange_rotation_for_vertical_tool(a)
    assert np.allclose(Rv @ axis_f, [0, 0, -1])
    ev = _barrier_events(Rv, axis_f, np.zeros(3), r, z_flange=zf)
    assert ev["up"][0] + ev["up"][1] == pytest.approx(ev["down"][0] + ev["down"][1])   # x_up5+6 = x_down5+6
    z7 = H_UP + L        # tip (at L along the vertical axis below the flange origin) reaches h_up
    res = parallel_barriers_tool(x_up, x_down, h_up_mm=H_UP, h_down_mm=H_DOWN, z7_mm=z7,
                                 x_up_vertical=ev["up"], x_down_vertical=ev["down"])
    assert res.length_mm == pytest.approx(L)
    assert np.allclose(res.tcp_mm, L * axis_f)
    assert res.tilt_deg == pytest.approx(_angle_deg(axis_f, [0, 0, 1]))
    assert res.vertical_residual_deg == pytest.approx(0.0, abs=1e-9)
    assert np.allclose(res.T_flange_tool[:3, 2], axis_f)
    # noisy events (0.01 mm): axis within ~0.05 deg for delta_h = 20 mm
    n = rng.normal(0, 0.01, (2, 4))
    res_n = parallel_barriers_tool(np.add(x_up, n[0]), np.add(x_down, n[1]), H_UP - H_DOWN)
    assert _angle_deg(res_n.axis, axis_f) < 0.1


def test_tool_rotation_5d_matches_4_10():
    psi, theta = math.radians(35.0), math.radians(8.0)
    R = rot_z(psi) @ rot_x(theta) @ rot_z(-psi)
    assert np.allclose(tool_rotation_5d(R[:, 2]), R)
    # expanded form of (4-10), third column
    assert np.allclose(R[:, 2], [math.sin(psi) * math.sin(theta), -math.cos(psi) * math.sin(theta), math.cos(theta)])


# ---------------------------------------------------------------------------------------------
# cross-laser sensor calibration (4-15 ... 4-27)
# ---------------------------------------------------------------------------------------------


def _line_events(Q0, d, pin_dir, move_dir, start, r):
    """Positions start + lam move_dir where the pin (axis start + w pin_dir, radius r) is at
    distance r from the beam line Q0 + s d: (blocked, freed) in the order of the motion."""
    c = np.cross(pin_dir, d)
    c /= np.linalg.norm(c)
    d0 = (start - Q0) @ c
    rate = move_dir @ c
    lams = sorted((sgn * r - d0) / rate for sgn in (-1.0, 1.0))
    return [start + lam * move_dir for lam in lams]


def _simulate_sensor(rng, beta_deg=88.0, tilt_deg=2.0, gap=0.6, r=3.0, noise=0.01, off_along=0.0):
    """Skewed, non-coplanar beams in a sensor tilted from the base; returns (points, truth)."""
    R_bs = rot_z(math.radians(5.0)) @ rot_axis([1.0, 1.0, 0.0], math.radians(tilt_deg))
    O = np.array([850.0, -120.0, 250.0])
    n = R_bs @ [1.0, 0.0, 0.0]
    m = R_bs @ [math.cos(math.radians(beta_deg)), math.sin(math.radians(beta_deg)), 0.0]
    p = R_bs @ [0.0, 0.0, 1.0]
    QX, QY = O - 0.5 * gap * p, O + 0.5 * gap * p        # X beam below, Y beam above
    pts = {}
    ez = np.array([0.0, 0.0, 1.0])
    for label, Q0, d, s, move in (("A", QX, n, -60.0, [0, 1.0, 0]), ("B", QX, n, 90.0, [0, 1.0, 0]),
                                  ("C", QY, m, -70.0, [1.0, 0, 0]), ("D", QY, m, 80.0, [1.0, 0, 0])):
        move = np.array(move)
        target = Q0 + s * d
        # 1/2: vertical pin moving horizontally along the base axis across the beam
        start = target - 25.0 * move + [0.0, 0.0, 40.0]
        e1, e2 = _line_events(Q0, d, ez, move, start, r)
        # 3/4: horizontal pin along the same base axis, moving down through the beam
        along = np.array([move[1], -move[0], 0.0])   # a horizontal direction roughly along the beam
        start = np.array([e1[0], e1[1], 0.0]) + 0.5 * (e2 - e1) * [1, 1, 0] + off_along * along
        start = start - 30.0 * move + [0.0, 0.0, target[2] + 20.0]
        e3, e4 = _line_events(Q0, d, move, -ez, start, r)
        for i, e in enumerate((e1, e2, e3, e4), 1):
            pts[f"{label}{i}"] = e + rng.normal(0.0, noise, 3)
    P, Q, _, _ = common_perpendicular(QX, QX + n, QY, QY + m)
    truth = dict(origin=0.5 * (P + Q), n=n, m=m, p=p, beta=beta_deg, gap=gap)
    return pts, truth


def test_common_perpendicular_hand_case_and_4_21():
    P, Q, t, s = common_perpendicular([-1, 0, 0], [2, 0, 0], [0, 3, 1], [0, 5, 1])
    assert np.allclose(P, [0, 0, 0]) and np.allclose(Q, [0, 0, 1])
    assert t == pytest.approx(1 / 3) and s == pytest.approx(-1.5)
    # against a brute-force minimization of (4-19)
    from scipy.optimize import minimize

    rng = np.random.default_rng(6)
    A, B, C, D = rng.normal(size=(4, 3)) * 50
    P, Q, t, s = common_perpendicular(A, B, C, D)
    f = lambda x: np.sum((A + x[0] * (B - A) - C - x[1] * (D - C)) ** 2)  # noqa: E731
    opt = minimize(f, [0.0, 0.0], tol=1e-14)
    assert np.allclose([t, s], opt.x, atol=1e-5)
    assert abs((Q - P) @ (B - A)) < 1e-8 and abs((Q - P) @ (D - C)) < 1e-8


def test_sensor_calibration_recovers_simulated_beams():
    pts, truth = _simulate_sensor(np.random.default_rng(7))
    cal = calibrate_sensor(pts)
    assert np.linalg.norm(cal.origin_mm - truth["origin"]) < 0.05
    assert _angle_deg(cal.x_axis, truth["n"]) < 0.02
    assert _angle_deg(cal.y_axis, truth["m"]) < 0.02
    assert _angle_deg(cal.z_axis, truth["p"]) < 0.02
    assert abs(cal.beta_deg - truth["beta"]) < 0.02
    assert abs(cal.gap_mm - truth["gap"]) < 0.05
    T = cal.T_base_sensor
    assert np.allclose(T[:3, :3].T @ T[:3, :3], np.eye(3)) and np.linalg.det(T[:3, :3]) == pytest.approx(1.0)
    assert np.allclose(T[:3, 3], cal.origin_mm) and np.allclose(T[:3, 1], cal.y_axis_orthogonal)
    # the derived beam points lie on the true beams (radius 3 mm cancelled)
    assert set(cal.to_dict()) >= {"origin_mm", "x_axis", "y_axis", "y_axis_orthogonal", "z_axis",
                                  "T_base_sensor", "beta_deg", "gap_mm"}


def test_sensor_calibration_exact_and_slope_refinement():
    # noise-free, 3/4 straight above the 1/2 midpoint: the thesis's (4-16) is exact
    pts, truth = _simulate_sensor(np.random.default_rng(8), noise=0.0)
    for refine in (True, False):
        cal = calibrate_sensor(pts, refine_height=refine)
        assert np.allclose(cal.origin_mm, truth["origin"], atol=1e-9)
        assert np.allclose(cal.y_axis, truth["m"], atol=1e-12)
        assert cal.gap_mm == pytest.approx(truth["gap"], abs=1e-9)
    # 3/4 recorded 8 mm along the beam from the midpoint: the thesis formula takes the beam's
    # height at the wrong place (beam tilted ~2 deg -> ~0.2 mm); the refinement removes it
    pts, truth = _simulate_sensor(np.random.default_rng(8), noise=0.0, off_along=8.0)
    plain = calibrate_sensor(pts, refine_height=False)
    refined = calibrate_sensor(pts)
    assert np.linalg.norm(plain.origin_mm - truth["origin"]) > 0.05
    assert np.allclose(refined.origin_mm, truth["origin"], atol=1e-8)
    assert np.allclose(refined.x_axis, truth["n"], atol=1e-10)
    # the midpoint of a block/unblock pair is independent of the pin radius
    p3, _ = _simulate_sensor(np.random.default_rng(8), noise=0.0, r=1.0)
    p9, _ = _simulate_sensor(np.random.default_rng(8), noise=0.0, r=9.0)
    assert np.allclose(beam_point(*[p3[f"A{i}"] for i in range(1, 5)]),
                       beam_point(*[p9[f"A{i}"] for i in range(1, 5)]), atol=1e-9)


def test_sensor_points_csv_roundtrip_and_errors(tmp_path):
    pts, _ = _simulate_sensor(np.random.default_rng(9))
    f = write_sensor_points_csv(tmp_path / "s.csv", pts)
    back = read_sensor_points_csv(f)
    assert all(np.allclose(back[k], pts[k], atol=1e-6) for k in SENSOR_POINT_LABELS)
    lines = f.read_text().splitlines()
    bad = tmp_path / "bad.csv"
    bad.write_text("\n".join(lines[:-1]) + "\n")
    with pytest.raises(TcpFileError, match="missing labels D4"):
        read_sensor_points_csv(bad)
    bad.write_text("\n".join(lines + [lines[-1]]) + "\n")
    with pytest.raises(TcpFileError, match=r"line \d+, column 'label': duplicate label 'D4'"):
        read_sensor_points_csv(bad)
    i = next(k for k, ln in enumerate(lines) if ln.startswith("B2,"))
    bad.write_text("\n".join(lines[:i] + ["B2,1.0,abc,3.0"] + lines[i + 1:]) + "\n")
    with pytest.raises(TcpFileError, match=rf"bad.csv, line {i + 1}, column 'y': 'abc' is not a number"):
        read_sensor_points_csv(bad)
    bad.write_text("lbl,x,y,z\n")
    with pytest.raises(TcpFileError, match="header must be 'label,x,y,z'"):
        read_sensor_points_csv(bad)


# ---------------------------------------------------------------------------------------------
# beta correction (4-28 ... 4-30)
# ---------------------------------------------------------------------------------------------


def test_beta_conversions_against_geometry():
    rng = np.random.default_rng(10)
    for _ in range(20):
        beta = math.radians(rng.uniform(80.0, 100.0))
        x, y = rng.uniform(-8, 8, 2)
        # independent: signed 2-D distances to the beams through the origin
        ex, ey = np.array([1.0, 0.0]), np.array([math.cos(beta), math.sin(beta)])
        cross = lambda a, b: a[0] * b[1] - a[1] * b[0]  # noqa: E731
        d_x = cross(ex, [x, y])           # + on the +Y' side of the X beam
        d_y = -cross(ey, [x, y])          # + on the +X side of the Y beam
        assert np.allclose(beam_distances_from_center(x, y, beta), (d_x, d_y))
        assert np.allclose(center_from_beam_distances(d_x, d_y, beta), (x, y))
        # thesis (4-28): oblique coordinates, and (4-29) from them
        u, v = d_y / math.cos(beta - math.pi / 2), d_x / math.sin(beta)
        assert np.allclose(orthogonal_to_skew(x, y, beta), (u, v))
        assert np.allclose(np.array([u, 0]) + v * ey, [x, y])           # point = u X_s + v Y_beam
        assert np.allclose(skew_to_orthogonal(u, v, beta), (x, y))
        assert np.allclose(u + d_x / math.tan(beta), x)                   # (4-29) as printed
    # at beta = 90 deg the correction vanishes: (x, y) = (d_y, d_x)
    assert np.allclose(center_from_beam_distances(2.0, -3.0, math.pi / 2), (-3.0, 2.0))


def test_beta_error_4_30_numbers():
    for beta_deg in (88.0, 89.5, 91.0, 93.0):
        b = math.radians(beta_deg)
        x2, _ = center_from_beam_distances(5.0, 5.0, b)
        assert beta_error_mm(5.0, b) == pytest.approx(5.0 - x2)
    assert beta_error_mm(5.0, math.radians(90.0)) == pytest.approx(0.0, abs=1e-15)
    assert abs(beta_error_mm(5.0, math.radians(91.2))) > 0.1
    assert abs(beta_error_mm(5.0, math.radians(88.8))) > 0.1
    assert abs(beta_error_mm(5.0, math.radians(91.1))) < 0.1
    below, above = beta_error_threshold_deg(0.1, 5.0)
    # the thesis says "beyond +-1.2 deg"; the exact thresholds are 1.135 deg (below) and 1.157 (above)
    assert 1.13 < below < 1.14 and 1.15 < above < 1.16
    # nearly odd in (beta - 90): the d_x / tan(beta) term dominates
    assert beta_error_mm(5.0, math.radians(92.0)) == pytest.approx(-beta_error_mm(5.0, math.radians(88.0)), rel=0.05)


# ---------------------------------------------------------------------------------------------
# tool data
# ---------------------------------------------------------------------------------------------


def test_tool_data_hand_case_and_roundtrip():
    T = _transform(rot_y(math.radians(20.0)), [1.0, 2.0, 150.0])
    d = tool_data_all(T)
    assert d["kuka"].as_dict() == pytest.approx({"X": 1, "Y": 2, "Z": 150, "A": 0, "B": 20, "C": 0}, abs=1e-9)
    assert d["fanuc"].as_dict() == pytest.approx({"X": 1, "Y": 2, "Z": 150, "W": 0, "P": 20, "R": 0}, abs=1e-9)
    c, s = math.cos(math.radians(10)), math.sin(math.radians(10))
    assert d["abb"].values == pytest.approx([1, 2, 150, c, 0, s, 0], abs=1e-9)
    assert d["ur"].values == pytest.approx([0.001, 0.002, 0.15, 0, math.radians(20), 0], abs=1e-12)
    assert d["kawasaki"].values == pytest.approx([1, 2, 150, 0, 20, 0], abs=1e-9)
    assert d["kuka"].text == "TOOL_DATA[1]={X 1.000,Y 2.000,Z 150.000,A 0.0000,B 20.0000,C 0.0000}"
    assert d["ur"].text.startswith("set_tcp(p[0.001000, 0.002000, 0.150000")
    R = rot_z(0.3) @ rot_y(-0.2) @ rot_x(0.7)
    T = _transform(R, [5.0, -3.0, 120.0])
    for name, (conv, lu, au, names, _) in CONTROLLERS.items():
        td = tool_data(T, name)
        assert len(td.values) == len(names)
        assert np.allclose(transform_from_pose(td.values, conv, lu, au or "deg"), T, atol=1e-9), name
    with pytest.raises(ValueError, match="unknown controller"):
        tool_data(T, "staubli")


# ---------------------------------------------------------------------------------------------
# CLI
# ---------------------------------------------------------------------------------------------


def _write_pose_csv(path, T, conv="kuka_abc", lu="mm", au="deg", labels=None):
    v = pose_from_transform(T, conv, lu, au)
    ori = ["qw", "qx", "qy", "qz"] if conv == "quaternion" else ["A", "B", "C"]
    rows = [f"# orientation: {conv}", f"# length_unit: {lu}", f"# angle_unit: {au}",
            ",".join(["pose", "x", "y", "z", *ori])]
    for i, row in enumerate(v):
        rows.append(",".join([labels[i] if labels else f"P{i + 1}", *(f"{x:.9f}" for x in row)]))
    path.write_text("\n".join(rows) + "\n")
    return str(path)


def test_cli_four_point(tmp_path):
    T = _touch_poses(6, np.random.default_rng(11))
    f = _write_pose_csv(tmp_path / "touch.csv", T)
    r = CliRunner().invoke(tcp_cli, ["four-point", f, "--json"])
    assert r.exit_code == 0, r.output
    d = json.loads(r.output)
    assert np.allclose(d["tcp_mm"], TCP_TRUE, atol=1e-5)
    assert list(d["residuals_mm"]) == [f"P{i}" for i in range(1, 7)]
    r = CliRunner().invoke(tcp_cli, ["four-point", f])
    assert r.exit_code == 0 and "residual per pose" in r.output and "P6" in r.output
    # degenerate -> one-line error
    Td = _touch_poses(5, np.random.default_rng(12), tilt_deg=(1.0, 2.0))
    r = CliRunner().invoke(tcp_cli, ["four-point", _write_pose_csv(tmp_path / "deg.csv", Td)])
    assert r.exit_code == 1 and r.output.startswith("Error: flange orientations too similar")
    assert r.output.count("\n") == 1
    # a file without the convention header
    (tmp_path / "nohdr.csv").write_text("pose,x,y,z,a,b,c\n1,0,0,0,0,0,0\n")
    r = CliRunner().invoke(tcp_cli, ["four-point", str(tmp_path / "nohdr.csv")])
    assert r.exit_code == 1 and "orientation" in r.output and r.output.count("\n") == 1


def test_cli_seven_point_and_reader(tmp_path):
    rng = np.random.default_rng(13)
    T4 = _touch_poses(5, rng)
    R_ft = rot_z(math.radians(10.0))
    R_bf = rot_x(math.radians(1.0)) @ R_ft.T
    p5 = np.array([700.0, 50.0, 420.0])
    T567 = [_transform(R_bf, p) for p in (p5, p5 + [50, 0, 0], p5 + [50, 0, 40])]
    T = np.concatenate([T4, T567])
    f = _write_pose_csv(tmp_path / "seven.csv", T, conv="quaternion", lu="m", au="rad")
    poses = read_flange_poses_csv(f)
    assert np.allclose(poses.T_base_flange, T, atol=1e-6) and poses.convention == "quaternion"
    r = CliRunner().invoke(tcp_cli, ["seven-point", f, "--json"])
    assert r.exit_code == 0, r.output
    d = json.loads(r.output)
    Tft = np.array(d["T_flange_tool"])
    assert np.allclose(Tft[:3, 3], TCP_TRUE, atol=1e-4)
    assert np.allclose(R_bf @ Tft[:3, :3], np.eye(3), atol=1e-6)
    assert set(d["tool_data"]) == set(CONTROLLERS)
    r = CliRunner().invoke(tcp_cli, ["seven-point", f, "--tool", "12,-7,180"])
    assert r.exit_code == 0 and "TOOL_DATA[1]" in r.output and "set_tcp(p[" in r.output


def test_cli_parallel_barriers(tmp_path):
    axis_f = np.array([-0.04, 0.06, 1.0])
    axis_f /= np.linalg.norm(axis_f)
    e12 = _barrier_events(R_FLANGE_STEP12, axis_f, np.zeros(3), 3.0, z_flange=600.0)
    e3 = _barrier_events(R_FLANGE_STEP3, axis_f, np.zeros(3), 3.0, z_flange=600.0)
    f = tmp_path / "pb.toml"
    f.write_text(f"""length_unit = "mm"
h_up = {H_UP}
h_down = {H_DOWN}
x_up = {json.dumps([float(x) for x in (*e12['up'], *e3['up'])])}
x_down = {json.dumps([float(x) for x in (*e12['down'], *e3['down'])])}
z7 = {H_UP + 155.0}
""")
    r = CliRunner().invoke(tcp_cli, ["parallel-barriers", str(f), "--json"])
    assert r.exit_code == 0, r.output
    d = json.loads(r.output)
    assert np.allclose(d["axis"], axis_f) and d["length_mm"] == pytest.approx(155.0)
    assert np.allclose(d["tcp_mm"], 155.0 * axis_f)
    f.write_text('h_up = 1.0\nx_up = [1, 2, 3]\nx_down = [1, 2, 3, 4]\n')
    r = CliRunner().invoke(tcp_cli, ["parallel-barriers", str(f)])
    assert r.exit_code == 1 and "x_up" in r.output and r.output.count("\n") == 1


def test_cli_sensor_calibrate(tmp_path):
    pts, truth = _simulate_sensor(np.random.default_rng(14))
    f = write_sensor_points_csv(tmp_path / "sensor.csv", pts)
    r = CliRunner().invoke(tcp_cli, ["calibrate-sensor", str(f), "--json"])
    assert r.exit_code == 0, r.output
    d = json.loads(r.output)
    for key in ("origin_mm", "x_axis", "y_axis", "y_axis_orthogonal", "z_axis", "T_base_sensor", "beta_deg", "gap_mm"):
        assert key in d
    assert np.array(d["T_base_sensor"]).shape == (4, 4)
    assert np.linalg.norm(np.subtract(d["origin_mm"], truth["origin"])) < 0.05
    assert abs(d["beta_deg"] - 88.0) < 0.02
    r = CliRunner().invoke(tcp_cli, ["calibrate-sensor", str(f)])
    assert r.exit_code == 0 and "beta" in r.output
    r = CliRunner().invoke(tcp_cli, ["calibrate-sensor", str(tmp_path / "missing.csv")])
    assert r.exit_code == 1 and "file not found" in r.output
