"""GA-RBF learned IK seed (issue 17): accuracy on held-out poses, IK seeding on a beta-tilted model
(no closed form), the domain check, the GA, and the network file.

Small networks (3000 FK samples, 300 centres) keep the tests fast; the benchmark
(benchmarks/bench_ik_seed.py) measures the full-size ones.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from click.testing import CliRunner

from robocal.cli import main
from robocal.io.ik_network import IKNetworkFileError, load_ik_network, save_ik_network
from robocal.kinematics import ik_analytic, ik_numeric, is_analytic
from robocal.kinematics.convert import dh_with_beta
from robocal.kinematics.ik_net import (
    Structure,
    default_branch,
    ik_with_seed_network,
    on_branch,
    reference_model,
    sample_branch,
    train_ik_network,
)
from robocal.kinematics.ik_net.network import pose_error_stats
from robocal.robots import load_robot

SMALL = Structure(n_centres=300, width_factor=2.0, reg=1e-8, position_weight=3.0)


def _tilted():
    """A 'calibrated' IRB140: Hayati beta tilts and length errors, so no closed form exists."""
    return dh_with_beta(load_robot("abb_irb140")).with_params(
        beta2=np.radians(0.3), beta3=np.radians(-0.2), beta5=np.radians(0.15), a2=360.4, d4=379.7)


@pytest.fixture(scope="module")
def irb140():
    return load_robot("abb_irb140")


@pytest.fixture(scope="module")
def net140(irb140):
    return train_ik_network(irb140, 3000, seed=3, tune=False, structure=SMALL)


@pytest.fixture(scope="module")
def tilted_and_net():
    m = _tilted()
    return m, train_ik_network(m, 3000, seed=3, tune=False, structure=SMALL)


def _held_out(model, n=500, seed=11):
    q = sample_branch(reference_model(model), default_branch(model), n, np.random.default_rng(seed))
    return q, model.fk(q)


def test_branch_samples_are_one_closed_form_branch(irb140):
    q, T = _held_out(irb140, 300)
    q_all, valid = ik_analytic(irb140, T)
    assert valid[:, 0].all()
    np.testing.assert_allclose(q_all[:, 0], q, atol=1e-7)      # branch 0 (front/up/noflip) reproduces them
    assert np.all(q[:, 4] >= np.radians(10) - 1e-12)            # IRB140: OPW theta5 = q5, margin 10 deg
    # the beta-tilted model is labelled through its beta-free nominal shape
    m = _tilted()
    assert not is_analytic(m) and is_analytic(reference_model(m))


def test_held_out_accuracy(irb140, net140):
    """Measured (3000 samples, 300 centres, seed 3): median position error 94 mm, median joint error
    (worst joint) 48 deg on 500 held-out poses; the mean-joints guess is ~770 mm off."""
    q, T = _held_out(irb140)
    st = pose_error_stats(irb140, net140.predict_joints(T), q, T)
    mean_guess = pose_error_stats(irb140, np.broadcast_to(net140.rbf.y_mean, q.shape), q, T)
    assert st["position_mm"]["median"] < 120.0
    assert st["position_mm"]["median"] < mean_guess["position_mm"]["median"] / 5


def test_seed_beats_nominal_seed_on_tilted_model(tilted_and_net):
    """Measured: median 5 iterations (99 % converged) from the network seed against 23 (55 %) from the
    middle of the joint ranges."""
    m, net = tilted_and_net
    q, T = _held_out(m)
    res, pred, branch_ok = ik_with_seed_network(m, T, net)
    res_mid = ik_numeric(m, T, m.limits.mean(axis=1))
    assert np.median(res.iterations) < np.median(res_mid.iterations)
    assert res.converged.mean() > 0.95 > res_mid.converged.mean()
    assert np.all(res.position_error_mm[res.converged] < 1e-6)
    assert branch_ok.mean() > 0.9                                   # and mostly on the trained branch


def test_out_of_workspace_and_out_of_branch_are_flagged(irb140, net140):
    """Measured: 86 % of held-out branch poses pass the check (false alarms: seed joints beyond the box,
    or FK of the seed beyond the validation p95); of poses needing J1 = 175 deg (outside the box) 6.5 %
    pass; every pose 2-3 m out is ``outside_workspace``."""
    q, T = _held_out(irb140)
    assert net140.seed(irb140, T).in_domain.mean() > 0.8          # not a flag that is always on
    far = T[:3].copy()
    far[:, :3, 3] *= 4.0                                            # 2-3 m away: outside the workspace
    # the same poses reached over the back (shoulder "back" branch, J1 near 180 deg on branch 0)
    q_back = q[:200].copy()
    q_back[:, 0] = np.radians(175.0)
    back = irb140.fk(q_back)
    assert not on_branch(irb140, q_back, net140.branch).any()
    p_far, p_back = net140.seed(irb140, far), net140.seed(irb140, back)
    assert not p_far.in_domain.any() and set(p_far.status) == {"outside_workspace"}
    assert p_back.in_domain.mean() < 0.12


def test_file_round_trip_and_wrong_robot(tmp_path, irb140, net140):
    path = save_ik_network(tmp_path / "irb140.iknet.npz", net140)
    back = load_ik_network(path, irb140)
    _, T = _held_out(irb140, 50)
    np.testing.assert_array_equal(back.predict_joints(T), net140.predict_joints(T))
    assert back.branch.name == "front/up/noflip" and back.structure == net140.structure
    assert back.envelope == net140.envelope
    with pytest.raises(FileExistsError):
        save_ik_network(path, net140)
    with pytest.raises(IKNetworkFileError, match="trained for robot 'abb_irb140'.*not for 'kuka_kr150_r3100'"):
        load_ik_network(path, load_robot("kuka_kr150_r3100"))
    with pytest.raises(IKNetworkFileError, match="other kinematic parameters of 'abb_irb140'"):
        load_ik_network(path, irb140.with_params(a2=360.5))
    (tmp_path / "junk.npz").write_bytes(b"not a zip")
    with pytest.raises(IKNetworkFileError, match="junk.npz"):
        load_ik_network(tmp_path / "junk.npz")


def test_ga_is_seeded_and_not_worse_than_the_default(irb140):
    pytest.importorskip("deap")
    from robocal.kinematics.ik_net.encoding import encode_poses
    from robocal.kinematics.ik_net.tuning import tune_structure, validation_rms

    q, T = _held_out(irb140, 1500, seed=5)
    X = encode_poses(T, 800.0)
    args = (X[300:], q[300:], X[:300], q[:300])
    runs = [tune_structure(*args, seed=2, population=4, generations=1, k_min=20, k_max=150) for _ in range(2)]
    assert runs[0][0] == runs[1][0]                                      # reproducible
    best, history = runs[0]
    assert history[-1]["best_rms_rad"] <= history[0]["best_rms_rad"]
    assert validation_rms(best, *args, seed=2) == pytest.approx(history[-1]["best_rms_rad"])
    start = Structure(int(round(np.exp(np.log(20) + 0.72 * np.log(150 / 20)))), 2.0, 1e-8, 3.0)
    assert history[-1]["best_rms_rad"] <= validation_rms(start, *args, seed=2) * 1.05


def test_cli_train_and_seeded_ik(tmp_path, irb140):
    out = tmp_path / "net.npz"
    r = CliRunner().invoke(main, ["ik-train", "abb_irb140", "--samples", "1500", "--seed", "1", "--out", str(out),
                                  "--no-tune"])
    assert r.exit_code == 0, r.output
    assert "[sample]" in r.output and "wrote" in r.output
    q_true = np.radians([20.0, 10.0, 15.0, 30.0, 50.0, -40.0])
    T = irb140.fk(q_true)
    from robocal.transforms import pose_from_transform

    pose = pose_from_transform(T, "kuka_abc", length_unit="mm", angle_unit="deg")
    r = CliRunner().invoke(main, ["ik", "abb_irb140", *map(str, pose), "--seed-net", str(out), "--json"])
    assert r.exit_code == 0, r.output
    data = json.loads(r.output)
    assert data["seed"]["in_domain"] and data["seed"]["branch"] == "front/up/noflip"
    assert data["seed"]["solution_on_branch"]
    q = np.array(data["solutions"][0]["joints"])
    np.testing.assert_allclose(irb140.fk(q)[:3, 3], T[:3, 3], atol=1e-5)
    r = CliRunner().invoke(main, ["ik", "kuka_kr150_r3100", "1965", "0", "1984", "0", "90", "0", "--seed-net", str(out)])
    assert r.exit_code == 1 and "trained for robot 'abb_irb140'" in r.output


def test_joint_box_branch_without_closed_form(tmp_path):
    """UR10 (offset wrist, no closed form in robocal): the branch is a joint box (elbow J3 and wrist J5
    on one side, J1 within +-90 deg). Measured (3000 samples, 300 centres, 400 poses): median 5 iterations,
    99 % converged, 96.5 % inside the box from the seed; 19 iterations and 56 % converged from the middle
    of the joint ranges; 10 iterations, 95 % converged but only 61 % inside the box from the box's middle."""
    from robocal.kinematics.ik_net import joint_box_branch

    ur10 = load_robot("ur10")
    box = {"J1": (-90, 90), "J2": (-170, -10), "J3": (10, 150), "J5": (10, 150)}
    branch = joint_box_branch(ur10, {k: np.radians(v) for k, v in box.items()})
    net = train_ik_network(ur10, 3000, seed=3, tune=False, structure=SMALL, branch=branch)
    q = sample_branch(None, branch, 400, np.random.default_rng(11))
    T = ur10.fk(q)
    res, pred, in_box = ik_with_seed_network(ur10, T, net)
    res_mid = ik_numeric(ur10, T, ur10.limits.mean(axis=1))
    assert np.median(res.iterations) < np.median(res_mid.iterations)
    assert res.converged.mean() > 0.95 and in_box.mean() > 0.85
    r = CliRunner().invoke(main, ["ik-train", "ur10", "--samples", "500", "--no-tune", "--out", str(tmp_path / "x.npz")])
    assert r.exit_code == 1 and "--joint-box" in r.output and "no closed form" in r.output


def test_cli_network_file_next_to_robot_file(tmp_path):
    """A calibrated robot file (beta tilts): ik-train without --out writes <stem>.iknet.npz beside it,
    and the file is valid for that robot file (fingerprint survives the TOML round trip)."""
    from robocal.robots import robot_to_toml

    robot_file = tmp_path / "cell.toml"
    robot_file.write_text(robot_to_toml(_tilted()), encoding="utf-8")
    r = CliRunner().invoke(main, ["ik-train", str(robot_file), "--samples", "1000", "--seed", "2", "--no-tune"])
    assert r.exit_code == 0, r.output
    net_file = tmp_path / "cell.iknet.npz"
    assert net_file.is_file()
    r = CliRunner().invoke(main, ["ik", str(robot_file), "450", "50", "700", "10", "80", "20", "--seed-net",
                                  str(net_file), "--json"])
    assert r.exit_code == 0, r.output
    assert json.loads(r.output)["seed"]["branch"] == "front/up/noflip"
    r = CliRunner().invoke(main, ["ik-train", str(robot_file), "--samples", "1000", "--no-tune"])
    assert r.exit_code == 1 and "file exists" in r.output
