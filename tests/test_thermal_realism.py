"""The thermal simulator's effects outside the compensation model, and table 5-2 as a
distribution over seeds (issue 11). Every random draw seeded; the multi-seed figures are pinned
with tolerances measured from the seed-group to seed-group spread (see each test)."""

import math
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from robocal.robots import load_robot
from robocal.sim.thermal.simulator import ProductionSchedule, ThermalCell, standard_schedules
from robocal.sim.thermal.deformation import (
    apply_link_twists,
    gravity_torques,
    link_geometry,
    link_twists,
)
from robocal.sim.thermal.deformation_transfer import TRANSFER_MOTOR_TEMPERATURES_K, deformation_transfer
from robocal.sim.thermal.effects import HallTemperature, HeatResponse, LinkDeformation, thermal_effects
from robocal.sim.thermal.measurement import add_outliers, approach_sides, backlash_offsets, distance_noise
from robocal.sim.thermal.response import hall_temperature, motor_temperatures
from robocal.transforms import so3_exp


@pytest.fixture(scope="module")
def kr150():
    return load_robot("kuka_kr150_r3100")


@pytest.fixture(scope="module")
def real_cell():
    return ThermalCell.standard(3, preset="realistic")


REFERENCE = Path(__file__).parent / "data" / "thermal_ideal_fae18d9.npz"


# ------------------------------------------------------------------------------------------ presets
def test_ideal_preset_is_the_previous_simulator():
    """Today's ideal preset against the arrays the simulator produced at commit fae18d9, before the
    effects existed (tests/data/make_thermal_ideal_reference.py). 1e-9 mm (and 1e-9 rad for the
    parameter deltas): far below any effect (the smallest, the distance noise, is ~1e-3 mm), far above
    rounding, which differs between machines (fused multiply-add, SIMD width)."""
    ref = np.load(REFERENCE)
    cell = ThermalCell.standard(2024, preset="ideal")
    run = cell.simulate(standard_schedules(7, 12)[1], 5)
    for name in ("sphere", "monitor", "delta_true", "tcp_drift_mm", "sphere_cold", "monitor_cold"):
        np.testing.assert_allclose(getattr(run, name), ref[name], rtol=0, atol=1e-9, err_msg=name)
    assert run.conditions is None and cell.effects.is_ideal and cell.realism is None


def test_presets_and_switches():
    r = thermal_effects("realistic")
    assert r.enabled == ("heat", "hall", "deformation", "joints", "noise", "outliers")
    assert thermal_effects("ideal").enabled == ()
    assert r.without("hall", "outliers").enabled == ("heat", "deformation", "joints", "noise")
    assert r.only("noise").enabled == ("noise",)
    d = r.as_dict()
    assert d["hall"]["amplitude_K"] == 1.5 and d["outliers"]["sphere_range_mm"] == (0.05, 0.2)
    with pytest.raises(ValueError, match="unknown effect"):
        r.without("wind")
    with pytest.raises(ValueError, match="unknown thermal preset"):
        thermal_effects("warm")


def test_realistic_cell_shares_every_other_draw_with_the_ideal_one(real_cell):
    ideal = ThermalCell.standard(3)
    np.testing.assert_array_equal(ideal.q_sphere, real_cell.q_sphere)
    np.testing.assert_array_equal(ideal.T_sensor_base, real_cell.T_sensor_base)
    np.testing.assert_array_equal(ideal.robot.true_model.params.values, real_cell.robot.true_model.params.values)


# ------------------------------------------------------------------------------------------ heat
def test_two_mode_nonlinear_heating_matches_an_independent_integration(real_cell):
    """The RK4 integration over the piecewise-constant load against scipy's adaptive solver."""
    th, heat = real_cell.thermal, HeatResponse()
    sched = ProductionSchedule.generate(4, 12).with_programs(5, heat.n_programs, heat.duty_spread)
    t = np.sort(np.random.default_rng(1).uniform(0, sched.duration_s + 1800.0, 15))
    got = motor_temperatures(th, sched, t, heat)
    t0, dur, loads = sched.segments()
    a = np.array([heat.fast_share, 1 - heat.fast_share])[:, None]
    G = a * th.gains
    tau = np.stack([np.full(6, heat.fast_tau_s), th.taus * heat.slow_tau_scale])
    k = heat.loss_nonlinearity

    def rhs(time, y):
        i = np.searchsorted(t0, time, side="right") - 1
        u = loads[i] if time < t0[-1] + dur[-1] else np.zeros(6)
        h = y.reshape(2, 6)
        return (((1 + k) * G * u ** heat.load_exponent - h - k * h * h / G) / tau).ravel()

    ref = solve_ivp(rhs, (0.0, t[-1]), np.zeros(12), t_eval=t, rtol=1e-10, atol=1e-10, max_step=20.0,
                    method="DOP853").y.reshape(2, 6, -1).sum(axis=0).T
    np.testing.assert_allclose(got, ref, atol=2e-4)                     # K


def test_heating_settles_at_the_gain_and_cools_faster_than_one_exponential(real_cell):
    th, heat = real_cell.thermal, HeatResponse()
    on = ProductionSchedule(np.array([30 * 3600.0]), np.ones(1), np.zeros(1), measure_s=0.0)
    h = motor_temperatures(th, on, [30 * 3600.0 - 1.0], heat)[0]
    # at steady state each mode satisfies (1 + k) G u^p = h + k h^2 / G, whose root for u = 1 is G
    u = np.array([0.6, 1.0, 0.9, 0.8, 0.5, 0.5])
    steady = 0.0
    for share in (heat.fast_share, 1 - heat.fast_share):
        Gm = share * th.gains
        c = (1 + heat.loss_nonlinearity) * Gm * u ** heat.load_exponent
        steady = steady + (-Gm + np.sqrt(Gm ** 2 + 4 * heat.loss_nonlinearity * c * Gm)) / (2 * heat.loss_nonlinearity)
    np.testing.assert_allclose(h, steady, rtol=1e-6)
    # cooling: after one fast time constant more than a pure slow exponential would lose is gone
    end = 30 * 3600.0
    c = motor_temperatures(th, on, [end, end + heat.fast_tau_s], heat)
    kept = c[1] / c[0]
    assert np.all(kept < np.exp(-heat.fast_tau_s / (th.taus * heat.slow_tau_scale)) - 0.05)


def test_programs_change_the_joint_duty_per_cycle():
    s = ProductionSchedule.generate(2, 30)
    p = s.with_programs(3, 3, 0.3)
    assert p.duty.shape == (30, 6) and len({tuple(r) for r in p.duty}) == 3
    assert np.all(np.abs(p.duty - 1.0) <= 0.3)
    _, _, plain = s.segments()
    _, _, dutied = p.segments()
    np.testing.assert_allclose(dutied[0::3], np.minimum(plain[0::3] * p.duty, 1.0))
    np.testing.assert_array_equal(dutied[1::3], plain[1::3])              # measurement and idle unchanged
    with pytest.raises(ValueError, match="duty"):
        ProductionSchedule(np.ones(2), np.ones(2), np.zeros(2), duty=np.ones((2, 5)))


def test_hall_temperature_daily_sine_and_wander():
    hall = HallTemperature(wander_K=0.0)
    t = np.linspace(0.0, 86400.0, 25)
    d = hall_temperature(t, hall, 3)
    assert d[0] == 0.0 and abs(d[-1]) < 1e-9 and 2 * hall.amplitude_K * 0.95 < np.ptp(d) <= 2 * hall.amplitude_K
    # the wander alone: stationary rms w, so the change over >> tau has variance 2 w^2
    w = HallTemperature(amplitude_K=0.0)
    late = np.array([hall_temperature([0.0, 20 * 3600.0], w, s)[1] for s in range(2000)])
    assert np.std(late) == pytest.approx(math.sqrt(2) * w.wander_K, rel=0.06)
    # and over a short step it barely moves: var = 2 w^2 (1 - exp(-dt / tau))
    short = np.array([hall_temperature([0.0, 60.0], w, s)[1] for s in range(2000)])
    assert np.std(short) == pytest.approx(w.wander_K * math.sqrt(2 * (1 - math.exp(-60 / w.wander_tau_s))), rel=0.06)


# ------------------------------------------------------------------------------------------ deformation
def test_bending_closed_form_equals_the_integrated_curvature_field(kr150):
    """phi and w of :func:`link_twists` against a numerical double integration of kappa(s)."""
    geom = link_geometry(kr150, 4, 6)
    dfm = LinkDeformation()
    temps = np.array([[6.0, 21.0, 17.0, 12.0, 5.0, 3.0]])
    tw = link_twists(geom, temps, dfm, 6)[0]
    b = 1                                                              # the upper arm
    L = np.linalg.norm(geom.end[b] - geom.start[b])
    Tp, Td = temps[0, geom.source[b]]
    s = np.linspace(0.0, L, 20001)
    kappa = dfm.expansion_per_K * dfm.gradient_share * (Tp + (Td - Tp) * s / L) / dfm.section_depth_mm
    theta = np.concatenate([[0.0], np.cumsum((kappa[1:] + kappa[:-1]) / 2 * np.diff(s))])
    w = np.trapezoid(theta, s)
    k = geom.link[b]
    np.testing.assert_allclose(tw[k, :3], theta[-1] * geom.axes[b], rtol=1e-8, atol=1e-15)
    e = (geom.end[b] - geom.start[b]) / L
    np.testing.assert_allclose(tw[k, 3:] + np.cross(tw[k, :3], geom.end[b]), w * np.cross(geom.axes[b], e),
                               rtol=1e-6, atol=1e-12)


def test_link_twists_compose_like_the_exact_chain(kr150):
    """A link's small motion applied to the flange against the chain rebuilt with the motion
    inserted after that link's frame (F E F^-1 T), and two links against their product."""
    q = np.radians([[10.0, -70.0, 100.0, 20.0, 40.0, -30.0]])
    T = kr150.fk(q)
    for k in range(6):
        tw = np.zeros((6, 6))
        tw[k] = np.array([1e-4, -2e-4, 1.5e-4, 0.05, -0.03, 0.02])
        got = apply_link_twists(kr150, q, T, tw)[0]
        F = kr150.link_frames(q)[0, k]
        E = np.eye(4)
        E[:3, :3] = so3_exp(tw[k, :3])
        E[:3, 3] = tw[k, 3:]
        exact = F @ E @ np.linalg.inv(F) @ T[0]
        np.testing.assert_allclose(got, exact, atol=1e-9)
    tw = np.zeros((6, 6))
    tw[1], tw[3] = [2e-4, 0.0, -1e-4, 0.1, 0.0, 0.0], [0.0, 3e-4, 0.0, 0.0, 0.05, 0.0]
    F = kr150.link_frames(q)[0]
    M = [F[k] @ np.block([[so3_exp(tw[k, :3]), tw[k, 3:, None]], [np.zeros((1, 3)), np.ones((1, 1))]])
         @ np.linalg.inv(F[k]) for k in (1, 3)]
    np.testing.assert_allclose(apply_link_twists(kr150, q, T, tw)[0], M[0] @ M[1] @ T[0], atol=1e-9)


def test_gravity_torques_are_the_potential_energy_gradient(kr150):
    geom = link_geometry(kr150, 4, 6)
    q = np.radians([30.0, -60.0, 60.0, 10.0, 20.0, 5.0])
    tau, ref = gravity_torques(kr150, q[None], geom)

    def energy(qq):                                                      # [J] of the same point masses
        F = kr150.link_frames(qq)
        c = np.einsum("bij,bj->bi", F[geom.link, :3, :3], 0.5 * (geom.start + geom.end)) + F[geom.link, :3, 3]
        m = 0.2 * np.linalg.norm(geom.end - geom.start, axis=1)
        return 9.81 * (m @ c[:, 2] + 10.0 * kr150.fk(qq)[2, 3]) / 1000.0

    fd = [-(energy(q + e) - energy(q - e)) / 2e-6 for e in np.eye(6) * 1e-6]
    np.testing.assert_allclose(tau[0], fd, atol=1e-3 * np.abs(fd).max())
    assert np.all(np.abs(tau[0]) <= ref + 1e-9) and abs(tau[0, 1]) > 1000.0    # joint 2 carries the arm


_transfer = deformation_transfer  # written once in robocal.sim.thermal.deformation_transfer (docs/thermal.md's producer)


def test_bending_is_a_parameter_change_the_warm_sag_only_locally():
    """The measured finding behind docs/thermal.md ("Realism"): a body-fixed bending of the links
    is a change of the 24 free parameters (at the monitored points and fitted from the sphere
    poses alike, to ~2 %); the sag that softens with the heat is one locally (2 % outside the span
    at the car body) but not between the sphere and the car-body poses (measured 5-66 % left)."""
    temps = TRANSFER_MOTOR_TEMPERATURES_K
    rows = []
    for seed in (3, 4, 5):
        cell = ThermalCell.standard(seed, preset="realistic")
        rows.append(_transfer(cell, temps, "bend") + _transfer(cell, temps, "sag"))
    rows = np.array(rows)
    bend_span, bend_transfer, bend_rms, sag_span, sag_transfer, sag_rms = rows.T
    assert np.all(bend_span < 1e-3) and np.all(bend_transfer < 0.03) and np.all((0.03 < bend_rms) & (bend_rms < 0.15))
    assert np.all(sag_span > 0.01) and np.all(sag_transfer > 2 * bend_transfer) and sag_transfer.max() > 0.3
    assert np.all((0.01 < sag_rms) & (sag_rms < 0.05))                    # mm at 25 K on joint 2


# ------------------------------------------------------------------------------------------ measurement
def test_distance_noise_grows_with_distance():
    rng = np.random.default_rng(4)
    near = distance_noise(np.tile([0.0, 0.0, 700.0], (40000, 1)), 0.012, 0.03, 700.0, rng)
    far = distance_noise(np.tile([0.0, 0.0, -1050.0], (40000, 1)), 0.012, 0.03, 700.0, rng)
    np.testing.assert_allclose(near.std(axis=0), [0.012, 0.012, 0.03], rtol=0.03)
    np.testing.assert_allclose(far.std(axis=0), [0.018, 0.018, 0.0675], rtol=0.03)      # x1.5, x2.25


def test_outliers_rate_and_size():
    rng = np.random.default_rng(5)
    p, hit = add_outliers(np.zeros((20000, 3)), 0.01, (0.1, 0.4), rng)
    assert hit.mean() == pytest.approx(0.01, abs=0.002)
    size = np.linalg.norm(p[hit], axis=1)
    assert size.min() >= 0.1 and size.max() <= 0.4 and np.all(p[~hit] == 0.0)


def test_backlash_flips_the_approach_side():
    rng = np.random.default_rng(6)
    sides = approach_sides(5000, 6, rng)
    from robocal.sim.thermal.effects import JointErrors

    je = JointErrors()
    off = backlash_offsets(sides, je, rng)
    np.testing.assert_allclose(np.abs(off), np.broadcast_to(np.radians(je.backlash_deg), off.shape))
    flipped = np.sign(off) != sides
    assert flipped.mean() == pytest.approx(je.flip_probability, abs=0.01)


# ------------------------------------------------------------------------------------------ a realistic run
def test_realistic_drift_after_three_hours_is_in_the_thesis_range():
    """Thesis ch. 3: after 3 h of continuous production the TCP drifts up to 0.5 mm; fig. 3-1b: a
    car-body point's coordinates drift 0.1-0.5 mm. Over 8 cells, measured: TCP 0.28-0.56 mm,
    median 0.41 mm (the ideal cell on this schedule: 0.35-0.38, median 0.36; docs/thermal.md)."""
    sched = ProductionSchedule(np.full(60, 140.0), np.full(60, 1.0), np.zeros(60))          # 3 h non-stop
    tcp, body = [], []
    for seed in range(1, 9):
        cell = ThermalCell.standard(seed, preset="realistic")
        run = cell.simulate(sched, seed)
        tcp.append(np.interp(3 * 3600.0, run.timeline_s, run.tcp_drift_mm))
        body.append(np.max(np.abs(run.monitor[-1] - run.monitor_cold)))
    assert 0.2 <= min(tcp) and max(tcp) <= 0.6 and 0.3 <= np.median(tcp) <= 0.5
    assert 0.1 <= np.median(body) <= 0.6
    assert run.conditions["preset"] == "realistic" and run.conditions["hall_K"].shape == (60,)


def test_realistic_runs_are_seeded(real_cell):
    s = ProductionSchedule.generate(3, 6)
    a, b = real_cell.simulate(s, 8), real_cell.simulate(s, 8)
    np.testing.assert_array_equal(a.sphere, b.sphere)
    np.testing.assert_array_equal(a.monitor, b.monitor)
    assert not np.array_equal(real_cell.simulate(s, 9).sphere, a.sphere)
