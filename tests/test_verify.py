"""Quick verification: the chi-square decision keeps its false-alarm rate and names a joint's jump."""

from __future__ import annotations

import json

import numpy as np
import pytest
from click.testing import CliRunner

from robocal.cli import main
from robocal.performance.verify import verify_positions
from robocal.robots import load_robot


#: a reflector on a tool 150 mm beyond the flange and 100 mm off its axis (a typical SMR holder)
REFLECTOR = np.array([0.0, 100.0, 150.0])


def _points(model, q):
    T = model.fk(q)
    return T[:, :3, :3] @ REFLECTOR + T[:, :3, 3]


def _jacobian(model, q, h=1e-6):
    n = q.shape[1]
    J = np.empty((len(q), 3, n))
    for j in range(n):
        dq = np.zeros(n)
        dq[j] = h
        J[:, :, j] = (_points(model, q + dq) - _points(model, q - dq)) / (2 * h)
    return J


def test_false_alarm_rate_is_the_stated_one():
    """1000 healthy checks: the robot differs from the calibrated model only by a draw from the
    calibration's covariance, plus instrument noise; the test flags alpha of them (+-2 %)."""
    rng = np.random.default_rng(0)
    N, P, sigma = 10, 20, 0.02
    Jp = rng.normal(0, 1, (3 * N, P))
    Cp = np.diag(rng.uniform(0.0005, 0.002, P))          # parameter covariance: 0.02-0.05 mm effects
    C = Jp @ Cp @ Jp.T
    pred = rng.uniform(-1000, 1000, (N, 3))
    L = np.linalg.cholesky(Cp)
    for alpha in (0.01, 0.05):
        flagged = 0
        for _ in range(1000):
            truth = pred + (Jp @ (L @ rng.normal(0, 1, P))).reshape(N, 3)
            meas = truth + rng.normal(0, sigma, (N, 3))
            v = verify_positions(meas, pred, instrument_sigma_mm=sigma, prediction_covariance_mm2=C,
                                 false_alarm_rate=alpha)
            flagged += v.decision != "ok"
        assert abs(flagged / 1000 - alpha) <= 0.02, (alpha, flagged)


@pytest.mark.parametrize("joint", [0, 1, 2, 3, 4])
def test_an_offset_jump_of_005_deg_is_detected_and_named(joint):
    """A 0.05 deg jump of J1..J5 on an IRB 140, 10 random poses, tracker noise 0.02 mm, calibration
    uncertainty 0.01 mm per coordinate, a reflector 150 mm beyond the flange: detected in >= 95 %, the joint named in >= 80 % of 100 trials."""
    model = load_robot("abb_irb140")
    rng = np.random.default_rng(10 + joint)
    lo, hi = model.limits[:, 0], model.limits[:, 1]
    detected = named = 0
    for _ in range(100):
        q = lo + (hi - lo) * rng.uniform(0.2, 0.8, (10, 6))
        pred = _points(model, q)
        dq = np.zeros(6)
        dq[joint] = np.radians(0.05)
        truth = _points(model, q + dq)
        meas = truth + rng.normal(0, 0.02, truth.shape)
        C = np.tile(np.eye(3) * 0.01 ** 2, (10, 1, 1))
        v = verify_positions(meas, pred, instrument_sigma_mm=0.02, prediction_covariance_mm2=C,
                             joint_jacobian=_jacobian(model, q), joint_names=model.controller_joints)
        detected += v.decision != "ok"
        named += v.suspect_joint == model.controller_joints[joint]
    assert detected >= 95
    assert named >= 80


def test_verify_command_ok_and_fault(tmp_path):
    run = CliRunner().invoke
    assert run(main, ["simulate", "tracker", "abb_irb140", "--poses", "60", "--seed", "3",
                      "--out", str(tmp_path / "c.csv")]).exit_code == 0
    assert run(main, ["calibrate", "abb_irb140", str(tmp_path / "c.csv"), "--out", str(tmp_path / "cal")]).exit_code == 0
    # a healthy check: ten new poses of the same robot
    assert run(main, ["simulate", "tracker", "abb_irb140", "--poses", "10", "--seed", "3",
                      "--out", str(tmp_path / "v.csv")]).exit_code == 0
    db = ["--db", str(tmp_path / "h.sqlite"), "--robot-id", "irb140-cell2", "--instrument", "AT960 #42"]
    r = run(main, ["verify", str(tmp_path / "cal"), str(tmp_path / "v.csv"), "--json", "--time", "2026-05-01T06:00Z",
                   "--temperature", "23.5"] + db)
    assert r.exit_code == 0, r.output
    assert json.loads(r.output)["decision"] == "ok"
    # J3's encoder jumped by 0.2 deg: the joint readings of the check are off by it
    lines = (tmp_path / "v.csv").read_text().splitlines()
    head = [i for i, s in enumerate(lines) if not s.startswith("#")][0]
    cols = lines[head].split(",")
    k = cols.index("J3")
    out = lines[:head + 1]
    for s in lines[head + 1:]:
        v = s.split(",")
        v[k] = repr(float(v[k]) - 0.2)
        out.append(",".join(v))
    (tmp_path / "f.csv").write_text("\n".join(out) + "\n")
    r = run(main, ["verify", str(tmp_path / "cal"), str(tmp_path / "f.csv"), "--json", "--time", "2026-06-01T06:00Z"]
            + db)
    assert r.exit_code == 6, r.output
    res = json.loads(r.output)
    assert res["decision"] == "mechanical fault suspected" and res["suspect_joint"] == "J3"
    assert res["suspect_offset"]["value"] == pytest.approx(0.2, abs=0.02)
    # both checks are in the robot's history, with time, temperature and instrument
    r = run(main, ["history", "irb140-cell2", "--db", str(tmp_path / "h.sqlite"), "--json"])
    assert r.exit_code == 0, r.output
    ver = json.loads(r.output)["verifications"]
    assert [v["decision"] for v in ver] == ["ok", "mechanical fault suspected"]
    assert ver[0]["time"].startswith("2026-05-01T06:00") and ver[0]["temperature_c"] == 23.5
    assert ver[1]["suspect"] == "J3 offset" and ver[1]["instrument"] == "AT960 #42"
    assert abs(ver[1]["suspect_value"]) == pytest.approx(np.radians(0.2), abs=np.radians(0.02))
    r = run(main, ["history", "irb140-cell2", "--db", str(tmp_path / "h.sqlite"), "--plot", str(tmp_path / "v.png")])
    assert r.exit_code == 0 and "mechanical fault suspected" in r.output
    # fleet status lists the last verification and flags the robot
    r = run(main, ["fleet", "status", "--db", str(tmp_path / "h.sqlite"), "--no-plots", "--json"])
    row = json.loads(r.output)["robots"][0]
    assert row["last_verification"]["decision"] == "mechanical fault suspected" and row["verification_failed"]
