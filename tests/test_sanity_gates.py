"""Issue 9: no silent wrong answer. The reproducers of the issue (swapped joint columns, swapped
x/z, radians declared as degrees, 500 mm noise, random points) end in a FAILED result (exit code
3, ``status: failed`` with reasons, a report banner, no calibrated robot file) or an input error;
the same gates are in the Python API (:mod:`robocal.calib.sanity`)."""

import json
import math

import numpy as np
import pytest
from click.testing import CliRunner

from robocal.calib import sanity
from robocal.cli import main

SEED = 5


def run(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


@pytest.fixture(scope="module")
def campaign(tmp_path_factory):
    d = tmp_path_factory.mktemp("gates")
    csv = d / "ur10.csv"
    r = run("simulate", "tracker", "ur10", "--poses", 30, "--noise", 0.02, "--seed", SEED, "--out", csv)
    assert r.exit_code == 0, r.output
    return d, csv


def _rewrite(src, dst, fn):
    """``dst`` with the header lines of ``src`` and fn(list of data rows as float lists) as rows."""
    lines = src.read_text().splitlines()
    head = [ln for ln in lines if not ln[:1].isdigit()]
    rows = [[float(v) for v in ln.split(",")] for ln in lines if ln[:1].isdigit()]
    body = [",".join([str(int(r[0]))] + [repr(float(v)) for v in r[1:]]) for r in fn(rows)]
    dst.write_text("\n".join(head + body) + "\n")
    return dst


def _assert_failed(r, out, *needles, robot_file=False):
    assert r.exit_code == 3, r.output
    res = json.loads((out / "result.json").read_text())
    assert res["status"] == "failed" and res["reasons"]
    text = " ".join(res["reasons"])
    for n in needles:
        assert n in text, text
    assert (out / "calibrated_robot.toml").exists() == robot_file  # only with --force
    assert "FAILED: this result did not pass the sanity gates" in (out / "report.html").read_text()
    assert "FAILED" in r.output
    return res


def test_a_good_campaign_passes(campaign):
    d, csv = campaign
    r = run("calibrate", "ur10", csv, "--out", d / "good", "--noise", 0.02)
    assert r.exit_code == 0, r.output
    res = json.loads((d / "good" / "result.json").read_text())
    assert res["status"] == "ok" and res["reasons"] == []
    assert all(c["passed"] for c in res["sanity_checks"].values())
    assert (d / "good" / "calibrated_robot.toml").exists()


def test_swapped_joint_columns_fail(campaign):
    d, csv = campaign
    bad = d / "swapped_joints.csv"
    bad.write_text(csv.read_text().replace("pose,J1,J2,", "pose,J2,J1,"))
    res = _assert_failed(run("calibrate", "ur10", bad, "--out", d / "o1"), d / "o1", "swapped joint",
                         "misses the measurements")
    assert res["sanity_checks"]["nominal_misfit"]["value"] > 100.0


def test_swapped_x_and_z_fail(campaign):
    d, csv = campaign
    bad = _rewrite(csv, d / "swapped_xz.csv", lambda rows: [r[:7] + [r[9], r[8], r[7]] for r in rows])
    _assert_failed(run("calibrate", "ur10", bad, "--out", d / "o2"), d / "o2", "x/y/z columns")


def test_500_mm_noise_fails_and_force_writes_the_robot(campaign):
    d, csv = campaign
    rng = np.random.default_rng(1)
    bad = _rewrite(csv, d / "noisy.csv", lambda rows: [r[:7] + list(np.array(r[7:]) + rng.normal(0, 500, 3))
                                                       for r in rows])
    res = _assert_failed(run("calibrate", "ur10", bad, "--out", d / "o3", "--noise", 0.02, "--force"), d / "o3",
                         "declared instrument noise", robot_file=True)
    assert not res["sanity_checks"]["residual_vs_noise"]["passed"]


def test_random_points_fail(campaign):
    d, csv = campaign
    rng = np.random.default_rng(2)
    bad = _rewrite(csv, d / "random.csv", lambda rows: [r[:7] + list(rng.uniform(-2000, 2000, 3)) for r in rows])
    _assert_failed(run("calibrate", "ur10", bad, "--out", d / "o4"), d / "o4", "misses the measurements")


def test_radians_declared_as_degrees_is_an_input_error(campaign):
    d, csv = campaign
    bad = _rewrite(csv, d / "radians.csv", lambda rows: [r[:1] + list(np.radians(r[1:7])) + r[7:] for r in rows])
    r = run("calibrate", "ur10", bad, "--out", d / "o5")
    assert r.exit_code == 1 and r.output.startswith("Error:"), r.output
    assert "look like radians" in r.output and "angle_unit: rad" in r.output
    assert not (d / "o5").exists()


# ------------------------------------------------------------------------------------ Python API
def test_verdict_thresholds():
    ok = sanity.calibration_verdict(robot="r", rms_before_mm=2.0, rms_after_mm=0.05, sigma_mm=0.02,
                                    holdout_before_mm=2.1, holdout_after_mm=0.06)
    assert ok.ok and ok.status == "ok" and ok.to_dict()["reasons"] == []
    # 0.05 mm is 1.4 x the noise RMS of sigma 0.02; 0.4 mm is 11.5 x: above the factor 10
    v = sanity.calibration_verdict(robot="r", rms_before_mm=2.0, rms_after_mm=0.4, sigma_mm=0.02)
    assert v.status == "failed" and "12 x the declared instrument noise" in v.reasons[0]
    v = sanity.calibration_verdict(robot="r", rms_before_mm=2.0, rms_after_mm=0.05,
                                   holdout_before_mm=1.0, holdout_after_mm=1.2)
    assert not v.ok and "held-out error got worse: 1 -> 1.2 mm" in v.reasons[0]
    assert sanity.calibration_verdict(robot="r", rms_before_mm=2.0, rms_after_mm=0.05, holdout_before_mm=1.0,
                                      holdout_after_mm=1.09).ok
    assert not sanity.calibration_verdict(robot="r", rms_before_mm=60.0, rms_after_mm=0.05).ok
    assert not sanity.calibration_verdict(robot="r", rms_before_mm=2.0, rms_after_mm=6.0).ok  # no sigma: 5 mm


def test_parameter_plausibility_bounds():
    names, units = ["a2", "d1", "theta3"], ["mm", "mm", "rad"]
    nominal = [1000.0, 0.0, 0.0]

    def v(change):
        return sanity.calibration_verdict(robot="r", rms_before_mm=2.0, rms_after_mm=0.1,
                                          parameters=(names, units, nominal, np.add(nominal, change)))

    assert v([49.0, 24.0, math.radians(4.9)]).ok  # 5 % of 1000 mm = 50 mm; 25 mm; 5 deg
    bad = v([51.0, 0.0, 0.0])
    assert not bad.ok and "a2 +51 mm" in bad.reasons[0]
    assert "d1 +26 mm" in v([0.0, 26.0, 0.0]).reasons[0]
    assert "theta3 +6 deg" in v([0.0, 0.0, math.radians(6.0)]).reasons[0]


def test_tool_and_sensor_verdicts():
    assert sanity.touchup_verdict(0.3, [0, 0, 250]).ok
    assert "residual RMS 8 mm" in sanity.touchup_verdict(8.0, [0, 0, 250]).reasons[0]
    assert "2500 mm from the flange" in sanity.touchup_verdict(0.3, [0, 0, 2500]).reasons[0]
    assert sanity.sensor_verdict(90.5, 0.2).ok
    assert not sanity.sensor_verdict(75.0, 0.2).ok and not sanity.sensor_verdict(90.0, 30.0).ok
