"""ISO 9283 figures and verification outcomes over the robot's life: the history database
(schema version 3, migrated from older files), `robocal history` and `robocal fleet status`."""

from __future__ import annotations

import json
import math
import sqlite3

import pytest
from click.testing import CliRunner

from robocal.cli import main
from robocal.store import HistoryInputError, HistoryStore


def _run(args):
    r = CliRunner().invoke(main, [str(a) for a in args])
    return r


def test_a_version_2_database_gains_the_iso_and_verification_tables(tmp_path):
    """An older history file (schema 2, one calibration) opened by this robocal: version 3, the
    old cycle untouched, ISO figures and a verification can be added."""
    from robocal.store import _schema

    db = tmp_path / "v2.sqlite"
    full = _schema.MIGRATIONS
    try:
        _schema.MIGRATIONS, _schema.SCHEMA_VERSION = full[:2], 2
        with HistoryStore.open(db) as s:
            with s.cycle("kr", "geometric_calibration", started_at="2026-01-01T00:00Z") as c:
                c.add_parameter("theta2", 1e-4, "rad")
                c.add_metric("residual_rms_after", 0.03, "mm")
        con = sqlite3.connect(db)
        assert {r[0] for r in con.execute("SELECT name FROM sqlite_master WHERE type='table'")} \
            .isdisjoint({"iso9283_figures", "verifications"})
        con.close()
    finally:
        _schema.MIGRATIONS, _schema.SCHEMA_VERSION = full, full[-1].version
    with HistoryStore.open(db) as s:
        assert s.schema_version == 3
        (old,) = s.cycles("kr")
        assert old.metrics["residual_rms_after"].value == pytest.approx(0.03)
        assert s.parameter_history("kr", "theta2")["theta2"].values[0] == pytest.approx(1e-4)
        with s.cycle("kr", "measurement", started_at="2026-02-01T00:00Z") as c:
            c.add_iso_figures([{"symbol": "AP", "pose": "P1", "value": 0.5, "unit": "mm", "uncertainty": 0.04,
                                "adequate": True},
                               {"symbol": "AP", "pose": "", "value": 0.5, "unit": "mm"}])
        with s.cycle("kr", "measurement", started_at="2026-03-01T00:00Z") as c:
            c.add_verification(decision="mechanical fault suspected", statistic=120.0, dof=30, threshold=50.9,
                               false_alarm_rate=0.01, n_poses=10, rms_mm=0.2, suspect="J3 offset",
                               suspect_value=math.radians(0.05), suspect_unit="rad", instrument="AT960 #1234",
                               temperature_c=24.5)
        ap = s.iso_figure_history("kr", "AP")
        assert list(ap.values) == [0.5] and math.isnan(ap.std[0])
        ap1 = s.iso_figure_history("kr", "AP", "P1")
        assert ap1.std[0] == pytest.approx(0.02)         # U/2
        (v,) = s.verifications("kr")
        assert v["decision"] == "mechanical fault suspected" and v["suspect"] == "J3 offset"
        assert v["temperature_c"] == 24.5 and v["instrument"] == "AT960 #1234"
        assert s.check() == []


@pytest.fixture(params=["sqlite", "postgresql"])
def any_db(request, tmp_path):
    if request.param == "sqlite":
        return str(tmp_path / "h.sqlite")
    return request.getfixturevalue("fresh_server_db")


def test_iso_figures_and_verifications_round_trip(any_db):
    """The new tables on SQLite and on a PostgreSQL server: written by the workflow helpers, read back."""
    from robocal.workflows.performance.iso9283_history import record_iso_run, record_verification

    run = {"pose": {"P1": {"AP_mm": 0.8, "AP_x_mm": 0.1, "AP_y_mm": -0.2, "AP_z_mm": 0.77, "RP_mm": 0.06,
                           "AP_a_deg": -0.01, "RP_a_deg": 0.004},
                    "P2": {"AP_mm": 1.1, "AP_x_mm": 0.0, "AP_y_mm": 0.0, "AP_z_mm": 1.1, "RP_mm": 0.05}},
           "vap": {}, "distance": {"AD_mm": -0.3, "RD_mm": 0.04}, "drift": None,
           "path": {"line": {"AT_mm": 0.9, "RT_mm": 0.07}},
           "adequacy": {"RP_mm.P1": {"U_mm": 0.03, "adequate": False}, "AP_mm.P2": {"U_mm": 0.03, "adequate": True}}}
    cid = record_iso_run(any_db, "r1", run, time="2026-04-01T10:00Z", temperature_c=25.0, instrument="AT960")
    record_verification(any_db, "r1", {"decision": "recalibrate", "statistic": 80.0, "dof": 30, "threshold": 50.9,
                                       "false_alarm_rate": 0.01, "n_poses": 10, "rms_mm": 0.09, "max_mm": 0.2,
                                       "suspect_joint": None, "time": "2026-05-01T10:00Z", "instrument": "AT960",
                                       "temperature_c": None, "model": "cal/calibrated_robot.toml"})
    with HistoryStore.open(any_db, create=False) as s:
        figs = {(f["symbol"], f["pose"]): f for f in s.iso_figures(cid)}
        assert figs["AP", ""]["value"] == pytest.approx(1.1) and figs["AP", ""]["adequate"] is True
        assert figs["RP", ""]["value"] == pytest.approx(0.06) and figs["RP", ""]["adequate"] is False
        assert figs["AP_a", "P1"]["unit"] == "rad" and figs["AP_a", "P1"]["value"] == pytest.approx(math.radians(-0.01))
        assert figs["AP_a", ""]["value"] == pytest.approx(math.radians(0.01))     # worst = largest magnitude
        assert figs["AD", ""]["value"] == pytest.approx(-0.3) and figs["AT", "line"]["value"] == pytest.approx(0.9)
        assert s.metric_history("r1", "iso9283.RP").values == pytest.approx([0.06])
        (v,) = s.verifications("r1")
        assert v["decision"] == "recalibrate" and v["suspect"] is None and v["time"].month == 5


def test_bad_iso_figures_and_verifications_are_refused(tmp_path):
    with HistoryStore.open(tmp_path / "h.sqlite") as s:
        with pytest.raises(HistoryInputError, match="convert to radians"):
            with s.cycle("r", "measurement", record_failure=False) as c:
                c.add_iso_figures([{"symbol": "AP_a", "pose": "P1", "value": 0.1, "unit": "deg"}])
        with pytest.raises(HistoryInputError, match="already added"):
            with s.cycle("r", "measurement", record_failure=False) as c:
                c.add_iso_figures([{"symbol": "RP", "pose": "P1", "value": 0.1, "unit": "mm"}] * 2)
        with pytest.raises(HistoryInputError, match="decision"):
            with s.cycle("r", "measurement", record_failure=False) as c:
                c.add_verification(decision="fine", statistic=1.0, dof=3, threshold=11.3, false_alarm_rate=0.01,
                                   n_poses=1)
        assert s.robots() == [] or s.cycles("r") == []


@pytest.fixture(scope="module")
def fleet_db(tmp_path_factory):
    """Two simulated IRB 140 (the same hidden true robot of `simulate tracker --seed 3`) tested
    after the ISO plan three times, 60 days apart: "worn" loses repeatability (joint noise 0.002,
    0.005, 0.008 deg: worn bearings), "healthy" keeps 0.002 deg. Every run is evaluated with
    --db; also a geometric calibration of each so that neither is stale."""
    d = tmp_path_factory.mktemp("isohist")
    r = _run(["iso9283", "plan", "abb_irb140", "--out", d / "plan", "--cycles", "10", "--path-cycles", "2"])
    assert r.exit_code == 0, r.output
    r = _run(["simulate", "tracker", "abb_irb140", "--poses", "10", "--seed", "3", "--out", d / "c.csv"])
    assert r.exit_code == 0, r.output
    db = d / "h.sqlite"
    with HistoryStore.open(db) as s:
        for robot in ("worn", "healthy"):
            with s.cycle(robot, "geometric_calibration", started_at="2026-01-01T00:00Z") as c:
                c.add_parameter("theta2", 0.0, "rad")
    results = {}
    for robot, noise in (("worn", (0.002, 0.005, 0.008)), ("healthy", (0.002, 0.002, 0.002))):
        for k, jn in enumerate(noise):
            out = d / f"{robot}{k}.csv"
            r = _run(["simulate", "iso9283", "abb_irb140", d / "plan", "--seed", 10 + k, "--truth", d / "c.truth.json",
                      "--out", out, "--joint-noise", jn, "--instrument-at", "3500,0,300"])
            assert r.exit_code == 0, r.output
            r = _run(["iso9283", "evaluate", d / "plan", out, "--out", d / f"ev-{robot}{k}", "--mpe", "15um+6um/m",
                      "--instrument-at", "3500,0,300", "--db", db, "--robot-id", robot,
                      "--time", f"2026-0{1 + 2 * k}-02T08:00Z", "--temperature", 21 + k, "--instrument", "AT960",
                      "--json"])
            assert r.exit_code == 0, r.output
            results[robot, k] = json.loads(r.output)
    return d, db, results


def test_iso_runs_are_recorded_with_time_temperature_and_instrument(fleet_db):
    _, db, results = fleet_db
    with HistoryStore.open(db, create=False) as s:
        rp = s.iso_figure_history("worn", "RP")
        ap = s.iso_figure_history("worn", "AP")
        assert len(rp) == 3 and len(ap) == 3
        for k in range(3):
            summ = results["worn", k]["runs"][0]["summary"]
            assert rp.values[k] == pytest.approx(summ["RP_mm"], abs=1e-12)
            assert ap.values[k] == pytest.approx(summ["AP_mm"], abs=1e-12)
            # the stated uncertainty is the tracker's MPE at the pose's distance (< 4.2 m: U < 40 um)
            assert 0.015 < 2 * rp.std[k] < 0.015 + 0.006 * 4.2
        cyc = s.cycles("worn", kind="measurement")
        assert [c.meta["temperature_c"] for c in cyc] == [21, 22, 23]
        assert all(c.meta["instrument"] == "AT960" and c.meta["test"] == "iso9283" for c in cyc)
        assert str(rp.times[1]).startswith("2026-03-02T08:00")
        per_pose = s.iso_figures(cyc[0].id)
        assert {f["pose"] for f in per_pose if f["symbol"] == "RP"} == {"P1", "P2", "P3", "P4", "P5", ""}
        # worn bearings: RP grows with the joint noise (0.002 -> 0.008 deg: x 4, less the instrument part)
        assert rp.values[2] > 2.5 * rp.values[0]
        hr = s.iso_figure_history("healthy", "RP")
        assert max(hr.values) < 1.6 * min(hr.values)      # 10 cycles: RP scatters by ~ 20 %


def test_fleet_status_flags_the_robot_whose_rp_trend_crosses_the_tolerance(fleet_db):
    _, db, results = fleet_db
    rp_worn = [results["worn", k]["runs"][0]["summary"]["RP_mm"] for k in range(3)]
    rp_healthy = [results["healthy", k]["runs"][0]["summary"]["RP_mm"] for k in range(3)]
    tol = 0.15
    assert max(rp_healthy) < tol < max(rp_worn) * 1.2     # the numbers the verdict rests on
    r = _run(["fleet", "status", "--db", db, "--rp-tolerance", tol, "--ap-tolerance", 5, "--no-plots", "--json",
              "--max-age", 10000])
    assert r.exit_code == 3, r.output
    res = json.loads(r.output)
    assert res["flagged"] == ["worn"]
    rows = {row["robot"]: row for row in res["robots"]}
    worn, healthy = rows["worn"], rows["healthy"]
    assert worn["performance_drifting"] and not healthy["performance_drifting"]
    assert worn["iso"]["RP"]["over"] and not worn["iso"]["AP"]["over"]
    # the trend line through the three tests, extrapolated to now, is above the last test's value
    assert worn["iso"]["RP"]["trend_now_mm"] > worn["iso"]["RP"]["last_mm"] > tol
    assert worn["iso"]["RP"]["slope_mm_per_day"] > 0
    assert any("RP trend" in s for s in worn["reasons"])
    assert healthy["iso"]["RP"]["trend_now_mm"] < tol
    # without the ISO tolerances nobody is flagged (neither is stale, no parameter drifts)
    r = _run(["fleet", "status", "--db", db, "--no-plots", "--max-age", 10000])
    assert r.exit_code == 0, r.output
    assert "last verification -" in r.output


def test_fleet_status_at_a_fixed_time_gives_the_trend_line_there(fleet_db):
    """``--at``: the trend is the least-squares line through the three tests (times 2026-01-02,
    03-02, 05-02 08:00Z), evaluated at the given time, whatever day the command runs; a time
    without a zone is refused (exit 1)."""
    import numpy as np

    _, db, results = fleet_db
    rp = [results["worn", k]["runs"][0]["summary"]["RP_mm"] for k in range(3)]
    days = np.array([0.0, 59.0, 120.0])  # 2026-01-02, 03-02, 05-02
    b, a = np.polyfit(days, rp, 1)
    at_days = 328.0 + 16.0 / 24.0  # 2026-11-27T00:00Z after 2026-01-02T08:00Z
    r = _run(["fleet", "status", "--db", db, "--rp-tolerance", 0.15, "--no-plots", "--json", "--at",
              "2026-11-27T00:00Z"])
    assert r.exit_code == 3, r.output
    worn = {row["robot"]: row for row in json.loads(r.output)["robots"]}["worn"]
    assert worn["iso"]["RP"]["trend_now_mm"] == pytest.approx(a + b * at_days, rel=1e-9)
    assert worn["age_days"] == pytest.approx(330.0, abs=1e-9)  # the calibration of 2026-01-01T00:00Z
    r = _run(["fleet", "status", "--db", db, "--no-plots", "--at", "2026-11-27T00:00"])
    assert r.exit_code == 1 and "Error:" in r.output and "time zone" in r.output, r.output


def test_history_lists_and_plots_ap_rp_over_time(fleet_db, tmp_path):
    _, db, results = fleet_db
    r = _run(["history", "worn", "--db", db, "--plots", tmp_path])
    assert r.exit_code == 0, r.output
    assert "ISO 9283 performance tests" in r.output
    rp0 = results["worn", 0]["runs"][0]["summary"]["RP_mm"]
    assert f"{rp0:.4f}" in r.output
    png = (tmp_path / "worn_drift.png").read_bytes()
    assert png[:8] == b"\x89PNG\r\n\x1a\n" and len(png) > 10000
    r = _run(["history", "worn", "--db", db, "--json"])
    data = json.loads(r.output)
    assert data["iso9283"]["RP"]["values"] == pytest.approx(
        [results["worn", k]["runs"][0]["summary"]["RP_mm"] for k in range(3)], abs=1e-12)
    assert data["verifications"] == []


def test_history_options_are_checked_before_any_work(fleet_db, tmp_path):
    d, _, _ = fleet_db
    base = ["iso9283", "evaluate", d / "plan", d / "worn0.csv", "--out", tmp_path / "ev"]
    r = _run(base + ["--db", tmp_path / "h.sqlite"])
    assert r.exit_code == 1 and "--db and --robot-id go together" in r.output
    r = _run(base + ["--db", tmp_path / "h.sqlite", "--robot-id", "r1", "--time", "2026-05-01 08:00"])
    assert r.exit_code == 1 and "no time zone" in r.output
    assert not (tmp_path / "ev").exists() and not (tmp_path / "h.sqlite").exists()
