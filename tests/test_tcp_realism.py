"""Light-barrier cell realism (issue 11): dirty beams, latency jitter, tool runout, the robot's
absolute error, the measuring arm; the parallel-barrier method through the simulator; and the
tool-frame repeatability / accuracy over 20 cells. Every random draw seeded."""

import math

import numpy as np
import pytest

from robocal.robots import load_robot
from robocal.sim.tool.barrier_effects import BarrierEffects, MeasuringArm, RobotAccuracy
from robocal.sim.tool.barrier_geometry import BeamDirt, barrier_blocked
from robocal.sim.tool.light_barrier import (
    CrossLaserSensor,
    CylinderTool,
    LightBarrier,
    LightBarrierCell,
    simulate_sensor_calibration_points,
)
from robocal.sim.tool.parallel_barrier_cell import (
    ParallelBarrierRig,
    measure_beam_heights,
    record_parallel_barriers,
    straight_tool,
)
from robocal.sim.robot import VirtualRobot
from robocal.tcp.cross_laser import CrossLaserSettings, recalibrate_tool
from robocal.tcp.parallel_barriers import parallel_barriers_tool
from robocal.transforms import rot_x, rot_y, transforms_from

EXACT = dict(repeatability_mm=0.0, io_rate_hz=20000.0, latency_s=0.0)
T_NOM = transforms_from(np.eye(3), [-850.0, -170.0, 200.0])
UR10_Q = np.array([0.0, -1.2, 1.6, -1.97, -1.57, 0.0])


def _sensor():
    return CrossLaserSensor.build(T_NOM, beta_deg=88.0, gap_mm=0.3, tilt_deg=2.0, tilt_axis_deg=30.0, yaw_deg=0.5)


# ------------------------------------------------------------------------------------------ dirt
def test_dirty_beam_blocks_earlier_from_the_clean_side():
    """Dust on the lower quarter of a 2 mm beam: a tool coming from above blocks 0.5 mm (f w)
    earlier, from below as on a clean beam, from the side 0.25 mm earlier (f w / 2)."""
    beam = LightBarrier("x", [0, 0, 0], [1, 0, 0])
    dirt = BeamDirt(0.25, 2.0, [0, 0, -1])
    r = 3.0

    def horizontal(z):                                      # tool axis along y, at height z
        return barrier_blocked(beam, [[0, -50, z]], [[0, 50, z]], r, "spherical", dirt)[0]

    def vertical(y):                                        # tool axis along z, beside the beam at y
        return barrier_blocked(beam, [[0, y, 100]], [[0, y, -100]], r, "spherical", dirt)[0]

    assert horizontal(r + 0.45) and not horizontal(r + 0.55)
    assert horizontal(-(r - 0.05)) and not horizontal(-(r + 0.05))
    assert vertical(r + 0.2) and not vertical(r + 0.3) and vertical(-(r + 0.2))
    clean = barrier_blocked(beam, [[0, -50, r + 0.45]], [[0, 50, r + 0.45]], r, "spherical")[0]
    assert not clean
    # the flat-ended cylinder widens the same way
    assert barrier_blocked(beam, [[0, -50, r + 0.45]], [[0, 50, r + 0.45]], r, "flat", dirt)[0]
    with pytest.raises(ValueError):
        BeamDirt(0.6, 2.0, [0, 0, -1])


def test_dirt_biases_the_calibrated_beam_height_by_half_its_reach():
    """The horizontal pin comes down from the clean side and leaves on the dirty side: the
    block/clear midpoint, the beam's measured height, is f w / 2 too high."""
    sensor = CrossLaserSensor.build(T_NOM)
    dirt = {k: BeamDirt(0.25, 2.0, [0, 0, -1]) for k in ("x", "y")}
    kw = dict(EXACT, io_rate_hz=5000.0)
    clean, _ = simulate_sensor_calibration_points(sensor, T_NOM, 1, **kw)
    dirty, _ = simulate_sensor_calibration_points(sensor, T_NOM, 1, dirt=dirt, **kw)
    for p in "ABCD":
        mid = lambda pts, p=p: 0.5 * (pts[f"{p}3"][2] + pts[f"{p}4"][2])  # noqa: E731
        assert mid(dirty) - mid(clean) == pytest.approx(0.25, abs=0.005)
        # the vertical pin crosses sideways: both edges move out by f w / 2, the midpoint stays
        np.testing.assert_allclose(0.5 * (dirty[f"{p}1"] + dirty[f"{p}2"]), 0.5 * (clean[f"{p}1"] + clean[f"{p}2"]),
                                   atol=0.005)


# ------------------------------------------------------------------------------------------ latency jitter
def test_latency_jitter_delays_each_event_by_up_to_the_jitter():
    sensor = _sensor()
    tool = straight_tool()
    from robocal.tcp.cross_laser import plan_axis_circles

    c1, _ = plan_axis_circles(sensor.true_frame(), tool.T_flange_tool, CrossLaserSettings())
    kw = dict(repeatability_mm=0.0, io_rate_hz=1000.0, latency_s=0.002)
    plain = LightBarrierCell(sensor, tool, 3, **kw).run(c1).events
    late = LightBarrierCell(sensor, tool, 3, latency_jitter_s=0.008, **kw).run(c1).events
    assert [(e.barrier, e.state) for e in plain] == [(e.barrier, e.state) for e in late]
    d = np.array([b.time_s - a.time_s for a, b in zip(plain, late)])
    assert np.all(d >= -1e-12) and np.all(d <= 0.008 + 1e-9)
    assert np.allclose(d * 1000.0, np.round(d * 1000.0), atol=1e-6)            # on the 1 kHz I/O clock
    assert d.max() > 0.002
    again = LightBarrierCell(sensor, tool, 3, **kw).run(c1).events               # no jitter: unchanged
    assert [e.time_s for e in again] == [e.time_s for e in plain]


# ------------------------------------------------------------------------------------------ runout
def test_runout_moves_the_cylinder_not_the_tcp():
    tool = straight_tool()
    run = tool.with_runout(0.5, 0.0, 4)
    np.testing.assert_array_equal(run.T_flange_tool, tool.T_flange_tool)
    b0, e0 = tool.segment_flange()
    b1, e1 = run.segment_flange()
    assert np.linalg.norm(b1 - b0) == pytest.approx(0.5) and np.linalg.norm(e1 - e0) == pytest.approx(0.5)
    bent, _ = run.collided(2)
    np.testing.assert_array_equal(bent.T_tool_shank, run.T_tool_shank)
    # the cross-laser method sees the cylinder: its TCP is off by the eccentricity, sideways
    sensor = _sensor()
    res = recalibrate_tool(LightBarrierCell(sensor, run, 1, **EXACT), sensor.true_frame(), tool.T_flange_tool)
    err = res.tcp_flange_mm - run.tcp_flange_mm
    assert np.linalg.norm(err[:2]) == pytest.approx(0.5, abs=0.01) and abs(err[2]) < 0.01


# ------------------------------------------------------------------------------------------ absolute error, arm
@pytest.fixture(scope="module")
def ur10():
    return load_robot("ur10")


def test_robot_accuracy_is_the_true_arm_at_the_controllers_joints(ur10):
    from robocal.kinematics import ik_numeric
    from robocal.tcp.cross_laser import LinearMove

    true = VirtualRobot.perturbed(ur10, 5, length_sigma_mm=0.1, angle_sigma_deg=0.01, offset_sigma_deg=0.01).true_model
    acc = RobotAccuracy(ur10, true, UR10_Q)
    R = np.diag([1.0, -1.0, -1.0])
    mv = LinearMove(np.array([-860.0, -170.0, 420.0]), np.array([-840.0, -150.0, 400.0]), R, R, 20.0, 1.0, 2000.0)
    ts = np.linspace(0.0, mv.duration_s, acc.n_samples)
    T = mv.poses(ts)
    moved = acc.apply(mv, ts, T)
    q = ik_numeric(ur10, T, UR10_Q).q
    np.testing.assert_allclose(moved, true.fk(q), atol=1e-6)
    err = np.linalg.norm(moved[:, :3, 3] - T[:, :3, 3], axis=1)
    assert 0.05 < err.mean() < 1.0 and acc.reach_errors_mm[-1] < 1e-3
    same = RobotAccuracy(ur10, ur10, UR10_Q).apply(mv, ts, T)
    np.testing.assert_allclose(same, T, atol=1e-6)


def test_measuring_arm_registration_and_noise():
    arm = MeasuringArm(0.0, 0.0, 0.0, 1)
    np.testing.assert_allclose(arm.probe([100.0, 200.0, 300.0]), [100.0, 200.0, 300.0])
    arm = MeasuringArm(0.025, 0.05, 0.003, 2)
    p = np.array([arm.probe([-700.0, -170.0, 350.0]) for _ in range(4000)])
    assert p.std(axis=0) == pytest.approx([0.025] * 3, rel=0.06)
    bias = np.linalg.norm(p.mean(axis=0) - [-700.0, -170.0, 350.0])
    assert 0.0 < bias < 0.3                                                      # the registration error


# ------------------------------------------------------------------------------------------ parallel barriers
def test_parallel_barriers_through_the_simulator():
    """(4-6), (4-7) from simulated events, noise-free: the beam heights, the axis and the length D
    are exact; the TCP is exact for a tool whose axis passes through the flange origin and off by
    the axis's distance from the flange origin otherwise (the method's assumption)."""
    rig = ParallelBarrierRig()
    h_up, h_down = measure_beam_heights(rig, 1, **EXACT)
    assert (h_up, h_down) == pytest.approx((rig.h_up_mm, rig.h_down_mm), abs=1e-3)
    nominal = straight_tool()
    R = rot_x(math.radians(1.5)) @ rot_y(math.radians(-1.0))
    about_flange = CylinderTool(transforms_from(R, R @ [0.0, 0.0, 181.0]), 3.0, 180.0)
    collided, _ = nominal.collided(7)
    for tool in (about_flange, collided):
        kw, cycle = record_parallel_barriers(LightBarrierCell(rig.beams(), tool, 2, **EXACT), rig,
                                             nominal.T_flange_tool, h_up, h_down)
        res = parallel_barriers_tool(**kw)
        a, t = tool.axis_flange, tool.tcp_flange_mm
        assert math.degrees(math.acos(min(1.0, res.axis @ a))) < 1e-3
        assert res.length_mm == pytest.approx(t @ a, abs=2e-3)
        off_axis = np.linalg.norm(t - (t @ a) * a)
        assert np.linalg.norm(res.tcp_mm - t) == pytest.approx(off_axis, abs=3e-3)
        assert res.vertical_residual_deg < 1e-3 and 20.0 < cycle < 60.0
    assert off_axis > 0.3                                                        # the collided tool


# ------------------------------------------------------------------------------------------ 20 cells
@pytest.fixture(scope="module")
def cells():
    """Realistic preset, 20 cells x 3 repeats of the same bent tool (~10 s; the docs' table uses
    10 repeats: ``robocal tcp accuracy``)."""
    from robocal.workflows.tool.accuracy import tcp_accuracy_study

    return tcp_accuracy_study(preset="realistic", seeds=20, first_seed=1, repeats=3)


THESIS_RMS_MM = 0.48  # thesis 5.2 (METHODS.md section 5): rms of 10 recalibrated TCPs, checked with a ROMER arm
DIRT_BIAS_MM = 0.3  # BarrierEffects.realistic: dust on up to 30 % of a 2 mm beam biases a crossing by f w / 2
ROBOT_ABS_MM = (0.2, 0.4)  # BarrierEffects.realistic: the robot's absolute error after calibration, 0.2-0.4 mm
ARM_MM = 0.025 * math.sqrt(3)  # the arm's 0.025 mm per coordinate, 3-D
REGISTRATION_MM = 0.05 + math.radians(0.003) * 800.0  # 0.05 mm + 0.003 deg at the check point (~0.8 m from the base)
REPEAT_MM = 0.1 / 3.6 * math.sqrt(3)  # ISO repeatability 0.1 mm (~3.6 sigma of the 3-D distance), as simulated
IO_PB_MM = (0.008 + 0.008) * 5.0  # parallel barriers: one 125 Hz cycle late + 8 ms jitter at the rig's 5 mm/s


def test_tool_frame_repeatability_and_accuracy_over_20_cells(cells):
    """Against the thesis and the simulated truth, not against robocal's earlier medians (those
    are documented figures of docs/tcp.md, checked by ``python -m robocal.docs.figures --all``).

    * Thesis: its 0.48 mm rms (one UR10 cell, 10 recalibrations checked with a measuring arm) must
      lie within the interquartile range of the simulated cells' arm check (the same kind of
      figure). A simulated cell is another cell with other dirt, another robot and another bent
      tool: it cannot be expected to match one real cell more closely than the cells match each
      other. The ideal cell's arm check (quartiles 0.055 / 0.072 mm) would fail this.
    * Truth, parallel barriers: (4-6, 4-7) take the TCP as ``D * axis``; the bent tool's axis
      misses the flange origin, so its TCP error must equal the true tool's off-axis distance (the
      method's assumption, from the hidden bent tool) within what the cell's effects can add: the
      dirt's beam-height bias (f w / 2 <= 0.3 mm), the robot's absolute error (<= 0.4 mm) and the
      I/O's delay at the rig's 5 mm/s (16 ms: 0.08 mm), summed as a worst case, 0.78 mm, in every
      cell (the tool's runout, 0.02 mm / 0.02 deg, is below the rounding of these).
    * Truth, cross-laser: its TCP error is part of what the arm check sees, and the check adds the
      robot's absolute error at the check pose, the arm and its registration and the robot's
      repeatability (independent of the TCP's error, so in quadrature): ``sqrt(median(check^2 -
      accuracy^2))`` must lie between the robot's stated 0.2 mm and the worst-case sum 0.4 + 0.043
      + 0.092 + 0.048 = 0.58 mm; the median TCP error must stay below the thesis's check figure.

    Measured (cells 1-20, 3 repeats): arm check quartiles 0.337 / 0.594 mm (median 0.480);
    parallel barriers |error - off-axis| <= 0.44 mm (median 0.07); cross-laser accuracy median
    0.196 mm, check part beyond the TCP 0.40 mm.
    """
    from robocal.sim.tool.parallel_barrier_cell import straight_tool

    s = cells["summary"]
    cl, pb = s["cross_laser"], s["parallel_barriers"]
    assert cl["check_mm"]["q25"] <= THESIS_RMS_MM <= cl["check_mm"]["q75"], cl["check_mm"]
    for c in cells["per_seed"]:
        s_tool = np.random.SeedSequence([c["seed"], 11]).spawn(6)[1]  # the cell's bent tool, as tcp_accuracy_study draws it
        bent, _ = straight_tool().collided(np.random.default_rng(s_tool))
        t, a = bent.tcp_flange_mm, bent.axis_flange
        np.testing.assert_allclose(t, c["tcp_true_mm"], atol=1e-9)
        off_axis = np.linalg.norm(t - (t @ a) * a)
        assert abs(c["tcp_off_axis_mm"] - off_axis) < 1e-9  # the study's record (docs/testing.md's figures use it)
        assert abs(c["parallel_barriers"]["accuracy_mm"] - off_axis) <= DIRT_BIAS_MM + ROBOT_ABS_MM[1] + IO_PB_MM, \
            (c["seed"], off_axis)
    acc = np.array([c["cross_laser"]["accuracy_mm"] for c in cells["per_seed"]])
    chk = np.array([c["cross_laser"]["check_mm"] for c in cells["per_seed"]])
    beyond_tcp = math.sqrt(max(float(np.median(chk**2 - acc**2)), 0.0))
    assert ROBOT_ABS_MM[0] <= beyond_tcp <= ROBOT_ABS_MM[1] + ARM_MM + REGISTRATION_MM + REPEAT_MM, beyond_tcp
    assert cl["accuracy_mm"]["median"] < THESIS_RMS_MM
    # repeatability is not accuracy: the spread of the same tool is a fraction of the error
    assert cl["repeatability_mm"]["median"] < 0.5 * cl["accuracy_mm"]["median"] < cl["check_mm"]["median"]
    # the arm check adds the robot's absolute error at the check pose and the arm's own error
    assert sum(c["cross_laser"]["check_mm"] > c["cross_laser"]["accuracy_mm"] for c in cells["per_seed"]) >= 15
    # the parallel barriers measure the axis well, the TCP only through the flange origin
    assert pb["axis_accuracy_deg"]["median"] < cl["axis_accuracy_deg"]["median"]
    assert pb["accuracy_mm"]["median"] > 4 * cl["accuracy_mm"]["median"]
    assert cells["thesis_rms_mm"] == THESIS_RMS_MM


def test_ideal_cell_is_an_order_of_magnitude_better():
    from robocal.workflows.tool.accuracy import tcp_accuracy_study

    ideal = tcp_accuracy_study(preset="ideal", seeds=4, first_seed=1, repeats=3, methods=("cross_laser",))
    s = ideal["summary"]["cross_laser"]
    assert s["accuracy_mm"]["max"] < 0.1 and s["check_mm"]["max"] < 0.12
    assert ideal["settings"]["effects"] == {**vars(BarrierEffects.ideal())}


def test_cli_accuracy_prints_the_librarys_study():
    import json

    from click.testing import CliRunner

    from robocal.cli.main import main
    from robocal.workflows.tool.accuracy import tcp_accuracy_study

    r = CliRunner().invoke(main, ["tcp", "accuracy", "--seeds", "1", "--seed", "3", "--repeats", "2",
                                  "--method", "cross_laser", "--json"])
    assert r.exit_code == 0, r.output
    out = json.loads(r.stdout)
    lib = tcp_accuracy_study(preset="realistic", seeds=1, first_seed=3, repeats=2, methods=("cross_laser",))
    assert out["summary"]["cross_laser"]["accuracy_mm"]["median"] == pytest.approx(
        lib["summary"]["cross_laser"]["accuracy_mm"]["median"])
    assert out["settings"]["preset"] == "realistic" and out["thesis_rms_mm"] == 0.48
    bad = CliRunner().invoke(main, ["tcp", "accuracy", "--repeats", "1"])
    assert bad.exit_code != 0 and "repeats" in bad.output
