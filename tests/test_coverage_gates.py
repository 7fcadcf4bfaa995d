"""Issue 28, item 5: coverage gates on calibrate. The three degenerate campaigns of the issue (J4
never moved; J2 and J3 fixed; only J1 moved) fail the gate with exit 3 and a reason naming the
joint, and write no robot file; a full campaign still passes and the result shows the joint-range
coverage."""

from __future__ import annotations

import json
from dataclasses import replace

import numpy as np
import pytest
from click.testing import CliRunner

from robocal.calib.cell import default_cell, sample_feasible
from robocal.cli import main
from robocal.io.measurements import write_measurements
from robocal.robots import load_robot
from robocal.sim import LaserTracker, VirtualRobot

ROBOT = "kuka_kr150_r3100"


def _campaign(tmp_path, fixed: dict, n=40):
    model = load_robot(ROBOT)
    ranges = np.array(model.limits, dtype=float)
    for k, deg in fixed.items():
        ranges[k] = np.radians([deg, deg])
    cell = replace(default_cell((15.0, -10.0, 60.0)), joint_ranges=ranges)
    q, _ = sample_feasible(cell, model, n, np.random.default_rng(3), margin=0.05)
    virtual = VirtualRobot.perturbed(model, 4, joint_noise_deg=0.0)
    tracker = LaserTracker.placed(5, np.array([[15.0, -10.0, 60.0]]), sigma_mm=0.02)
    meas = tracker.measure(virtual, q, np.random.default_rng(6))
    path = tmp_path / "m.csv"
    write_measurements(path, meas)
    return path


@pytest.mark.parametrize("fixed, joints", [({3: 0.0}, ["A4"]), ({1: -60.0, 2: 60.0}, ["A2", "A3"]),
                                           ({1: -60.0, 2: 60.0, 3: 0.0, 4: 40.0, 5: 0.0}, ["A2", "A6"])])
def test_degenerate_campaigns_fail_naming_the_joint(tmp_path, fixed, joints):
    data = _campaign(tmp_path, fixed)
    out = tmp_path / "cal"
    r = CliRunner().invoke(main, ["calibrate", ROBOT, str(data), "--out", str(out), "--no-report"])
    assert r.exit_code == 3, r.output
    res = json.loads((out / "result.json").read_text())
    assert res["status"] == "failed"
    text = " ".join(res["reasons"])
    for j in joints:
        assert f"joint {j} moved only" in text, text
    assert not (out / "calibrated_robot.toml").exists()
    if len(fixed) == 5:  # only A1 moved: most parameters are not identified
        assert "parameters a full campaign identifies were identified" in text


def test_full_campaign_passes_and_reports_coverage(tmp_path):
    data = _campaign(tmp_path, {})
    out = tmp_path / "cal"
    r = CliRunner().invoke(main, ["calibrate", ROBOT, str(data), "--out", str(out)])
    assert r.exit_code == 0, r.output
    res = json.loads((out / "result.json").read_text())
    assert res["status"] == "ok", res["reasons"]
    cov = {c["joint"]: c for c in res["joint_coverage"]}
    assert cov["A4"]["span"] > 100.0 and 0 < cov["A4"]["fraction"] <= 1.0
    assert "Joint-range coverage" in (out / "report.html").read_text()
