"""Cross-laser tool recalibration (thesis 4.2, 4.3.2) against the light-barrier simulator."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from click.testing import CliRunner

from robocal.io.barrier_events import read_events_csv, write_events_csv
from robocal.sim.tool.light_barrier import (CrossLaserSensor, CylinderTool, LightBarrier, LightBarrierCell,
                                       barrier_blocked)
from robocal.tcp.cross_laser import (CrossLaserSettings, angles_from_durations, axis_vector_thesis, center_distances,
                                     circle_center, euler_psi_theta, evaluate_circle, evaluate_recording,
                                     minimal_rotation, plan_axis_circles, psi_theta_from_axis,
                                     recalibrate_tool, rotation_5d, tcp_in_flange)
from robocal.tcp.sensor import beta_error_mm
from robocal.transforms import rot_x, rot_y, rot_z, so3_log, transforms_from

T_SENSOR_NOM = transforms_from(np.eye(3), [-850.0, -170.0, 200.0])
EXACT = dict(repeatability_mm=0.0, io_rate_hz=20000.0, latency_s=0.0)  # noise-free, fine sampling


def _sensor(beta=88.0, gap=0.3, tilt=2.0, yaw=0.5):
    return CrossLaserSensor.build(T_SENSOR_NOM, beta_deg=beta, gap_mm=gap, tilt_deg=tilt, tilt_axis_deg=30.0,
                                  yaw_deg=yaw)


def _straight_tool(offset_xy=(0.0, 0.0), length=180.0, radius=3.0, tip="spherical"):
    return CylinderTool(transforms_from(np.eye(3), [offset_xy[0], offset_xy[1], length]), radius, length, tip)


def _axis_err_deg(a, b):
    return math.degrees(math.acos(min(1.0, float(np.dot(a, b)))))


# ------------------------------------------------------------------------------- acceptance


@pytest.fixture(scope="module")
def study():
    from robocal.workflows.tool.recalibration import tcp_repeatability_study

    return tcp_repeatability_study(collisions=10, seed=0)


def test_acceptance_repeatability_study(study):
    """UR10-class, 0.1 mm repeatability, 1 kHz I/O, r = 3 mm, beta = 88 deg, sensor tilted 2 deg:
    10 collisions -> TCP RMS <= 0.2 mm, axis <= 0.1 deg (every run), cycle <= 15 s."""
    c = study["config"]
    assert (c["repeatability_mm"], c["io_rate_hz"], c["tool_radius_mm"], c["beta_deg"], c["tilt_deg"]) == \
        (0.1, 1000.0, 3.0, 88.0, 2.0)
    s = study["variants"]["beta_corrected"]["summary"]
    assert s["n"] == 10
    assert s["tcp_rms_mm"] <= 0.2
    assert s["axis_max_deg"] <= 0.1
    assert s["cycle_max_s"] <= 15.0
    # every motion reachable by the UR10 (numerical IK)
    assert study["reachability"]["checked"] and study["reachability"]["worst_position_error_mm"] < 1e-3
    # the collisions really bent the tool by degrees and millimetres
    assert all(1.0 <= d["tilt_deg"] <= 3.0 for d in study["collisions"])
    # 5-D: the full rotation error is the axis error (no twist; up to a second-order term)
    for r in study["variants"]["beta_corrected"]["runs"]:
        assert r["rotation_error_deg"] == pytest.approx(r["axis_error_deg"], abs=1e-4)


def test_beta_correction_matters(study):
    """Without the beta correction: with the thesis's step 3 (which measures the full lateral
    offset) the TCP error grows several-fold; with the null-centred step 3 the TCP is protected
    but the axis error still grows."""
    v = {k: x["summary"] for k, x in study["variants"].items()}
    ratio_tcp = v["thesis_step3_no_beta"]["tcp_rms_mm"] / v["thesis_step3"]["tcp_rms_mm"]
    ratio_axis = v["no_beta_correction"]["axis_rms_deg"] / v["beta_corrected"]["axis_rms_deg"]
    print(f"TCP RMS thesis step 3: {v['thesis_step3']['tcp_rms_mm']:.3f} -> {v['thesis_step3_no_beta']['tcp_rms_mm']:.3f} "
          f"mm (x{ratio_tcp:.1f}); axis RMS: {v['beta_corrected']['axis_rms_deg']:.3f} -> "
          f"{v['no_beta_correction']['axis_rms_deg']:.3f} deg (x{ratio_axis:.1f})")
    assert ratio_tcp > 2.0
    assert ratio_axis > 1.5
    assert v["thesis_step3"]["tcp_rms_mm"] <= 0.2


def test_beta_error_equals_4_30_noise_free():
    """Noise-free, thesis step 3 with a tool offset of several mm: the TCP error without the
    correction is the (4-30) error of the step-3 centre, and vanishes with the correction."""
    sensor = _sensor(beta=88.0, gap=0.0, tilt=2.0)
    tf = sensor.true_frame()
    nominal = _straight_tool()
    bent = CylinderTool(transforms_from(rot_x(math.radians(1.5)) @ rot_y(math.radians(-1.0)), [4.0, -6.0, 180.0]),
                        3.0, 180.0)
    out = {}
    for corr in (True, False):
        s = CrossLaserSettings(beta_correction=corr, step3_center="nominal")
        res = recalibrate_tool(LightBarrierCell(sensor, bent, 1, **EXACT), tf, nominal.T_flange_tool, s)
        out[corr] = res
    err_on = np.linalg.norm(out[True].tcp_flange_mm - bent.tcp_flange_mm)
    c3 = out[False].steps["circle3"]
    predicted = abs(float(beta_error_mm(c3.d_x_mm, math.radians(tf["beta_deg"]), c3.d_y_mm)))
    err_off = np.linalg.norm(out[False].tcp_flange_mm - bent.tcp_flange_mm)
    assert err_on < 0.01
    assert predicted > 0.1
    # plus a little from the axis tilted by the uncorrected steps 1-2 (cot(beta) x the centre
    # change between the circles / dz, times the 15 mm from the step-3 cut to the tip)
    assert err_off == pytest.approx(predicted, abs=0.03)


# ------------------------------------------------------------------------------- (4-8), (4-9)


def test_angles_from_durations_hand_case():
    a = angles_from_durations([1.0, 2.0, 3.0, 4.0])
    assert np.allclose(a, 2 * np.pi * np.array([0.1, 0.2, 0.3, 0.4]))
    assert a.sum() == pytest.approx(2 * np.pi)
    # centred circle: four right angles -> centre on the origin
    d_x, d_y = center_distances(np.full(4, np.pi / 2), 25.0)
    assert abs(d_x) < 1e-12 and abs(d_y) < 1e-12
    # centre: (d_y, d_x) without the beta correction, (4-29) with it
    b = math.radians(88.0)
    assert np.allclose(circle_center(3.0, 5.0, b, beta_correction=False), [5.0, 3.0])
    assert np.allclose(circle_center(3.0, 5.0, b), [5.0 / math.sin(b) + 3.0 / math.tan(b), 3.0])
    assert np.allclose(circle_center(3.0, 5.0, math.pi / 2), [5.0, 3.0])


def _one_circle(sensor, tool, *, direction=1, radius=25.0, settings_kw=None, rng=3, cell_kw=None):
    tf = sensor.true_frame()
    s = CrossLaserSettings(radius_mm=radius, direction=direction, **(settings_kw or {}))
    c1, _ = plan_axis_circles(tf, _straight_tool().T_flange_tool, s)  # flange circle centred above O_s
    cell = LightBarrierCell(sensor, tool, rng, **(cell_kw or EXACT))
    rec = cell.run(c1)
    return evaluate_circle(rec, tf, s), tf, c1


@pytest.mark.parametrize("beta", [90.0, 88.0, 93.0])
@pytest.mark.parametrize("direction", [1, -1])
@pytest.mark.parametrize("quadrant", [(1, 1), (-1, 1), (-1, -1), (1, -1)])
def test_4_9_signs_all_quadrants(quadrant, direction, beta):
    """Circle centre placed in each quadrant of the sensor frame: (4-9) gives the signed
    distances to the X beam (positive on +Y_s') and to the Y beam (positive on +X_s), and the
    (beta-corrected) centre is the true one."""
    sx, sy = quadrant
    cx, cy = 6.0 * sx, 4.0 * sy
    sensor = _sensor(beta=beta, gap=0.0, tilt=2.0)
    # thesis orientation: flange x = X_s, y = -Y_s -> a tool offset (ox, oy) appears at (ox, -oy)
    tool = _straight_tool((cx, -cy))
    res, tf, _ = _one_circle(sensor, tool, direction=direction)
    b = math.radians(tf["beta_deg"])
    true_dx = cy
    true_dy = cx * math.sin(b) - cy * math.cos(b)
    assert np.sign(res.d_x_mm) == sy and np.sign(res.d_y_mm) == np.sign(true_dy)
    assert res.d_x_mm == pytest.approx(true_dx, abs=0.01)
    assert res.d_y_mm == pytest.approx(true_dy, abs=0.01)
    assert np.allclose(res.center_mm, [cx, cy], atol=0.01)
    # the thesis's raw (4-9) (no arc correction) has the same signs, only a scale error cos(delta/2)
    raw = center_distances(res.angles_rad, 25.0)
    assert np.sign(raw[0]) == sy and np.sign(raw[1]) == np.sign(true_dy)
    # the tool-axis point in the flange frame is the tool offset
    assert np.allclose(res.axis_point_flange[:2], [cx, -cy], atol=0.01)


def test_4_8_angles_against_geometry():
    """A thin tool: the arcs (4-8) equal the central angles between the circle's crossings of
    the two beam lines, computed analytically."""
    sensor = _sensor(beta=88.0, gap=0.0, tilt=0.0, yaw=0.0)
    cx, cy, R = 5.0, -3.0, 25.0
    tool = _straight_tool((cx, -cy), radius=0.05)
    res, tf, _ = _one_circle(sensor, tool, radius=R, settings_kw={"arc_correction": False})
    b = math.radians(tf["beta_deg"])
    c = np.array([cx, cy])

    def crossings(d):  # angles phi where c + R u(phi) lies on the line through 0 along d
        n = np.array([-d[1], d[0]])
        s = float(n @ c) / R
        base = math.atan2(n[1], n[0])
        # n . u(phi) = -s  ->  phi = base +- acos(-s)
        return [base + math.acos(-s), base - math.acos(-s)]

    xs = crossings(np.array([1.0, 0.0]))
    ys = crossings(np.array([math.cos(b), math.sin(b)]))

    def label(phi, d, name):
        p = c + R * np.array([math.cos(phi), math.sin(phi)])
        return name + ("+" if p @ d > 0 else "-")

    pts = {label(p, np.array([1.0, 0]), "X"): p % (2 * np.pi) for p in xs}
    pts.update({label(p, np.array([math.cos(b), math.sin(b)]), "Y"): p % (2 * np.pi) for p in ys})
    arc = lambda a, z: (pts[z] - pts[a]) % (2 * np.pi)  # noqa: E731 counter-clockwise from a to z
    expected = [arc("X+", "Y+"), arc("Y+", "X-"), arc("X-", "Y-"), arc("Y-", "X+")]
    assert np.allclose(res.angles_rad, expected, atol=2e-3)


def test_arc_width_correction_is_exact():
    """With a thick tool the thesis's (4-9) scales the centre by cos(delta/2); the corrected one is exact."""
    sensor = _sensor(beta=90.0, gap=0.0, tilt=0.0, yaw=0.0)
    tool = _straight_tool((8.0, -6.0), radius=4.0)
    on, _, _ = _one_circle(sensor, tool)
    off, _, _ = _one_circle(sensor, tool, settings_kw={"arc_correction": False})
    assert np.allclose(on.center_mm, [8.0, 6.0], atol=0.005)
    assert np.linalg.norm(off.center_mm - [8.0, 6.0]) > 0.05


# ------------------------------------------------------------------------------- (4-10 ... 4-13)


def _rodrigues(k, angle):
    k = np.asarray(k, float) / np.linalg.norm(k)
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + math.sin(angle) * K + (1 - math.cos(angle)) * K @ K


@pytest.mark.parametrize("axis", [(0.05, -0.02, 1.0), (-0.3, 0.1, 0.9), (0.0, 0.2, 1.0), (-0.1, -0.1, 1.0),
                                  (0.6, 0.0, 0.8)])
def test_5d_frame_against_independent_construction(axis):
    a = np.array(axis) / np.linalg.norm(axis)
    psi, theta = psi_theta_from_axis(a)
    R = rotation_5d(psi, theta)
    # independent: rotation about z x a by the angle between z and a (no twist about the axis)
    ez = np.array([0.0, 0.0, 1.0])
    R_ind = _rodrigues(np.cross(ez, a), math.acos(a[2]))
    assert np.allclose(R, R_ind, atol=1e-12)
    assert np.allclose(R[:, 2], a, atol=1e-12)
    assert abs(so3_log(R) @ ez) < 1e-12                    # rotation axis perpendicular to the tool axis
    # the closed form printed in (4-10)
    c, s, ct, st = math.cos(psi), math.sin(psi), math.cos(theta), math.sin(theta)
    printed = np.array([[c * c + s * s * ct, s * c * (1 - ct), s * st],
                        [s * c * (1 - ct), s * s + c * c * ct, -c * st],
                        [-s * st, c * st, ct]])
    assert np.allclose(R, printed, atol=1e-12)
    # (4-13) applied to the mirrored vector (-a_x, -a_y, a_z) is the same (psi, theta)
    assert np.allclose(euler_psi_theta((-a[0], -a[1], a[2])), (psi, theta))
    assert np.allclose(minimal_rotation(ez, a), R, atol=1e-12)
    assert -math.pi <= psi < math.pi and 0 <= theta < math.pi


def test_thesis_chain_4_11_to_4_13_gives_true_axis():
    """Thesis set-up (flange X_e = X_s, Y_e = -Y_s, circles centred under the flange, circle 2
    dz lower): (4-12) as printed fed to (4-13) and (4-10) yields a frame whose z column is the
    simulator's true tool axis; (4-12) itself is the axis mirrored in x and y."""
    sensor = _sensor(beta=90.0, gap=0.0, tilt=0.0, yaw=0.0)
    tf = sensor.true_frame()
    bent = CylinderTool(transforms_from(rot_x(math.radians(2.0)) @ rot_y(math.radians(-1.5)), [1.0, 2.0, 180.0]),
                        3.0, 180.0)
    s = CrossLaserSettings()
    c1m, c2m = plan_axis_circles(tf, _straight_tool().T_flange_tool, s)
    cell = LightBarrierCell(sensor, bent, 1, **EXACT)
    r1 = evaluate_circle(cell.run(c1m), tf, s)
    r2 = evaluate_circle(cell.run(c2m), tf, s)
    v = axis_vector_thesis(r1.center_mm, r2.center_mm, s.delta_z_mm)
    a_true = bent.axis_flange
    assert np.allclose(v / np.linalg.norm(v), [-a_true[0], -a_true[1], a_true[2]], atol=1e-4)
    R = rotation_5d(*euler_psi_theta(v))
    assert _axis_err_deg(R[:, 2], a_true) < 0.005


# ------------------------------------------------------------------------------- step 4 (4-14)


def test_tcp_in_flange_hand_case():
    R = rot_z(0.7) @ rot_y(2.5) @ rot_x(-0.4)
    t = np.array([3.0, -7.0, 150.0])
    O = np.array([100.0, 200.0, 50.0])
    p_e = O - R @ t                                           # flange position with the TCP at O
    assert np.allclose(tcp_in_flange(O, p_e, R), t)
    assert not np.allclose(O - p_e, t, atol=1.0)              # the thesis's base-frame difference


def test_step4_tcp_in_flange_frame_angled_tool():
    """An angled tool (axis 35 deg off the flange Z) on a tilted sensor: the measuring flange
    orientation is far from the base's, and the TCP still comes out in the flange frame."""
    sensor = _sensor(beta=88.0, gap=0.4, tilt=2.0, yaw=0.5)
    tf = sensor.true_frame()
    R_nom = rot_x(math.radians(35.0)) @ rot_z(math.radians(20.0))
    tip_nom = R_nom @ np.array([0, 0, 160.0]) + np.array([0, 0, 40.0])
    nominal = CylinderTool(transforms_from(R_nom, tip_nom), 3.0, 160.0, "flat")
    bent, _ = nominal.collided(11)
    res = recalibrate_tool(LightBarrierCell(sensor, bent, 2, **EXACT), tf, nominal.T_flange_tool)
    assert np.linalg.norm(res.tcp_flange_mm - bent.tcp_flange_mm) < 0.01
    assert _axis_err_deg(res.axis_flange, bent.axis_flange) < 0.005
    assert np.allclose(res.T_flange_tool[:3, :3], bent.T_flange_tool[:3, :3], atol=1e-4)
    # the flange was far from base-aligned during step 4, so (4-14) in base coordinates is wrong
    vert = res.steps["vertical"]
    naive = tf["origin_mm"] - vert.flange_mean_mm
    assert np.linalg.norm(naive - bent.tcp_flange_mm) > 50.0
    assert abs(vert.gap_residual_mm) < 0.01


# ------------------------------------------------------------------------------- simulator


def test_barrier_blocked_hand_cases():
    beam = LightBarrier("x", [0, 0, 0], [1, 0, 0])
    base = np.array([[0, 2.5, 100.0], [0, 3.5, 100.0], [0, 0, 100.0], [0, 0, 100.0]])
    end = np.array([[0, 2.5, -10.0], [0, 3.5, -10.0], [0, 0, 1.0], [0, 0, 2.9]])
    # vertical tool, radius 3: 2.5 mm from the beam blocks, 3.5 does not; tool ending above the beam
    assert barrier_blocked(beam, base, end, 3.0, "flat").tolist() == [True, False, False, False]
    # spherical: end = ball centre; blocks when the ball (r = 3) reaches the beam
    assert barrier_blocked(beam, base, end, 3.0, "spherical").tolist() == [True, False, True, True]
    # flat tip (r = 1) tilted 45 deg across the beam: its rim dips below the beam's height beside
    # the beam (at y = 0.7), but the beam is blocked only once the face reaches the beam itself
    d = np.array([0, 1.0, 1.0]) / math.sqrt(2)
    tips = np.array([[0, 0, -0.5], [0, 0, 0.5], [0, 0, 2.0]])
    assert barrier_blocked(beam, tips + 50 * d, tips, 1.0, "flat").tolist() == [True, False, False]


def test_sensor_truth_and_collision_model():
    s = _sensor(beta=87.0, gap=0.6, tilt=2.0)
    tf = s.true_frame()
    assert tf["beta_deg"] == pytest.approx(87.0)
    assert tf["gap_mm"] == pytest.approx(0.6)
    assert np.allclose(tf["origin_mm"], T_SENSOR_NOM[:3, 3])
    assert _axis_err_deg(tf["z_axis"], [0, 0, 1]) == pytest.approx(2.0)
    tool = _straight_tool()
    bent, info = tool.collided(5)
    R = bent.T_flange_tool[:3, :3]
    assert np.allclose(R, minimal_rotation([0, 0, 1], R[:, 2]), atol=1e-12)  # no twist
    assert 1.0 <= _axis_err_deg(R[:, 2], [0, 0, 1]) <= 3.0
    bent2, _ = tool.collided(5)
    assert np.array_equal(bent.T_flange_tool, bent2.T_flange_tool)         # seeded


def test_latency_and_sampling_shift_events():
    sensor = _sensor(gap=0.0, tilt=0.0, yaw=0.0, beta=90.0)
    tool = _straight_tool()
    a, _, c1 = _one_circle(sensor, tool, cell_kw=dict(repeatability_mm=0.0, io_rate_hz=1000.0, latency_s=0.0))
    b, _, _ = _one_circle(sensor, tool, cell_kw=dict(repeatability_mm=0.0, io_rate_hz=1000.0, latency_s=0.02))
    # a constant latency shifts every edge by the same time: the angles do not change
    assert np.allclose(a.angles_rad, b.angles_rad, atol=2e-3)
    cell = LightBarrierCell(sensor, tool, 0, **EXACT)
    rec = cell.run(c1)
    assert all(abs(e.time_s * 20000 - round(e.time_s * 20000)) < 1e-6 for e in rec.events)
    assert cell.time_s == pytest.approx(c1.duration_s + cell.settle_s)


# ------------------------------------------------------------------------------- files and CLI


def test_events_file_round_trip(tmp_path):
    sensor = _sensor()
    tf = sensor.true_frame()
    nominal = _straight_tool()
    bent, _ = nominal.collided(3)
    res = recalibrate_tool(LightBarrierCell(sensor, bent, 4), tf, nominal.T_flange_tool)
    p = write_events_csv(tmp_path / "ev.csv", res.records)
    again = evaluate_recording(read_events_csv(p), tf, nominal.T_flange_tool)
    assert np.allclose(again.T_flange_tool, res.T_flange_tool, atol=1e-5)
    assert again.cycle_time_s == pytest.approx(res.cycle_time_s, abs=1e-6)
    bad = tmp_path / "bad.csv"
    bad.write_text(p.read_text().replace(",x,blocked,", ",z,blocked,", 1))
    with pytest.raises(ValueError, match="column 'barrier'"):
        read_events_csv(bad)


def test_cli_simulate_then_cross_laser(tmp_path):
    from robocal.cli.tcp_cross_laser import cross_laser_cmd, simulate_cmd

    runner = CliRunner()
    ev, sj = tmp_path / "sim" / "events.csv", tmp_path / "sim" / "sensor.json"
    r = runner.invoke(simulate_cmd, ["none", "--collisions", "1", "--seed", "3", "--out", str(tmp_path / "sim"),
                                     "--json"])
    assert r.exit_code == 0, r.output
    study = json.loads(r.stdout)
    assert set(study["variants"]) == {"beta_corrected", "no_beta_correction", "thesis_step3", "thesis_step3_no_beta"}
    r = runner.invoke(cross_laser_cmd, [str(ev), "--sensor", str(sj), "--json"])
    assert r.exit_code == 0, r.output
    out = json.loads(r.output)
    T_true = np.array(study["collisions"][0]["T_flange_tool_true"])
    assert np.linalg.norm(np.array(out["tcp_flange_mm"]) - T_true[:3, 3]) < 0.2
    r = runner.invoke(cross_laser_cmd, [str(ev), "--sensor", str(tmp_path / "missing.json")])
    assert r.exit_code != 0 and "not found" in r.output
    r = runner.invoke(simulate_cmd, ["none", "--collisions", "1", "--no-beta-correction"])
    assert r.exit_code == 0 and "beta_corrected" not in r.output and "no_beta_correction" in r.output
