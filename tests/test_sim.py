"""Simulator: virtual robot (true parameters, encoder noise, limits) and virtual laser tracker."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from robocal.io import read_measurements
from robocal.robots import load_robot
from robocal.sim import LaserTracker, VirtualRobot, fit_rotations, parameter_kinds, reflector_triangle
from robocal.transforms import invert_transforms, rotation_angle, transform_points


@pytest.fixture(scope="module")
def kuka():
    return load_robot("kuka_kr150_r3100")


def _deltas(nominal, seeds, **kw):
    return np.array([
        VirtualRobot.perturbed(nominal, s, **kw).true_model.params.values - nominal.params.values for s in seeds
    ])


# ------------------------------------------------------------------ virtual robot


def test_perturbation_magnitudes(kuka):
    kw = dict(length_sigma_mm=0.5, angle_sigma_deg=0.05, offset_sigma_deg=0.2)
    d = _deltas(kuka, range(30), **kw)
    kinds = parameter_kinds(kuka)
    free = kuka.params.free
    expected = {"length": 0.5, "angle": math.radians(0.05), "offset": math.radians(0.2)}
    for kind, sigma in expected.items():
        sel = d[:, free & (kinds == kind)].ravel()
        assert sel.size >= 90
        rms = np.sqrt(np.mean(sel**2))  # mean is zero by construction
        assert abs(rms / sigma - 1.0) < 0.3, (kind, rms, sigma)
    assert set(kinds[[kuka.params.index(n) for n in ("theta1", "theta6")]]) == {"offset"}
    assert kinds[kuka.params.index("alpha2")] == "angle" and kinds[kuka.params.index("a2")] == "length"


def test_fixed_parameters_untouched(kuka):
    vr = VirtualRobot.perturbed(kuka, 7)
    fixed = ~kuka.params.free
    assert fixed.sum() == 6  # beta1, d2, beta3..beta6 of the KUKA file
    assert np.array_equal(vr.true_model.params.values[fixed], kuka.params.values[fixed])
    assert np.all(vr.true_model.params.values[~fixed] != kuka.params.values[~fixed])
    assert vr.true_parameters()["d2"] == kuka.params.values[kuka.params.index("d2")]
    # the nominal model is never changed
    assert np.array_equal(load_robot("kuka_kr150_r3100").params.values, kuka.params.values)


def test_perturbation_reproducible(kuka):
    a = VirtualRobot.perturbed(kuka, 11).true_parameters()
    b = VirtualRobot.perturbed(kuka, np.random.default_rng(11)).true_parameters()
    c = VirtualRobot.perturbed(kuka, 12).true_parameters()
    assert a == b
    assert a != c
    with pytest.raises(TypeError, match="seed"):
        VirtualRobot.perturbed(kuka, None)


def test_base_and_prismatic_joints():
    hilti = load_robot("hilti_trailblazer")
    base = np.eye(4)
    base[:3, 3] = [100.0, -50.0, 0.0]
    vr = VirtualRobot.perturbed(hilti, 3, base=base, joint_noise_deg=0.01, joint_noise_mm=0.05)
    assert list(vr.prismatic) == [True] + [False] * 6
    np.testing.assert_allclose(vr.joint_noise, [0.05] + [math.radians(0.01)] * 6)
    np.testing.assert_array_equal(vr.true_model.T_world_base, base)
    # prismatic joint offset d2 is a length parameter
    assert parameter_kinds(hilti)[hilti.params.index("d2")] == "offset"
    q = vr.random_configurations(5, 0)
    assert np.all(vr.nominal.within_limits(q))


def test_reach_encoder_noise_and_limits(kuka):
    vr = VirtualRobot.perturbed(kuka, 1, joint_noise_deg=0.002)
    q = vr.random_configurations(500, np.random.default_rng(2), margin=0.1)
    lo, hi = kuka.limits[:, 0], kuka.limits[:, 1]
    assert np.all(q >= lo + 0.1 * (hi - lo)) and np.all(q <= hi - 0.1 * (hi - lo))
    q_noisy = vr.encoder_noise(q, 3)
    std = np.std(q_noisy - q)
    assert abs(std / math.radians(0.002) - 1.0) < 0.1
    # reach = true FK at the noisy joints (same seed, same draw)
    np.testing.assert_allclose(vr.reach(q, 3), vr.true_model.fk(q_noisy), atol=1e-9)
    # the true robot differs from the nominal one by about a millimetre
    dev = np.linalg.norm(vr.true_poses(q)[:, :3, 3] - kuka.fk(q)[:, :3, 3], axis=1)
    assert 0.1 < np.median(dev) < 10.0
    bad = q[:4].copy()
    bad[2, 1] = math.radians(10.0)  # A2 limits are [-140, -5] deg
    with pytest.raises(ValueError, match=r"pose 2: joint A2 = 10\.0000 deg outside its limits"):
        vr.reach(bad, 0)
    with pytest.raises(ValueError, match=r"shape \(N, 6\)"):
        vr.reach(q[:, :5], 0)


# ------------------------------------------------------------------ laser tracker


def test_tracker_placement_is_seeded_and_metres_away():
    a, b, c = LaserTracker.placed(5), LaserTracker.placed(5), LaserTracker.placed(6)
    np.testing.assert_array_equal(a.T_tracker_world, b.T_tracker_world)
    assert not np.allclose(a.T_tracker_world, c.T_tracker_world)
    dist = np.linalg.norm(invert_transforms(a.T_tracker_world)[:3, 3])
    assert 2500.0 <= dist <= 4500.0
    assert rotation_angle(a.T_tracker_world[:3, :3]) > 0.05  # not aligned with the world


def test_tracker_noise_statistics(kuka):
    vr = VirtualRobot.perturbed(kuka, 1, joint_noise_deg=0.0)
    tr = LaserTracker.placed(2, 1, sigma_mm=0.02)
    q = vr.random_configurations(2000, 3)
    m = tr.measure(vr, q, 4)
    assert m.points.shape == (2000, 1, 3) and m.rotations is None
    err = m.points - tr.true_points(vr, q)
    assert abs(err.mean()) < 0.1 * 0.02
    for axis in range(3):
        assert abs(np.std(err[..., axis]) / 0.02 - 1.0) < 0.1
    assert m.metadata["frame"] == "tracker" and m.metadata["robot"] == "kuka_kr150_r3100"
    np.testing.assert_array_equal(m.joints, q)


def test_tracker_distance_dependent_noise(kuka):
    vr = VirtualRobot.perturbed(kuka, 1, joint_noise_deg=0.0)
    tr = LaserTracker.placed(2, 1, sigma_mm=0.0, ppm=10.0)  # 10 um per metre
    q = vr.random_configurations(2000, 3)
    true = tr.true_points(vr, q)
    err = tr.measure(vr, q, 4).points - true
    sigma = 10e-6 * np.linalg.norm(true, axis=-1)
    assert sigma.max() < 0.1 and sigma.max() > 2 * sigma.min()  # really distance-dependent
    assert abs(np.std(err / sigma[..., None]) - 1.0) < 0.1


def test_three_reflectors_rigid_triangle_and_orientation(kuka):
    vr = VirtualRobot.perturbed(kuka, 1)
    refl = reflector_triangle(radius_mm=100.0, height_mm=40.0)
    tr = LaserTracker.placed(8, refl, sigma_mm=0.02)
    q = vr.random_configurations(300, 9)
    m = tr.measure(vr, q, 10)
    assert m.targets == ("r1", "r2", "r3") and m.rotations is not None
    pairs = [(0, 1), (1, 2), (0, 2)]
    side_true = np.array([np.linalg.norm(refl[i] - refl[j]) for i, j in pairs])
    np.testing.assert_allclose(side_true, 100.0 * math.sqrt(3.0))
    side = np.stack([np.linalg.norm(m.points[:, i] - m.points[:, j], axis=-1) for i, j in pairs], axis=1)
    dev = side - side_true
    # a side is the difference of two noisy points: std sqrt(2) sigma along the side
    assert abs(np.std(dev) / (math.sqrt(2.0) * 0.02) - 1.0) < 0.15
    assert np.abs(dev).max() < 6 * math.sqrt(2.0) * 0.02
    # fitted orientation = true tracker-frame flange orientation within the noise (~sigma / radius rad)
    R_true = (tr.T_tracker_world @ vr.true_model.fk(q))[:, :3, :3]
    ang = rotation_angle(np.swapaxes(R_true, -1, -2) @ m.rotations)
    assert np.median(ang) < 0.02 / 100.0 * 3 + math.radians(0.002) * 3
    assert np.max(ang) < 1e-3


def test_fit_rotations_exact():
    rng = np.random.default_rng(0)
    from robocal.transforms import so3_exp
    R = so3_exp(rng.normal(size=(5, 3)))
    local = rng.normal(size=(4, 3)) * 100
    world = transform_points(np.concatenate([np.concatenate([R, rng.normal(size=(5, 3, 1))], 2),
                                             np.tile([[[0, 0, 0, 1.0]]], (5, 1, 1))], 1)[:, None], local[None])
    np.testing.assert_allclose(fit_rotations(local, world), R, atol=1e-12)


def test_campaign_files_and_reproducibility(kuka, tmp_path):
    vr = VirtualRobot.perturbed(kuka, 21)
    tr = LaserTracker.placed(22, 3, sigma_mm=0.02)
    mpath, tpath = tmp_path / "meas.csv", tmp_path / "truth.json"
    m, truth = tr.campaign(vr, 40, 23, measurements_path=mpath, truth_path=tpath)
    m2, _ = tr.campaign(vr, 40, 23)
    m3, _ = tr.campaign(vr, 40, 24)
    np.testing.assert_array_equal(m.points, m2.points)
    np.testing.assert_array_equal(m.joints, m2.joints)
    assert not np.allclose(m.points, m3.points)

    r = read_measurements(mpath, robot=kuka)
    np.testing.assert_allclose(r.points, m.points, atol=1e-9)
    np.testing.assert_allclose(r.joints, m.joints, atol=1e-14)
    np.testing.assert_allclose(r.rotations, m.rotations, atol=1e-12)
    assert r.metadata["instrument"].startswith("laser tracker")

    t = json.loads(tpath.read_text())
    assert t["seed"] == 23 and t["n_poses"] == 40 and t["robot"] == "kuka_kr150_r3100"
    assert t["true_parameters"] == pytest.approx(vr.true_parameters(), abs=0)
    np.testing.assert_array_equal(np.array(t["T_tracker_world"]), tr.T_tracker_world)
    np.testing.assert_array_equal(np.array(t["reflectors_mm"]), tr.reflectors)
    # the truth explains the measurements to the noise level (with encoder noise)
    T = np.array(t["T_tracker_base"]) @ vr.true_model.replace(T_world_base=np.eye(4)).fk(m.joints)
    pred = transform_points(T[:, None], np.array(t["reflectors_mm"])[None])
    assert np.sqrt(np.mean((pred - m.points) ** 2)) < 0.2

    before = (mpath.read_bytes(), tpath.read_bytes())
    with pytest.raises(FileExistsError):
        tr.campaign(vr, 40, 99, measurements_path=mpath, truth_path=tmp_path / "other.json")
    assert (mpath.read_bytes(), tpath.read_bytes()) == before
    assert not (tmp_path / "other.json").exists()
    tr.campaign(vr, 40, 99, measurements_path=mpath, truth_path=tpath, overwrite=True)
    assert mpath.read_bytes() != before[0]


# ------------------------------------------------------------------ campaign effects (issue 25)


def test_campaign_effects_are_what_their_definitions_say(kuka):
    """Each effect of :mod:`robocal.sim.campaign_effects` checked against its definition (no
    recorded numbers): ideal = the true geometric robot; the transmission error is bounded by the
    sum of its amplitudes and periodic in 2 pi; the growth is 0 at the first pose and
    ``growth_ppm`` of the distance from the base origin at the last; the tracker scale multiplies
    the tracker-frame distances; the noise has the tracker's sigma."""
    from robocal.sim.campaign_effects import CampaignEffects, measure_with_effects

    robot = VirtualRobot.perturbed(kuka, 3, joint_noise_deg=0.0)
    tracker = LaserTracker.placed(4, sigma_mm=0.0)
    q = robot.random_configurations(400, np.random.default_rng(5), margin=0.1)
    ideal = measure_with_effects(robot, tracker, q, "ideal", 6)
    np.testing.assert_allclose(ideal["points"], ideal["model"], atol=1e-9)
    np.testing.assert_allclose(ideal["reached"], ideal["model"], atol=1e-9)

    eff = CampaignEffects(transmission_deg=(0.01, 0.004), name="joints")
    dq = eff.joint_positions(robot, q, 7) - q
    assert np.abs(dq).max() <= math.radians(0.014) + 1e-15 and np.abs(dq).max() > math.radians(0.008)
    np.testing.assert_allclose(eff.joint_positions(robot, q + 2 * np.pi, 7) - (q + 2 * np.pi), dq, atol=1e-12)

    grow = CampaignEffects(growth_ppm=20.0, name="growth")
    g = measure_with_effects(robot, tracker, q, grow, 6)
    T_tb = tracker.T_tracker_world @ robot.true_model.T_world_base
    base = transform_points(invert_transforms(T_tb)[None, None], g["model"])
    moved = np.linalg.norm(g["reached"] - g["model"], axis=-1)[:, 0]
    assert moved[0] < 1e-9
    assert moved[-1] == pytest.approx(20e-6 * np.linalg.norm(base[-1, 0]), rel=1e-6)
    assert np.all(np.diff(moved / np.linalg.norm(base[:, 0], axis=-1)) > 0)

    scale = measure_with_effects(robot, tracker, q, CampaignEffects(tracker_scale_ppm=5.0), 6)
    np.testing.assert_allclose(scale["reached"], scale["model"], atol=1e-9)
    np.testing.assert_allclose(scale["points"], scale["model"] * (1 + 5e-6), rtol=1e-12, atol=1e-9)

    noisy = measure_with_effects(robot, LaserTracker.placed(4, sigma_mm=0.02), q, "ideal", 6)
    assert np.std(noisy["points"] - noisy["model"]) == pytest.approx(0.02, rel=0.1)
    with pytest.raises(ValueError, match="unknown campaign preset"):
        CampaignEffects.preset("hall")


def test_simulate_tracker_effects_reach_the_truth_file_and_the_virtual_controller(tmp_path):
    """``robocal simulate tracker --effects realistic``: the same poses as ``ideal`` (same seed),
    points moved by the effects (more than the noise, less than their bound), the effects and
    their phases in the truth file; ``robocal simulate execute`` on that truth file moves the
    true robot to ``q + a1 sin(q + phi1) + a2 sin(2q + phi2)`` and grows the arm by ``growth_ppm``
    about the base origin (the definitions, written out here); ``ideal`` has no effects entry."""
    from click.testing import CliRunner

    from robocal.cli import main

    def sim(effects):
        out = tmp_path / f"{effects}.csv"
        r = CliRunner().invoke(main, ["simulate", "tracker", "ur10", "--poses", "12", "--seed", "4", "--noise", "0",
                                      "--out", str(out), "--effects", effects])
        assert r.exit_code == 0, r.output
        return read_measurements(out), json.loads((tmp_path / f"{effects}.truth.json").read_text())

    (m_i, t_i), (m_r, t_r) = sim("ideal"), sim("realistic")
    assert "campaign_effects" not in t_i and t_r["simulation"]["effects"] == "realistic"
    np.testing.assert_allclose(m_r.joints, m_i.joints, atol=0)
    moved = np.linalg.norm(m_r.points - m_i.points, axis=-1)
    reach = np.linalg.norm(m_i.points - np.asarray(t_i["T_tracker_base"])[:3, 3], axis=-1)
    # bound: 0.008 deg of joint error over ~4 lever arms of the reach, 25 ppm of the tracker distance
    assert moved.max() > 0.01 and np.all(moved < np.radians(0.008) * 4 * reach + 25e-6 * 6000), moved
    eff = t_r["campaign_effects"]
    phases = np.asarray(eff["transmission_phases_rad"])
    assert phases.shape == (2, 6) and eff["growth_ppm"] == 20.0 and eff["tracker_scale_ppm"] == 5.0

    q = np.radians([20.0, -80.0, 70.0, -60.0, -90.0, 30.0])
    prog = tmp_path / "p.script"
    prog.write_text("def p():\n  movej([" + ", ".join(f"{v:.9f}" for v in q) + "])\nend\n")
    rows = {}
    for name in ("ideal", "realistic"):
        r = CliRunner().invoke(main, ["simulate", "execute", str(tmp_path / f"{name}.truth.json"), str(prog), "--json"])
        assert r.exit_code == 0, r.output
        rows[name] = json.loads(r.output)["targets"][0]
    nominal = load_robot("ur10")
    true = nominal.with_params(**{k: float(v) for k, v in t_r["true_parameters"].items()})
    a1, a2 = np.radians(eff["transmission_deg"])
    q_real = q + a1 * np.sin(q + phases[0]) + a2 * np.sin(2 * q + phases[1])
    p_ideal = (np.linalg.inv(true.T_world_base) @ true.fk(q))[:3, 3]
    p_real = (np.linalg.inv(true.T_world_base) @ true.fk(q_real))[:3, 3] * (1 + 20e-6)
    np.testing.assert_allclose(rows["ideal"]["tcp_base_mm"], p_ideal, atol=1e-3)  # JSON rounds to 1e-4 mm
    np.testing.assert_allclose(rows["realistic"]["tcp_base_mm"], p_real, atol=1e-3)
    assert np.linalg.norm(p_real - p_ideal) > 0.01
    assert rows["realistic"]["error_mm"] == pytest.approx(0.0, abs=1e-9)  # a joint target means where it goes
