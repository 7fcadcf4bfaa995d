"""``robocal fleet calibrate`` on a local Dask cluster (2 workers) with simulated robots: results equal
the serial ``robocal calibrate`` results (every number to 1e-9 relative); a corrupted entry fails alone with its reason;
a run killed mid-way resumes with only the missing robots; the history is recorded on SQLite and on
a real PostgreSQL server alike, also by concurrent writers on several workers."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import textwrap
import time
import tomllib
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from _close import assert_tree_close

distributed = pytest.importorskip("distributed", reason="dask.distributed not installed (the fleet extra)")

from robocal.cli import main  # noqa: E402
from robocal.io.fleet_file import read_fleet  # noqa: E402
from robocal.store import HistoryStore  # noqa: E402
from robocal.workflows.fleet.calibrate import flag_outliers, run_fleet_calibration  # noqa: E402
from robocal.workflows.fleet.cluster import run_pulled, run_tasks  # noqa: E402
from robocal.workflows.calibration.simulate import simulate_tracker  # noqa: E402

MODELS = ["ur10", "kuka_kr150_r3100", "ur10", "abb_irb140", "ur10", "kuka_kr150_r3100"]


@pytest.fixture(scope="module")
def campaigns(tmp_path_factory):
    """Six simulated tracker campaigns (40 poses, seeded; hidden true parameters differ per robot)."""
    d = tmp_path_factory.mktemp("campaigns")
    for i, model in enumerate(MODELS):
        simulate_tracker(model, d / f"r{i}.csv", n_poses=40, noise_mm=0.02, seed=100 + i)
    return d


def _toml(v) -> str:
    if isinstance(v, dict):
        return "{ " + ", ".join(f"{k} = {_toml(x)}" for k, x in v.items()) + " }"
    return json.dumps(v)  # strings, numbers and lists of them read the same in TOML


def fleet_toml(d: Path, entries, name="fleet.toml", options='[options]\nholdout = 0.25\nseed = 3\n') -> Path:
    text = options + "".join(
        "\n[[robot]]\n" + "".join(f"{k} = {_toml(v)}\n" for k, v in e.items()) for e in entries)
    p = d / name
    p.write_text(text)
    return p


def good_entries(campaigns, n=None):
    return [{"id": f"robot-{i}", "model": MODELS[i], "measurements": str(campaigns / f"r{i}.csv")}
            for i in range(len(MODELS) if n is None else n)]


@pytest.fixture(scope="module")
def client():
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=False, dashboard_address=None,
                                  silence_logs=40) as cluster, distributed.Client(cluster) as c:
        yield c


def _result(path):
    d = json.loads(Path(path).read_text())
    d["metadata"].pop("written")  # the time of writing is the one field that must differ
    return d


def test_fleet_results_equal_serial_calibrate(campaigns, client, tmp_path):
    """Same inputs, same options, same numbers: every float of result.json and of the robot file within
    1e-9 relative (+1e-12 absolute); a worker thread may round differently from the main one (BLAS
    kernels chosen per thread and CPU), a changed option or input changes them by far more."""
    fleet = fleet_toml(tmp_path, good_entries(campaigns, 3))
    r = run_fleet_calibration(fleet, tmp_path / "fleet", client=client, report=False)
    assert r["summary"]["counts"] == {"robots": 3, "ok": 3, "failed": 0, "not_converged": 0, "skipped": 0, "outliers": 0}
    for i in range(3):
        out = tmp_path / "serial" / f"robot-{i}"
        res = CliRunner().invoke(main, ["calibrate", MODELS[i], str(campaigns / f"r{i}.csv"), "--out", str(out),
                                        "--holdout", "0.25", "--seed", "3", "--no-report"])
        assert res.exit_code == 0, res.output
        serial, dask_result = _result(out / "result.json"), _result(tmp_path / "fleet" / f"robot-{i}" / "result.json")
        assert_tree_close(dask_result, serial, rtol=1e-9, atol=1e-12)
        robots = [tomllib.loads((d / "calibrated_robot.toml").read_text()) for d in (out, tmp_path / "fleet" / f"robot-{i}")]
        for robot in robots:
            robot.pop("source", None)  # its time stamp
        assert_tree_close(robots[1], robots[0], rtol=1e-9, atol=1e-12)  # the calibrated robot file
        assert len(json.dumps(robots[0])) > 500
        # the calibration did its job: held-out accuracy from ~mm to the tracker noise level
        row = r["summary"]["robots"][i]
        assert row["holdout_rms_before_mm"] > 0.3 and row["holdout_rms_after_mm"] < 0.06


def test_one_corrupted_entry_fails_alone_with_its_reason(campaigns, client, tmp_path):
    bad_csv = tmp_path / "bad.csv"
    lines = (campaigns / "r0.csv").read_text().splitlines()
    columns = max(i for i, line in enumerate(lines) if line.startswith("#")) + 1  # the column row
    lines[columns + 3] = lines[columns + 3].replace(",", ",oops,", 1)  # pose 3: a joint cell that is no number
    bad_csv.write_text("\n".join(lines) + "\n")
    entries = good_entries(campaigns, 3)
    entries.insert(1, {"id": "corrupt", "model": "ur10", "measurements": str(bad_csv)})
    entries.append({"id": "no-model", "measurements": str(campaigns / "r1.csv")})
    r = run_fleet_calibration(fleet_toml(tmp_path, entries), tmp_path / "out", client=client, report=False)
    rows = {row["id"]: row for row in r["summary"]["robots"]}
    assert [row["status"] for row in r["summary"]["robots"]] == ["ok", "failed", "ok", "ok", "failed"]
    assert "bad.csv, line" in rows["corrupt"]["reason"]
    assert "missing 'model'" in rows["no-model"]["reason"]
    on_disk = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert on_disk["counts"]["failed"] == 2 and on_disk["counts"]["ok"] == 3
    assert not (tmp_path / "out" / "corrupt" / "result.json").exists()
    assert (tmp_path / "out" / "summary.html").read_text().count('class="failed"') == 2


KILLED_RUN = textwrap.dedent("""
    import sys
    from robocal.workflows.fleet.calibrate import run_fleet_calibration
    run_fleet_calibration({fleet!r}, {out!r}, client=None, db={db!r}, report=False,
                          progress=lambda done, n, row: print("DONE", row["id"], flush=True))
""")


def test_a_run_killed_mid_way_resumes_with_only_the_missing_robots(campaigns, client, tmp_path):
    fleet = fleet_toml(tmp_path, good_entries(campaigns))
    out, db = tmp_path / "out", str(tmp_path / "history.sqlite")
    proc = subprocess.Popen([sys.executable, "-c", KILLED_RUN.format(fleet=str(fleet), out=str(out), db=db)],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        for _ in range(2):  # two robots finished, the third under way: kill -9
            line = proc.stdout.readline()
            assert line.startswith("DONE"), line + proc.stderr.read()
        time.sleep(0.05)
        os.kill(proc.pid, signal.SIGKILL)
    finally:
        proc.wait(timeout=60)
    finished = {p.parent.name for p in out.glob("*/fleet_inputs.json")}
    assert 2 <= len(finished) < len(MODELS) and not (out / "summary.json").exists()
    r = run_fleet_calibration(fleet, out, client=client, db=db, report=False)
    rows = r["summary"]["robots"]
    assert all(row["status"] == "ok" for row in rows)
    assert {row["id"] for row in rows if row["skipped"]} == finished
    assert r["summary"]["counts"]["skipped"] == len(finished)
    with HistoryStore.open(db, create=False) as store:  # one calibration per robot: none lost, none twice
        assert sorted(store.robots()) == sorted(f"robot-{i}" for i in range(len(MODELS)))
        assert all(len(store.cycles(rid, status="committed")) == 1 for rid in store.robots())
    again = run_fleet_calibration(fleet, out, client=client, db=db, report=False)
    assert again["summary"]["counts"]["skipped"] == len(MODELS)
    (campaigns / "r5.csv").touch()  # same content: still skipped (a hash of the content, not the time)
    os.utime(campaigns / "r5.csv", (1, 1))
    assert run_fleet_calibration(fleet, out, client=client, db=db, report=False)["summary"]["counts"]["skipped"] == 6


@pytest.fixture(params=["sqlite", "postgresql"])
def history_db(request, tmp_path):
    if request.param == "sqlite":
        return str(tmp_path / "history.sqlite")
    return request.getfixturevalue("fresh_server_db")


def test_every_result_is_recorded_in_the_history(campaigns, client, tmp_path, history_db):
    fleet = fleet_toml(tmp_path, good_entries(campaigns, 4))
    r = run_fleet_calibration(fleet, tmp_path / "out", client=client, db=history_db, report=False)
    with HistoryStore.open(history_db, create=False) as store:
        assert sorted(store.robots()) == [f"robot-{i}" for i in range(4)]
        for row in r["summary"]["robots"]:
            (c,) = store.cycles(row["id"], status="committed")
            assert c.id == row["history_cycle"] and c.kind == "geometric_calibration"
            assert c.meta["input_sha256"] == row["input_sha256"]
            assert c.metrics["holdout_rms_after"].value == row["holdout_rms_after_mm"]
            result = json.loads((tmp_path / "out" / row["result"]).read_text())
            est = {p["name"]: p for p in result["model_parameters"] if p["estimated"]}
            series = store.parameter_history(row["id"])
            assert set(series) == set(est)
            for name, s in series.items():
                assert s.values[0] == est[name]["change"]
            assert c.n_measurements == 40


def _write_cycles(task, db):
    """A worker's task: ``task = (w, k)``: three cycles of robot ``w<w>`` with known content; returns
    the committed cycle ids and the worker's address."""
    from datetime import datetime, timedelta, timezone

    w, k = task
    ids = []
    with HistoryStore.open(db, timeout=60.0) as store:
        for j in range(3):
            i = 3 * k + j
            rng = np.random.default_rng(1000 * w + i)
            with store.cycle(f"w{w}", "measurement", meta={"w": w, "i": i},
                             started_at=datetime(2025, 1, 1, tzinfo=timezone.utc) + timedelta(minutes=i)) as c:
                c.add_measurements(rng.uniform(-1, 1, (20, 6)), rng.uniform(-1500, 1500, (20, 3)))
                c.add_metric("index", float(i), "1")
            ids.append(c.id)
    return ids, distributed.get_worker().address


def test_concurrent_writers_on_several_workers_keep_every_committed_cycle(client, history_db):
    # no schema yet: the workers' first opens race to create it (serialised by the store)
    tasks = [(w, k) for k in range(8) for w in range(4)]
    done = run_tasks(client, _write_cycles, tasks, db=history_db)
    assert len({worker for _, worker in done}) == 2  # both workers wrote
    flat = [i for ids_, _ in done for i in ids_]
    assert len(flat) == len(set(flat)) == 96
    with HistoryStore.open(history_db, create=False) as store:
        assert store.check() == []
        for w in range(4):
            cycles = store.cycles(f"w{w}", status="committed")
            assert sorted(c.meta["i"] for c in cycles) == list(range(24))
            for c in cycles[::5]:
                sc = store.load_cycle(c.id)
                rng = np.random.default_rng(1000 * w + c.meta["i"])
                np.testing.assert_array_equal(sc.joints, rng.uniform(-1, 1, (20, 6)))
                np.testing.assert_array_equal(sc.points_mm, rng.uniform(-1500, 1500, (20, 3)))


def test_outliers_are_flagged_by_the_modified_z_score():
    rows = [{"id": str(i), "status": "ok", "holdout_rms_after_mm": v}
            for i, v in enumerate([0.030, 0.031, 0.029, 0.032, 0.030, 0.031, 0.090])]
    rows.append({"id": "x", "status": "failed", "reason": "r"})
    flag_outliers(rows)
    assert [r["outlier"] for r in rows] == [False] * 6 + [True, False]
    # median 0.031, MAD 0.001: z = 0.6745 * (0.090 - 0.031) / 0.001 = 39.8; the next largest 0.6745
    assert rows[6]["outlier_z"] == pytest.approx(0.6745 * 0.059 / 0.001, abs=0.01)
    assert rows[3]["outlier_z"] == pytest.approx(0.67, abs=0.01)


def test_fleet_file_errors_name_the_entry_and_the_problem(tmp_path, campaigns):
    good = {"id": "a", "model": "ur10", "measurements": str(campaigns / "r0.csv")}
    cases = [
        ({"id": "b c", "model": "ur10", "measurements": str(campaigns / "r0.csv")}, "'id' must be"),
        ({"id": "b", "model": "ur10", "measurements": "nope.csv"}, "measurements file"),
        ({"id": "b", "model": "robots/x.toml", "measurements": str(campaigns / "r0.csv")}, "model file"),
        ({"id": "b", "model": "ur10", "measurements": str(campaigns / "r0.csv"), "tool": [1, 2]}, "three numbers"),
        ({"id": "b", "model": "ur10", "measurements": str(campaigns / "r0.csv"), "options": {"holdot": 0.1}},
         "unknown option 'holdot'"),
        ({"id": "b", "model": "ur10", "measurements": str(campaigns / "r0.csv"), "options": {"seed": 1.5}},
         "must be an integer"),
        ({"id": "a", "model": "ur10", "measurements": str(campaigns / "r0.csv")}, "repeats robot #1"),
    ]
    for entry, message in cases:
        f = read_fleet(fleet_toml(tmp_path, [good, entry], options=""))
        assert [e.id for e in f.entries] == ["a"]
        (p,) = f.problems
        assert p.index == 2 and message in p.reason, p.reason


def _status_history(db, now):
    """Three robots: 'steady' (noise only, calibrated 10 days ago), 'drifter' (a2 grows 2 um/day,
    plus noise), 'old' (steady, but last calibrated 200 days ago)."""
    from datetime import timedelta

    rng = np.random.default_rng(5)
    plan = {"steady": (0.0, [130, 100, 70, 40, 10]), "drifter": (0.002, [130, 100, 70, 40, 10]),
            "old": (0.0, [290, 260, 230, 200])}
    with HistoryStore.open(db) as store:
        for robot, (rate, days_ago) in plan.items():
            for d in days_ago:
                t = now - timedelta(days=d)
                delta = 0.3 + rate * (130 - d) + rng.normal(0, 0.005)
                with store.cycle(robot, "geometric_calibration", started_at=t, finished_at=t) as c:
                    c.add_parameters(["a2", "beta3"], [delta, 1e-5 + rng.normal(0, 1e-6)], units=["mm", "rad"])
                    c.add_metric("holdout_rms_after", 0.03, "mm")


def test_fleet_file_paths_resolve_through_links_and_dot_dot(tmp_path, campaigns):
    """A measurement file named through a linked folder, a linked file or '..' is the real file's
    resolved path (what the output-is-input check and the summary name); a folder is refused."""
    real = tmp_path / "data"
    real.mkdir()
    (real / "r0.csv").write_bytes((campaigns / "r0.csv").read_bytes())
    (tmp_path / "linked-folder").symlink_to(real)
    (tmp_path / "linked-file.csv").symlink_to(real / "r0.csv")
    names = ["linked-folder/r0.csv", "linked-file.csv", "data/../data/r0.csv", str(real / "r0.csv"), "data"]
    fleet = read_fleet(fleet_toml(tmp_path, [{"id": f"r{i}", "model": "ur10", "measurements": n}
                                             for i, n in enumerate(names)]))
    assert [e.measurements for e in fleet.entries] == [(real / "r0.csv").resolve()] * 4
    assert len(fleet.problems) == 1 and "data not found (it is a folder)" in fleet.problems[0].reason


def test_fleet_status_flags_stale_and_drifting_robots(tmp_path, history_db):
    from datetime import datetime, timezone

    from robocal.workflows.fleet.status import drift_trend, fleet_status

    now = datetime(2026, 6, 1, 12, tzinfo=timezone.utc)
    _status_history(history_db, now)
    plots = "://" not in history_db  # the plots once (SQLite): they do not depend on the database
    r = fleet_status(history_db, max_age_days=90, tolerance_mm=0.1, tolerance_deg=0.01, now=now,
                     plot_dir=tmp_path / "plots" if plots else None)
    rows = {row["robot"]: row for row in r["robots"]}
    assert sorted(r["flagged"]) == ["drifter", "old"]
    assert (rows["old"]["stale"], rows["old"]["drifting"]) == (True, False)
    assert (rows["drifter"]["stale"], rows["drifter"]["drifting"]) == (False, True)
    assert not rows["steady"]["stale"] and not rows["steady"]["drifting"]
    a2 = rows["drifter"]["drift"][0]
    assert a2["parameter"] == "a2" and a2["over"]
    # 2 um/day over the 130 days since the first calibration, within the noise of the fitted slope
    assert a2["slope_per_day"] == pytest.approx(0.002, abs=2e-4) and a2["trend_drift"] == pytest.approx(0.26, abs=0.03)
    assert abs(rows["steady"]["drift"][0]["trend_drift"]) < 0.03
    if plots:
        assert Path(rows["drifter"]["plot"]).stat().st_size > 10_000 and "plot" not in rows["steady"]
    # the trend by hand: exact line through two points, extrapolated
    t = np.array(["2026-01-01", "2026-01-11"], dtype="datetime64[us]")
    slope, drift = drift_trend(t, [1.0, 2.0], datetime(2026, 1, 21, tzinfo=timezone.utc))
    assert (slope, drift) == (pytest.approx(0.1), pytest.approx(2.0))
    res = CliRunner().invoke(main, ["fleet", "status", "--db", history_db, "--no-plots"])
    assert res.exit_code == 3, res.output  # against today's date: flagged robots
    assert "3 robots" in res.output and "DRIFTING" in res.output.split("drifter")[1].splitlines()[0]


# -- robocal fleet study -------------------------------------------------------------------------

def test_chunk_size_keeps_task_overhead_under_five_percent():
    from robocal.workflows.fleet.chunks import chunk_size, chunks, overhead_share

    # 5 ms per task, 1 ms per item: k >= 5 * 0.95 / (0.05 * 1) = 95 items, share 5 / (5 + 95) = 5 %
    assert chunk_size(10_000, 1e-3, 5e-3, 2) == 95
    assert overhead_share(5e-3, 1e-3, 95) == pytest.approx(0.05)
    assert chunk_size(100, 1e-3, 5e-3, 2) == 50  # never fewer tasks than workers
    assert chunk_size(10_000, 0.5, 5e-3, 2) == 1  # long items: one per task
    assert chunks(7, 3) == [(0, 3), (3, 6), (6, 7)]


def test_monte_carlo_plan_on_dask_equals_the_serial_loop_and_the_first_order_prediction(client):
    from robocal.docs.figure_producers_pages import monte_carlo_test_plan  # also docs/fleet.md's figure
    from robocal.workflows.fleet.study import monte_carlo_plan

    q_plan = monte_carlo_test_plan()
    kw = dict(samples=14, noise_mm=0.02, check_poses=100, seed=4)
    dask_run = monte_carlo_plan("ur10", q_plan, client=client, **kw)
    serial = monte_carlo_plan("ur10", q_plan, client=None, **kw)
    assert dask_run["rms_after_mm"] == serial["rms_after_mm"] and dask_run["rms_before_mm"] == serial["rms_before_mm"]
    c = dask_run["chunking"]
    assert c["tasks"] * c["chunk_size"] >= 12 and c["workers"] == 2
    after, before = np.array(dask_run["rms_after_mm"]), np.array(dask_run["rms_before_mm"])
    # the hidden 0.5 mm / 0.05 deg errors give mm before; after calibration, the model error the
    # linear theory predicts for 30 D-optimal poses at 0.02 mm noise (within a factor 1.5 at the median)
    assert np.median(before) > 1.0 and np.all(after < 0.1 * before)
    ratio = np.median(after) / dask_run["predicted_model_std_mm"]
    print("MC median after / first-order prediction", ratio)
    assert 1 / 1.5 < ratio < 1.5, ratio


def test_pose_set_selection_is_reproducible_by_plan_poses(client, tmp_path):
    from robocal.workflows.fleet.study import pose_set_selection
    from robocal.workflows.calibration.plan_poses import plan_poses

    kw = dict(sets=5, count=15, candidates=120, seed=10)
    r = pose_set_selection("ur10", client=client, **kw)
    assert r["sets"] == pose_set_selection("ur10", client=None, **kw)["sets"]
    assert [s["seed"] for s in r["sets"]] == list(range(10, 15))
    best = r["best"]
    # ranked by the noise-free workspace accuracy, not by a held-out RMS the noise dominates
    assert r["criterion"] == "workspace_model_std_mm"
    assert best["workspace_model_std_mm"] == min(s["workspace_model_std_mm"] for s in r["sets"])
    assert best["seed"] in r["within_noise"] and 0 < best["relative_spread"] < 1
    p = plan_poses("ur10", tmp_path / "best.csv", count=15, candidates=120, seed=best["seed"])
    assert p["holdout_rms_mm"] == best["holdout_rms_mm"]


def test_workspace_accuracy_spread_matches_monte_carlo():
    """The predicted relative spread of one campaign's workspace error (Gaussian quadratic form)
    against the spread of e^T A e over draws e ~ N(0, C)."""
    from robocal.calib.plan import predicted_workspace_accuracy
    from robocal.robots import load_robot
    from robocal.workflows.fleet.study import workspace_poses
    from robocal.workflows.calibration.plan_poses import plan_cell, plan_in_cell

    model = load_robot("ur10")
    plan = plan_in_cell(model, plan_cell(model, None, None, (0, 0, 100.0)), count=15, candidates=120, seed=3,
                        efficiency=False)
    q_ref = workspace_poses(model, (0, 0, 100.0))
    acc = predicted_workspace_accuracy(model, plan, q_ref, tool=(0, 0, 100.0))
    from robocal.calib.plan import _jacobian_at

    prob = plan["typical"][0]
    J = _jacobian_at(plan["typical"], q_ref)[..., [prob.names.index(n) for n in plan["names"]]]
    e = np.random.default_rng(0).multivariate_normal(np.zeros(len(plan["names"])), plan["covariance"], 4000)
    rms = np.sqrt(np.mean(np.sum(np.einsum("rij,sj->sri", J, e) ** 2, axis=2), axis=1))
    assert np.sqrt(np.mean(rms**2)) == pytest.approx(acc["rms_mm"], rel=0.03)
    assert np.std(rms) / np.mean(rms) == pytest.approx(acc["relative_spread"], rel=0.15)


def test_thermal_screening_per_robot_on_dask_equals_thermal_screen(client, tmp_path):
    from robocal.workflows.fleet.study import thermal_screening
    from robocal.workflows.thermal.commands import screen_run, simulate_thermal_cell

    simulate_thermal_cell(tmp_path / "cell", n_cycles=8)
    (tmp_path / "empty").mkdir()
    runs = [("a", tmp_path / "cell" / "run1"), ("b", tmp_path / "cell" / "run2"), ("bad", tmp_path / "empty")]
    r = thermal_screening(runs, n_keep=6, client=client)
    assert (r["ok"], r["failed"]) == (2, 1)
    a, b, bad = r["robots"]
    for row, run in ((a, runs[0][1]), (b, runs[1][1])):
        alone = screen_run(run, n_keep=6)
        assert row["selected"] == alone["selected"] and row["lambda_percent"] == alone["lambda_percent"]
        assert len(row["selected"]) == 6
    assert bad["status"] == "failed" and "missing sphere_cold.csv" in bad["reason"]


def test_fleet_calibrate_command_on_an_existing_cluster(campaigns, client, tmp_path):
    entries = good_entries(campaigns, 2) + [{"id": "lost", "model": "ur10", "measurements": "nowhere.csv"}]
    fleet = fleet_toml(tmp_path, entries)
    args = ["fleet", "calibrate", str(fleet), "--out", str(tmp_path / "out"), "--no-report",
            "--scheduler", client.scheduler.address]
    res = CliRunner().invoke(main, args)
    assert res.exit_code == 3, res.output  # one robot failed
    assert "3 robots: 2 ok, 1 failed, 0 not converged, 0 unchanged" in res.output
    assert "FAILED lost:" in res.output and "nowhere.csv not found" in res.output
    assert res.output.strip().splitlines()[-1] == "Error: 1 of 3 robots failed (reasons above)"
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert summary["history"] == str(tmp_path / "out" / "history.sqlite")
    again = CliRunner().invoke(main, args)
    assert "3 robots: 2 ok, 1 failed, 0 not converged, 2 unchanged" in again.output
    both = CliRunner().invoke(main, args + ["--workers", "2"])
    assert both.exit_code == 1 and "either --scheduler" in both.output


def _square_or_raise(k):
    if k == 3:
        raise ValueError(f"item {k} is broken")
    return k * k


def test_a_task_that_raises_on_the_cluster_becomes_its_own_failed_row(client):
    seen = []
    out = run_tasks(client, _square_or_raise, range(6), progress=lambda done, n, row: seen.append((done, n)),
                    on_error=lambda item, exc: f"failed {item}: {type(exc).__name__}: {exc}")
    assert out == [0, 1, 4, "failed 3: ValueError: item 3 is broken", 16, 25]
    assert [d for d, _ in seen] == [1, 2, 3, 4, 5, 6] and {n for _, n in seen} == {6}
    with pytest.raises(ValueError, match="item 3 is broken"):  # without on_error the error is raised
        run_tasks(client, _square_or_raise, range(6))


def _slow_square(k):
    import threading

    time.sleep(0.02)
    return [k * k, threading.get_ident()]


def test_workers_pull_the_items_one_by_one_each_exactly_once(client, tmp_path):
    """The default execution of a fleet: one long task per worker thread taking the next unclaimed
    item; results in the order of the items, progress for every item, every worker busy, the claims
    folder removed."""
    seen = []
    out = run_pulled(client, _slow_square, range(30), claims_parent=tmp_path,
                     progress=lambda done, n, result: seen.append((done, n)))
    assert [r[0] for r in out] == [k * k for k in range(30)]
    assert len({r[1] for r in out}) == 2  # both worker threads took items
    assert [d for d, _ in seen] == list(range(1, 31)) and {n for _, n in seen} == {30}
    assert list(tmp_path.iterdir()) == []  # the claims folder is gone
    assert run_pulled(client, _slow_square, [], claims_parent=tmp_path) == []


def test_many_items_travel_to_the_workers_once_scattered(client, tmp_path, monkeypatch):
    from robocal.workflows.fleet import cluster

    monkeypatch.setattr(cluster, "_SCATTER_ABOVE", 0)  # every run scatters its items
    out = run_pulled(client, _slow_square, range(6), claims_parent=tmp_path)
    assert [r[0] for r in out] == [k * k for k in range(6)]


def test_a_pulled_item_that_raises_becomes_its_own_failed_row(client, tmp_path):
    out = run_pulled(client, _square_or_raise, range(6), claims_parent=tmp_path,
                     on_error=lambda item, exc: f"failed {item}: {type(exc).__name__}: {exc}")
    assert out == [0, 1, 4, "failed 3: ValueError: item 3 is broken", 16, 25]
    with pytest.raises(ValueError, match="item 3 is broken"):
        run_pulled(client, _square_or_raise, range(6), claims_parent=tmp_path)
    assert list(tmp_path.iterdir()) == []


class _TaskLost(BaseException):
    """Ends a long task as a lost worker would (Dask marks the task erred; the item loop never sees it)."""


def _square_once_lost(k, marker):
    if k == 4 and not os.path.exists(marker):
        Path(marker).touch()
        raise _TaskLost("the worker went away")
    return k * k


def test_items_of_a_lost_long_task_run_again_one_task_each(client, tmp_path):
    marker = str(tmp_path / "lost-once")
    claims = tmp_path / "claims"
    claims.mkdir()
    seen = []
    out = run_pulled(client, _square_once_lost, range(12), claims_parent=claims, marker=marker,
                     progress=lambda done, n, result: seen.append(done))
    assert os.path.exists(marker)  # the long task was lost once
    assert out == [k * k for k in range(12)]  # its items (item 4 included) ran again
    assert seen == list(range(1, 13))


def _heartbeat_ms(dask_worker):
    return dask_worker.periodic_callbacks["heartbeat"].callback_time


def _idle_checks_ms(dask_scheduler):
    return [dask_scheduler.periodic_callbacks[k].callback_time for k in ("idle-timeout", "no-workers-timeout")]


def test_the_local_cluster_holds_dask_background_work_low(tmp_path):
    """robocal's local cluster: its workers' heartbeats (Dask: every 0.5 s) and its scheduler's idle
    checks (every 0.25 s) are spaced out (fails if a Dask release renames what quiet_local_scheduler
    changes), and the workers still run the fleet's long tasks."""
    from robocal.workflows.fleet.cluster import LOCAL_HEARTBEAT_S, LOCAL_IDLE_CHECK_S, fleet_client

    with fleet_client(workers=2, processes=False) as c:
        deadline = time.monotonic() + 15  # a worker's first heartbeat answer sets its interval
        while min(c.run(_heartbeat_ms).values()) < 1000 * LOCAL_HEARTBEAT_S and time.monotonic() < deadline:
            time.sleep(0.1)
        assert min(c.run(_heartbeat_ms).values()) == pytest.approx(1000 * LOCAL_HEARTBEAT_S)
        assert c.run_on_scheduler(_idle_checks_ms) == [1000 * LOCAL_IDLE_CHECK_S] * 2
        assert [r[0] for r in run_pulled(c, _slow_square, range(8), claims_parent=tmp_path)] == [k * k for k in range(8)]


def test_a_calibration_leaves_every_thread_s_warning_filters_alone(campaigns, tmp_path, monkeypatch):
    """warnings.catch_warnings changes the filters of the whole process: two calibrations side by
    side in the threads of a fleet worker had left an "ignore" filter behind, and every later warning
    of the process went unseen. The default calibration path uses none."""
    import warnings

    from robocal.workflows.calibration.calibrate import run_calibration

    callers = []

    class Spy(warnings.catch_warnings):
        def __init__(self, *args, **kwargs):
            callers.append(sys._getframe(1).f_globals.get("__name__", ""))
            super().__init__(*args, **kwargs)

    monkeypatch.setattr(warnings, "catch_warnings", Spy)
    run_calibration("ur10", campaigns / "r0.csv", tmp_path / "out", report=False, holdout=0.25, seed=3)
    assert [c for c in callers if c.startswith("robocal")] == []


def test_fixed_groups_per_task_give_the_same_rows(campaigns, client, tmp_path):
    fleet = fleet_toml(tmp_path, good_entries(campaigns, 3))
    pulled = run_fleet_calibration(fleet, tmp_path / "a", client=client, report=False)["summary"]["robots"]
    grouped = run_fleet_calibration(fleet, tmp_path / "b", client=client, report=False, per_task=2)["summary"]["robots"]
    assert [r["id"] for r in grouped] == [r["id"] for r in pulled] == ["robot-0", "robot-1", "robot-2"]
    for a, b in zip(pulled, grouped):
        assert a["status"] == b["status"] == "ok"
        assert b["holdout_rms_after_mm"] == pytest.approx(a["holdout_rms_after_mm"], rel=1e-9)
    assert not list((tmp_path / "a").glob(".robocal-claims-*"))


def test_a_robot_whose_fit_does_not_converge_gets_no_robot_file_and_exit_4(campaigns, tmp_path, lm_one_iteration):
    """Issue 25: the convergence policy (every LM solve stopped after one iteration), in this process."""
    fleet = fleet_toml(tmp_path, good_entries(campaigns, 2))
    r = run_fleet_calibration(fleet, tmp_path / "a", client=None, report=False)
    assert r["summary"]["counts"]["not_converged"] == 2 and r["summary"]["counts"]["failed"] == 0
    row = r["summary"]["robots"][0]
    assert row["status"] == "not converged" and "did not converge" in row["reason"]
    assert not (tmp_path / "a" / "robot-0" / "calibrated_robot.toml").exists()
    r = run_fleet_calibration(fleet, tmp_path / "b", client=None, report=False, allow_unconverged=True)
    assert r["summary"]["counts"]["ok"] == 2 and r["summary"]["robots"][0]["converged"] is False
    assert (tmp_path / "b" / "robot-0" / "calibrated_robot.toml").exists()


def test_fleet_calibrate_command_exits_4_when_a_fit_does_not_converge(campaigns, client, tmp_path, lm_one_iteration):
    """Issue 25 through the command line: no failure, but fits that did not converge -> exit 4."""
    fleet = fleet_toml(tmp_path, good_entries(campaigns, 2))
    args = ["fleet", "calibrate", str(fleet), "--out", str(tmp_path / "out"), "--no-report", "--no-history",
            "--scheduler", client.scheduler.address]
    res = CliRunner().invoke(main, args)
    assert res.exit_code == 4, res.output
    assert "2 not converged" in res.output
    assert sum(line.startswith("Warning:") for line in res.output.splitlines()) == 1
    assert not (tmp_path / "out" / "robot-0" / "calibrated_robot.toml").exists()


def test_fleet_calibrate_refuses_an_output_that_is_an_input(campaigns, client, tmp_path):
    # robot-0's measurements kept where its folder's residuals.csv goes: the run would overwrite them
    keep = tmp_path / "out" / "robot-0" / "residuals.csv"
    keep.parent.mkdir(parents=True)
    keep.write_bytes((campaigns / "r0.csv").read_bytes())
    before = keep.read_bytes()
    entries = good_entries(campaigns, 2)
    entries[0]["measurements"] = str(keep)
    fleet = fleet_toml(tmp_path, entries)
    res = CliRunner().invoke(main, ["fleet", "calibrate", str(fleet), "--out", str(tmp_path / "out"), "--no-report",
                                    "--scheduler", client.scheduler.address])
    assert res.exit_code == 1, res.output
    last = res.output.strip().splitlines()[-1]
    assert last.startswith("Error:") and "residuals.csv" in last and "robot 'robot-0' measurements" in last, last
    assert keep.read_bytes() == before and not (tmp_path / "out" / "summary.json").exists()
