"""The history database: crash safety (a writer killed mid-cycle), the cycle API, validation,
queries, a reader beside a writer (WAL), the SQLAlchemy path, the plot and ``robocal history``."""

from __future__ import annotations

import json
import os
import re
import signal
import sqlite3
import subprocess
import sys
import textwrap
import threading
import time
from datetime import datetime, timedelta, timezone

import numpy as np
import pytest
from click.testing import CliRunner

from robocal.cli.history import history_cmd
from robocal.store import (
    CYCLE_KINDS, HistoryBusyError, HistoryError, HistoryInputError, HistoryLookupError, HistoryStore,
    UnknownRobotError, redact_url,
)

T0 = datetime(2024, 5, 1, 6, 0, tzinfo=timezone.utc)

try:
    import sqlalchemy  # noqa: F401

    HAVE_SA = True
except ImportError:
    HAVE_SA = False


# -- helpers -------------------------------------------------------------------------------------

def write_cycle(store, i, robot="kr150-cell3", kind="thermal_compensation", t=None):
    """Cycle number i with a deterministic content: 5 + 3 i measurements, parameters a2 and beta3,
    metrics lambda and residual_rms_after, 4 corrections."""
    rng = np.random.default_rng(i)
    n = 5 + 3 * i
    with store.cycle(robot, kind, started_at=t or T0 + timedelta(hours=i), meta={"i": i, "n": n}) as c:
        c.add_measurements(rng.uniform(-1, 1, (n, 6)), rng.uniform(-1500, 1500, (n, 3)), target="sphere", sensor="stereo")
        c.add_parameters(["a2", "beta3"], [0.01 * i, 2e-6 * i], units=["mm", "rad"], std=[0.001, 1e-7],
                         values=[1350.0 + 0.01 * i, None])
        c.add_metric("lambda", 90.0 + i, "%")
        c.add_metric("residual_rms_after", 0.02 + 0.001 * i, "mm")
        c.add_corrections(np.zeros((4, 6)), np.full((4, 6), 1e-4 * i), program="body_side")
        if t is None:
            c.finished_at = T0 + timedelta(hours=i, seconds=4)
    return c.id


def check_cycle(store, cid):
    """The cycle holds exactly what write_cycle wrote for its number."""
    sc = store.load_cycle(cid)
    i = sc.record.meta["i"]
    rng = np.random.default_rng(i)
    n = 5 + 3 * i
    assert sc.record.status == "committed"
    assert sc.joints.shape == (n, 6) and sc.points_mm.shape == (n, 3)
    np.testing.assert_array_equal(sc.joints, rng.uniform(-1, 1, (n, 6)))
    np.testing.assert_array_equal(sc.points_mm, rng.uniform(-1500, 1500, (n, 3)))
    assert sc.parameters["a2"].delta == pytest.approx(0.01 * i)
    assert sc.record.metrics["lambda"].value == pytest.approx(90.0 + i)
    assert sc.corrections_joints_after.shape == (4, 6)
    return i


def raw_integrity(path):
    con = sqlite3.connect(path)
    try:
        return [r[0] for r in con.execute("PRAGMA integrity_check")]
    finally:
        con.close()


@pytest.fixture(params=["sqlite3", "sqlalchemy", "server"])
def store(request, tmp_path):
    """The same tests on the standard library's sqlite3, on SQLAlchemy over SQLite, and on a real
    PostgreSQL server (``$ROBOCAL_TEST_DB_URL``, else one the suite starts from pgserver: conftest),
    in a fresh database per test."""
    if request.param != "sqlite3" and not HAVE_SA:
        pytest.skip("SQLAlchemy not installed (the 'db' extra)")
    if request.param == "sqlite3":
        s = HistoryStore.open(tmp_path / "h.sqlite")
    elif request.param == "sqlalchemy":
        s = HistoryStore.open(f"sqlite+pysqlite:///{tmp_path / 'h.sqlite'}")
    else:
        s = HistoryStore.open(request.getfixturevalue("fresh_server_db"))
    yield s
    s.close()


# -- crash safety (the acceptance test) ----------------------------------------------------------

CHILD_PRELUDE = textwrap.dedent("""
    import os, sys
    sys.path.insert(0, {tests!r})
    import numpy as np
    from test_history import write_cycle
    from robocal.store import HistoryStore
    store = HistoryStore.open({db!r})
""")

KILLED_MID_CYCLE = CHILD_PRELUDE + textwrap.dedent("""
    for i in range(1, 6):
        write_cycle(store, i)
    store._backend.conn.execute("PRAGMA cache_size = 8")   # spill uncommitted pages into the WAL early
    wal = {db!r} + "-wal"
    size_committed = os.path.getsize(wal)
    rng = np.random.default_rng(99)
    with store.cycle("kr150-cell3", "thermal_compensation", notes="killed") as c:
        c.add_parameters(["a2"], [123.0], units="mm")
        told = False
        while True:                                          # write until killed
            c.add_measurements(rng.uniform(-1, 1, (200, 6)), rng.uniform(-1500, 1500, (200, 3)))
            if not told and os.path.getsize(wal) > size_committed and c.counts["measurements"] >= 2000:
                print("READY", size_committed, c.counts["measurements"], flush=True)
                told = True
""")


def _spawn(code):
    return subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def test_killed_mid_cycle_keeps_every_committed_cycle(tmp_path):
    db = str(tmp_path / "history.sqlite")
    proc = _spawn(KILLED_MID_CYCLE.format(tests=os.path.dirname(__file__), db=db))
    watchdog = threading.Timer(60.0, proc.kill)  # never hang the suite on a stuck child
    watchdog.start()
    try:
        line = proc.stdout.readline()
        if not line.startswith("READY"):
            proc.kill()
            pytest.fail(f"child did not get ready: {line!r} {proc.communicate()[1]}")
        size_committed = int(line.split()[1])
        # while the writer is inside its transaction, another process reads the committed cycles
        with HistoryStore.open(db, create=False) as reader:
            assert [c.status for c in reader.cycles("kr150-cell3")] == ["committed"] * 5
        os.kill(proc.pid, signal.SIGKILL)
        proc.wait(timeout=10)
    finally:
        watchdog.cancel()
        if proc.poll() is None:
            proc.kill()
            proc.wait()
        for f in (proc.stdout, proc.stderr):
            if not f.closed:
                f.close()
    assert proc.returncode == -signal.SIGKILL
    # the killed transaction had uncommitted pages on disk, in the write-ahead log
    assert os.path.getsize(db + "-wal") > size_committed

    assert raw_integrity(db) == ["ok"]
    with HistoryStore.open(db, create=False) as store:
        assert store.check() == []
        cycles = store.cycles("kr150-cell3")
        assert [c.status for c in cycles] == ["committed"] * 5
        assert sorted(check_cycle(store, c.id) for c in cycles) == [1, 2, 3, 4, 5]
        # no row of the killed cycle anywhere
        n_meas = store._read("SELECT COUNT(*) AS n FROM measurements")[0]["n"]
        assert n_meas == sum(5 + 3 * i for i in range(1, 6))
        assert store._read("SELECT COUNT(*) AS n FROM parameters WHERE delta = 123.0")[0]["n"] == 0
        assert np.allclose(store.parameter_history("kr150-cell3", "a2")["a2"].values, 0.01 * np.arange(1, 6))
        # and the database takes new cycles
        cid = write_cycle(store, 6)
        check_cycle(store, cid)


RANDOM_KILL = CHILD_PRELUDE + textwrap.dedent("""
    i = {start}
    while True:
        cid = write_cycle(store, i % 40, t=None)
        print("COMMITTED", cid, flush=True)
        i += 1
""")


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_killed_at_random_moments_leaves_only_whole_cycles(tmp_path, seed):
    """A writer committing cycles back to back, killed at a seeded random moment (often inside a
    commit): every cycle it reported committed is there, whole; nothing else is."""
    db = str(tmp_path / "history.sqlite")
    rng = np.random.default_rng(seed)
    reported = set()
    for run in range(2):
        proc = _spawn(RANDOM_KILL.format(tests=os.path.dirname(__file__), db=db, start=1 + 100 * run))
        watchdog = threading.Timer(60.0, proc.kill)
        watchdog.start()
        try:
            line = proc.stdout.readline()  # at least one commit in this run
            assert line.startswith("COMMITTED"), proc.stderr.read() if proc.poll() is not None else line
            reported.add(int(line.split()[1]))
            time.sleep(float(rng.uniform(0.0, 0.15)))
            os.kill(proc.pid, signal.SIGKILL)
            proc.wait(timeout=10)
            # read through the same buffered stream as readline (communicate() reads the raw pipe
            # and would lose the lines readline had already buffered)
            out = proc.stdout.read()
        finally:
            watchdog.cancel()
            if proc.poll() is None:
                proc.kill()
                proc.wait()
        # only whole lines: the kill may cut the last print short ("COMMITTED 1" of "COMMITTED 12")
        reported |= {int(ln.split()[1]) for ln in out.splitlines(keepends=True)
                     if ln.startswith("COMMITTED") and ln.endswith("\n") and len(ln.split()) == 2}
    assert raw_integrity(db) == ["ok"]
    with HistoryStore.open(db, create=False) as store:
        assert store.check() == []
        cycles = store.cycles("kr150-cell3")
        ids = {c.id for c in cycles}
        assert reported <= ids  # a cycle killed after its commit but before the print may be there too
        assert len(ids - reported) <= 2
        for c in cycles:
            assert c.status == "committed"
            assert c.n_measurements == c.meta["n"] and c.n_parameters == 2 and c.n_corrections == 4
            check_cycle(store, c.id)
        total = store._read("SELECT COUNT(*) AS n FROM measurements")[0]["n"]
        assert total == sum(c.meta["n"] for c in cycles)


# -- the cycle API -------------------------------------------------------------------------------

def test_round_trip_of_one_cycle(store):
    q = np.array([[0.1, -0.2, 0.3, 0.0, 1.0, -3.0], [0.2, -0.1, 0.2, 0.1, 0.9, -2.9]])
    p = np.array([[1500.0, 20.0, 800.5], [1490.25, -10.0, 805.0]])
    with store.cycle("cell 3/KR150#1", "geometric_calibration", started_at="2024-05-01T06:00:00Z",
                     finished_at="2024-05-01T08:20:00+02:00", notes="after install",
                     meta={"software": "robocal 0.1", "poses": 2}, robot_model="kuka_kr150_r3100") as c:
        assert c.add_measurements(q, p, pose_index=[3, 7], target=["SMR1", "SMR2"], sensor="tracker") == 2
        c.add_parameter("a2", 0.25, "mm", value=1350.25, std=0.01)
        c.add_parameters(["beta2", "theta3"], [1e-4, -2e-4], units="rad")
        c.add_metrics({"residual_rms_before": (1.2, "mm"), "residual_rms_after": (0.03, "mm"),
                       "condition_number": (85.0, "")})
        c.add_corrections(q, q + 1e-3, program="weld_7", point_names=["P1", "P2"])
    assert c.status == "committed"
    (rec,) = store.cycles("cell 3/KR150#1")
    assert rec.kind == "geometric_calibration" and rec.status == "committed"
    assert rec.started_at == T0 and rec.finished_at == datetime(2024, 5, 1, 6, 20, tzinfo=timezone.utc)  # in UTC
    assert rec.meta == {"software": "robocal 0.1", "poses": 2} and rec.notes == "after install"
    assert rec.metrics["condition_number"].unit == "1"
    assert (rec.n_measurements, rec.n_parameters, rec.n_corrections) == (2, 3, 2)
    sc = store.load_cycle(rec.id)
    np.testing.assert_array_equal(sc.joints, q)  # JSON keeps every bit of a float
    np.testing.assert_array_equal(sc.points_mm, p)
    assert list(sc.pose_index) == [3, 7] and sc.targets == ("SMR1", "SMR2") and sc.sensors == ("tracker",) * 2
    assert sc.joint_units == ("rad",) * 6
    assert sc.parameters["a2"] == (0.25, 1350.25, 0.01, "mm")
    assert sc.parameters["beta2"].value is None and sc.parameters["beta2"].unit == "rad"
    np.testing.assert_array_equal(sc.corrections_joints_after, q + 1e-3)
    assert sc.correction_programs == ("weld_7",) * 2 and sc.correction_point_names == ("P1", "P2")


def test_finished_before_started_is_refused(store):
    with pytest.raises(HistoryInputError, match="before started_at"):
        with store.cycle("r1", "measurement", started_at=T0, finished_at=T0 - timedelta(seconds=1)):
            pass
    assert [c.status for c in store.cycles("r1")] == ["failed"]


def test_exception_rolls_back_the_whole_cycle_and_records_the_failure(store):
    write_cycle(store, 1)
    with pytest.raises(RuntimeError, match="tracker lost the SMR"):
        with store.cycle("kr150-cell3", "geometric_calibration", notes="night shift") as c:
            c.add_measurements(np.zeros((50, 6)), np.full((50, 3), 900.0))
            c.add_parameter("a2", 5.0, "mm")
            raise RuntimeError("tracker lost the SMR")
    assert c.status == "failed"
    cycles = store.cycles("kr150-cell3")
    assert [x.status for x in cycles] == ["committed", "failed"]
    failed = cycles[1]
    assert failed.id == c.id and "night shift" in failed.notes and "RuntimeError: tracker lost the SMR" in failed.notes
    assert (failed.n_measurements, failed.n_parameters) == (0, 0)
    # failed cycles are not part of the drift
    assert list(store.parameter_history("kr150-cell3", "a2")["a2"].values) == [pytest.approx(0.01)]
    assert store.cycles("kr150-cell3", status="failed") == [failed]
    with pytest.raises(HistoryError, match="closed"):
        c.add_metric("lambda", 100.0, "%")


def test_failure_not_recorded_when_asked(store):
    with pytest.raises(ValueError):
        with store.cycle("r1", "measurement", record_failure=False) as c:
            c.add_metric("lambda", 50.0, "%")
            raise ValueError("stop")
    assert store.robots() == []  # not even the robot row stayed


def test_validation_error_inside_cycle_writes_nothing_of_that_call(store):
    with store.cycle("r1", "measurement") as c:
        c.add_parameter("a2", 0.1, "mm")
        with pytest.raises(HistoryInputError, match="beta2"):
            c.add_parameters(["a3", "beta2"], [0.1, 0.2], units=["mm", "deg"])
        c.add_parameter("a3", 0.3, "mm")  # a3 was not written by the failed call
    assert set(store.load_cycle(c.id).parameters) == {"a2", "a3"}


def test_one_open_cycle_per_store(store):
    with store.cycle("r1", "measurement") as c:
        with pytest.raises(HistoryError, match=f"cycle {c.id} is still open"):
            with store.cycle("r1", "measurement"):
                pass
    assert [x.status for x in store.cycles("r1")] == ["committed"]


def test_robot_model_is_checked(store):
    with store.cycle("r1", "measurement", robot_model="ur10"):
        pass
    with pytest.raises(HistoryInputError, match="recorded as model 'ur10', not 'ur5'"):
        with store.cycle("r1", "measurement", robot_model="ur5"):
            pass


@pytest.mark.parametrize("call, message", [
    (lambda s: s.cycle("", "measurement"), "robot id is empty"),
    (lambda s: s.cycle(" r1", "measurement"), "not valid"),
    (lambda s: s.cycle(42, "measurement"), "robot id must be a string"),
    (lambda s: s.cycle("r1", "calibration"), "cycle kind 'calibration' is not known; valid: geometric_calibration"),
    (lambda s: s.cycle("r1", "measurement", started_at=datetime(2024, 1, 1)), "has no time zone"),
    (lambda s: s.cycle("r1", "measurement", started_at="yesterday"), "not an ISO 8601 time"),
    (lambda s: s.cycle("r1", "measurement", meta={"x": float("nan")}), "meta must be JSON"),
    (lambda s: s.cycle("r1", "measurement", meta=[1]), "meta must be a dict"),
])
def test_cycle_arguments_are_validated(store, call, message):
    with pytest.raises(HistoryInputError, match=message):
        with call(store):
            pass
    assert store.robots() == []  # nothing was started


@pytest.mark.parametrize("add, message", [
    (lambda c: c.add_measurements(np.zeros((3, 6)), [[1, 2, 3], [4, np.nan, 6], [7, 8, 9]]),
     r"points_mm: row 1 column y is nan"),
    (lambda c: c.add_measurements(np.zeros((3, 6)), np.zeros((2, 3)) + 500), "3 joint rows but 2 points"),
    (lambda c: c.add_measurements(np.zeros((3, 6)), np.zeros((3, 2))), r"shape \(3, 2\), expected \(N, 3\)"),
    (lambda c: c.add_measurements(np.full((3, 6), 90.0), np.zeros((3, 3)) + 500), "beyond 4π; degrees"),
    (lambda c: c.add_measurements(np.zeros((1, 6)), np.zeros((1, 3)) + 500, joint_units=["deg"] * 6), "use 'rad'"),
    (lambda c: c.add_measurements(np.zeros((2, 6)), np.zeros((2, 3)) + 500, pose_index=[0.5, 1]), "pose_index"),
    (lambda c: c.add_parameter("a2", 0.001, "m"), "multiply by 1000 and store in 'mm'"),
    (lambda c: c.add_parameter("beta2", 0.1, "deg"), "convert to radians"),
    (lambda c: c.add_parameter("a2", 0.1, "furlong"), "unknown unit 'furlong'; valid: mm, rad"),
    (lambda c: c.add_parameter("a 2", 0.1, "mm"), "parameter name 'a 2' is not valid"),
    (lambda c: c.add_parameter("a2", float("inf"), "mm"), "row 0 is inf"),
    (lambda c: c.add_parameter("a2", 0.1, "mm", std=-1.0), "std is negative"),
    (lambda c: c.add_parameters(["a2", "a2"], [1, 2], units="mm"), "'a2' was already added"),
    (lambda c: c.add_parameters(["a2", "a3"], [1], units="mm"), "2 names but 1 deltas"),
    (lambda c: c.add_parameters(["a2"], [1], units=None), "units are required"),
    (lambda c: c.add_metric("lambda", True, "%"), "must be a finite number, got bool"),
    (lambda c: c.add_metric("lambda", "0.9", "%"), "must be a finite number, got str"),
    (lambda c: c.add_metric("cycle_time", 3, "min"), "multiply by 60"),
    (lambda c: c.add_metric("lambda", 0.95, "1"), "multiply a fraction by 100"),
    (lambda c: c.add_metrics({"lambda": 0.9}), r"give \(value, unit\)"),
    (lambda c: c.add_corrections(np.zeros((2, 6)), np.zeros((3, 6))), "joints_before has shape"),
    (lambda c: c.add_corrections(np.zeros((2, 6)), np.zeros((2, 6)), point_index=[1, 1]), "appears twice"),
])
def test_rows_are_validated(store, add, message):
    with store.cycle("r1", "measurement") as c:
        with pytest.raises(HistoryInputError, match=message):
            add(c)
    assert store.load_cycle(c.id).record.n_measurements == 0


def test_joint_count_must_not_change_within_a_cycle(store):
    with store.cycle("r1", "measurement") as c:
        c.add_measurements(np.zeros((1, 6)), [[500.0, 0, 0]])
        with pytest.raises(HistoryInputError, match="has 7 joints, earlier rows of this cycle had 6"):
            c.add_corrections(np.zeros((1, 7)), np.zeros((1, 7)))


def test_points_that_look_like_metres_warn(store):
    with store.cycle("r1", "measurement") as c:
        with pytest.warns(UserWarning, match="are these metres"):
            c.add_measurements(np.zeros((3, 6)), [[1.2, 0.1, 0.8], [1.1, 0.2, 0.9], [1.0, 0.3, 0.7]])


def test_prismatic_joints_in_mm(store):
    with store.cycle("gantry-1", "measurement") as c:
        c.add_measurements([[1500.0, 0.5]], [[1500.0, 20.0, 100.0]], joint_units=["mm", "rad"])
    assert store.load_cycle(c.id).joint_units == ("mm", "rad")


# -- queries -------------------------------------------------------------------------------------

def test_queries_order_filter_and_series(store):
    # written out of time order; kinds mixed; a second robot
    for i in (3, 1, 2, 5, 4):
        write_cycle(store, i, kind="geometric_calibration" if i == 1 else "thermal_compensation")
    write_cycle(store, 7, robot="ur10-lab")
    cycles = store.cycles("kr150-cell3")
    assert [c.meta["i"] for c in cycles] == [1, 2, 3, 4, 5]
    assert [c.meta["i"] for c in store.cycles("kr150-cell3", kind="geometric_calibration")] == [1]
    late = store.cycles("kr150-cell3", kind=["thermal_compensation"], since=T0 + timedelta(hours=4))
    assert [c.meta["i"] for c in late] == [4, 5]
    assert [c.meta["i"] for c in store.cycles("kr150-cell3", until="2024-05-01T08:00:00Z")] == [1, 2]
    assert store.robots() == ["kr150-cell3", "ur10-lab"]
    assert store.parameter_names("kr150-cell3") == ["a2", "beta3"]
    assert store.metric_names("kr150-cell3") == ["lambda", "residual_rms_after"]

    h = store.parameter_history("kr150-cell3", ["a2", "beta3"])
    a2 = h["a2"]
    assert a2.unit == "mm" and len(a2) == 5
    np.testing.assert_allclose(a2.values, 0.01 * np.arange(1, 6))
    np.testing.assert_allclose(a2.std, 0.001)
    assert a2.times[0] == np.datetime64("2024-05-01T07:00:00", "us")
    assert np.all(np.diff(a2.times) == np.timedelta64(3600, "s"))
    assert a2.kinds[0] == "geometric_calibration"
    assert h["beta3"].unit == "rad"
    vals = store.parameter_history("kr150-cell3", "a2", field="value")["a2"].values
    np.testing.assert_allclose(vals, 1350.0 + 0.01 * np.arange(1, 6))
    assert np.all(np.isnan(store.parameter_history("kr150-cell3", "beta3", field="value")["beta3"].values))
    only_thermal = store.parameter_history("kr150-cell3", "a2", kind="thermal_compensation")["a2"]
    assert len(only_thermal) == 4

    lam = store.metric_history("kr150-cell3", "lambda")
    np.testing.assert_allclose(lam.values, 90.0 + np.arange(1, 6))
    assert lam.unit == "%" and np.all(np.isnan(lam.std))
    assert list(lam.cycle_ids) == [c.id for c in cycles]
    assert len(store.metric_history("ur10-lab", "lambda")) == 1


def test_unknown_names_are_clear_errors(store):
    write_cycle(store, 1)
    with pytest.raises(UnknownRobotError, match="robot 'kr15' is not in the history database .*known robots: kr150-cell3") as e:
        store.cycles("kr15")
    assert e.value.known == ["kr150-cell3"]
    with pytest.raises(HistoryLookupError, match="no parameter 'a9' stored for robot 'kr150-cell3'; stored: a2, beta3"):
        store.parameter_history("kr150-cell3", ["a2", "a9"])
    with pytest.raises(HistoryLookupError, match="no metric 'rms'.*stored: lambda, residual_rms_after"):
        store.metric_history("kr150-cell3", "rms")
    with pytest.raises(HistoryLookupError, match="no cycle 999"):
        store.load_cycle(999)
    with pytest.raises(HistoryInputError, match="field must be"):
        store.parameter_history("kr150-cell3", "a2", field="std")


def test_empty_database_says_so(store):
    with pytest.raises(UnknownRobotError, match="the database has no robots yet"):
        store.cycles("r1")


# -- a reader beside a writer (WAL) --------------------------------------------------------------

def test_reader_sees_only_committed_cycles_while_a_writer_is_open(tmp_path):
    db = tmp_path / "h.sqlite"
    writer = HistoryStore.open(db)
    write_cycle(writer, 1)
    reader = HistoryStore.open(db, create=False, timeout=0.2)  # a blocked read would raise, not wait
    other_writer = HistoryStore.open(db, timeout=0.2)
    try:
        with writer.cycle("kr150-cell3", "thermal_compensation") as c:
            c.add_measurements(np.zeros((500, 6)), np.full((500, 3), 700.0))
            c.add_parameter("a2", 9.0, "mm")
            cycles = reader.cycles("kr150-cell3")  # not blocked by the open write transaction
            assert [x.meta["i"] for x in cycles] == [1]
            assert list(reader.parameter_history("kr150-cell3", "a2")["a2"].values) == [pytest.approx(0.01)]
            with pytest.raises(HistoryBusyError, match="being written by another process"):
                with other_writer.cycle("kr150-cell3", "measurement"):
                    pass
        assert [x.status for x in reader.cycles("kr150-cell3")] == ["committed", "committed"]
        assert reader.load_cycle(c.id).record.n_measurements == 500
        write_cycle(other_writer, 2)  # the lock is free again
        assert len(reader.cycles("kr150-cell3")) == 3
    finally:
        writer.close()
        reader.close()
        other_writer.close()


# -- opening -------------------------------------------------------------------------------------

def test_sqlite_file_settings_and_schema(tmp_path):
    db = tmp_path / "h.sqlite"
    with HistoryStore.open(db) as s:
        assert s.schema_version == 3
        assert s._backend.conn.execute("PRAGMA journal_mode").fetchone()[0] == "wal"
        assert s._backend.conn.execute("PRAGMA foreign_keys").fetchone()[0] == 1
    con = sqlite3.connect(db)
    tables = {r[0] for r in con.execute("SELECT name FROM sqlite_master WHERE type = 'table'")}
    assert tables == {"schema_version", "robots", "cycles", "measurements", "parameters", "metrics", "corrections",
                      "iso9283_figures", "verifications"}
    with pytest.raises(sqlite3.IntegrityError):  # the schema itself refuses unknown kinds
        con.execute("INSERT INTO robots (name, created_at) VALUES ('x', '2024')")
        con.execute("INSERT INTO cycles (robot_id, kind, status, started_at) VALUES (1, 'party', 'committed', '2024')")
    con.close()
    with HistoryStore.open(db) as s:  # reopening does not migrate twice
        assert s._read("SELECT COUNT(*) AS n FROM schema_version")[0]["n"] == 3



def test_first_open_waits_for_another_first_open_instead_of_failing(tmp_path):
    # Switching a fresh file to WAL upgrades a read lock to a write lock; while another connection
    # holds the write lock SQLite returns SQLITE_BUSY at once, without the busy handler (it was the
    # fleet test's intermittent "database is locked"). The store must wait, up to its timeout.
    db = tmp_path / "h.sqlite"
    other = sqlite3.connect(db, isolation_level=None, check_same_thread=False)  # another first open,
    other.execute("BEGIN IMMEDIATE")  # mid-way: rollback journal, holding the write lock
    release = threading.Timer(0.3, lambda: other.execute("COMMIT"))
    release.start()
    t0 = time.monotonic()
    try:
        with HistoryStore.open(db, timeout=10.0) as s:
            waited = time.monotonic() - t0
            assert s._backend.journal_mode == "wal"
            write_cycle(s, 1)
            assert len(s.cycles("kr150-cell3")) == 1
    finally:
        release.join()
        other.close()
    assert 0.25 < waited < 5.0
    # a lock held longer than the timeout is reported as busy, after the timeout, not at once
    db2 = tmp_path / "h2.sqlite"
    other = sqlite3.connect(db2, isolation_level=None)
    other.execute("BEGIN IMMEDIATE")
    t0 = time.monotonic()
    try:
        with pytest.raises(HistoryBusyError, match="stayed locked by another connection for 0.3 s"):
            HistoryStore.open(db2, timeout=0.3)
    finally:
        other.close()
    assert 0.29 < time.monotonic() - t0 < 3.0


@pytest.mark.parametrize("driver", ["sqlite3", "sqlalchemy"])
def test_many_first_opens_of_a_fresh_file_at_once(tmp_path, driver):
    # the fleet race in small: threads open one fresh file together, each writes cycles
    # (before the fix about one round in seven failed with "database is locked")
    problems = []

    def worker(db, w, barrier):
        barrier.wait()
        for i in range(2):
            try:
                with HistoryStore.open(db, timeout=30.0) as s:
                    with s.cycle(f"w{w}", "measurement", meta={"i": i}) as c:
                        c.add_metric("index", float(i), "1")
            except Exception as exc:  # noqa: BLE001 - collected and asserted below
                problems.append(f"{type(exc).__name__}: {exc}")

    if driver == "sqlalchemy":
        pytest.importorskip("sqlalchemy", reason="the 'db' extra (SQLAlchemy) is not installed")
    for r in range(30 if driver == "sqlite3" else 10):
        db = tmp_path / f"h{r}.sqlite"
        target = db if driver == "sqlite3" else f"sqlite+pysqlite:///{db}"
        barrier = threading.Barrier(3)
        threads = [threading.Thread(target=worker, args=(target, w, barrier)) for w in range(3)]
        for t in threads:
            t.start()
        for t in threads:
            t.join()
        if not problems:
            with HistoryStore.open(db, create=False) as s:
                assert sum(len(s.cycles(f"w{w}")) for w in range(3)) == 6
    assert problems == []


@pytest.mark.parametrize("form", ["path", "relative_url", "absolute_url"])
def test_sqlite_url_forms(tmp_path, monkeypatch, form):
    monkeypatch.chdir(tmp_path)
    target = {"path": "h.sqlite", "relative_url": "sqlite:///h.sqlite",
              "absolute_url": f"sqlite:///{tmp_path / 'h.sqlite'}"}[form]
    with HistoryStore.open(target) as s:
        write_cycle(s, 1)
    with HistoryStore.open(tmp_path / "h.sqlite", create=False) as s:
        assert len(s.cycles("kr150-cell3")) == 1


def test_in_memory_store():
    with HistoryStore.open("sqlite:///:memory:") as s:
        write_cycle(s, 1)
        assert len(s.cycles("kr150-cell3")) == 1


def test_opening_errors(tmp_path):
    with pytest.raises(HistoryError, match="no history database at"):
        HistoryStore.open(tmp_path / "missing.sqlite", create=False)
    with pytest.raises(HistoryError, match="folder .* does not exist"):
        HistoryStore.open(tmp_path / "no" / "h.sqlite")
    with pytest.raises(HistoryError, match="is a folder"):
        HistoryStore.open(tmp_path)
    junk = tmp_path / "junk.sqlite"
    junk.write_bytes(b"this is not a database at all, just some text" * 100)
    with pytest.raises(HistoryError, match="is not an SQLite database"):
        HistoryStore.open(junk)
    assert junk.read_bytes().startswith(b"this is not")  # untouched
    other = tmp_path / "other.sqlite"
    con = sqlite3.connect(other)
    con.execute("CREATE TABLE invoices (id INTEGER)")
    con.commit()
    con.close()
    with pytest.raises(HistoryError, match="not a robocal history database .*invoices"):
        HistoryStore.open(other)
    newer = tmp_path / "newer.sqlite"
    HistoryStore.open(newer).close()
    con = sqlite3.connect(newer)
    con.execute("INSERT INTO schema_version VALUES (99, '2030-01-01T00:00:00+00:00', 'future')")
    con.commit()
    con.close()
    with pytest.raises(HistoryError, match="schema version 99, newer than this robocal understands"):
        HistoryStore.open(newer)
    with pytest.raises(HistoryError, match="options in sqlite URLs"):
        HistoryStore.open("sqlite:///h.sqlite?mode=ro")


def test_server_url_without_sqlalchemy_names_the_extra(monkeypatch):
    monkeypatch.setitem(sys.modules, "sqlalchemy", None)  # import sqlalchemy now raises ImportError
    with pytest.raises(HistoryError) as e:
        HistoryStore.open("postgresql://robocal:s3cret@db.plant.local/history")
    msg = str(e.value)
    assert "SQLAlchemy" in msg and "'db' extra" in msg and "robocal[db]" in msg
    assert "s3cret" not in msg and "robocal:***@db.plant.local" in msg


@pytest.mark.skipif(not HAVE_SA, reason="SQLAlchemy not installed (the 'db' extra)")
def test_server_url_with_unknown_kind_or_missing_driver():
    with pytest.raises(HistoryError, match="knows no database kind 'nosuchdb'"):
        HistoryStore.open("nosuchdb://host/x")


@pytest.mark.skipif(not HAVE_SA, reason="SQLAlchemy not installed (the 'db' extra)")
def test_sqlalchemy_and_sqlite3_read_each_others_files(tmp_path):
    db = tmp_path / "h.sqlite"
    with HistoryStore.open(f"sqlite+pysqlite:///{db}") as s:
        write_cycle(s, 1)
    with HistoryStore.open(db) as s:
        check_cycle(s, s.cycles("kr150-cell3")[0].id)
        write_cycle(s, 2)
    with HistoryStore.open(f"sqlite+pysqlite:///{db}") as s:
        assert [check_cycle(s, c.id) for c in s.cycles("kr150-cell3")] == [1, 2]


def test_redact_url():
    assert redact_url("postgresql+psycopg://u:pw@h:5432/db") == "postgresql+psycopg://u:***@h:5432/db"
    assert redact_url("postgresql://h/db") == "postgresql://h/db"


def test_kinds_are_the_documented_four():
    assert CYCLE_KINDS == ("geometric_calibration", "thermal_compensation", "tool_recalibration", "measurement")


# -- plot and command line -----------------------------------------------------------------------

@pytest.fixture
def history_db(tmp_path):
    db = tmp_path / "history.sqlite"
    with HistoryStore.open(db) as s:
        for i in range(1, 7):
            write_cycle(s, i, kind="geometric_calibration" if i == 1 else "thermal_compensation")
        with pytest.raises(RuntimeError):
            with s.cycle("kr150-cell3", "tool_recalibration", started_at=T0 + timedelta(hours=7)):
                raise RuntimeError("collision")
        write_cycle(s, 1, robot="ur10-lab")
    return db


def test_plot_history_writes_png(history_db, tmp_path):
    from robocal.report.history_plot import plot_history

    with HistoryStore.open(history_db) as s:
        params = s.parameter_history("kr150-cell3")
        metrics = {m: s.metric_history("kr150-cell3", m) for m in s.metric_names("kr150-cell3")}
        events = [(c.started_at, c.kind) for c in s.cycles("kr150-cell3")]
    out = plot_history(params, metrics, tmp_path / "drift.png", "kr150-cell3", events=events)
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    with pytest.raises(ValueError, match="nothing to plot"):
        plot_history({}, {}, tmp_path / "empty.png", "x")
    assert not (tmp_path / "empty.png").exists()


def run_history(*args):
    return CliRunner().invoke(history_cmd, [str(a) for a in args])


def test_cli_history_table(history_db):
    r = run_history("kr150-cell3", "--db", history_db)
    assert r.exit_code == 0, r.output
    out = r.output
    assert "7 cycles (6 committed, 1 failed)" in out
    assert "2024-05-01 07:00:00  geometric_calibration" in out
    assert "tool_recalibration" in out and "failed" in out
    assert "residual_rms_after [mm]" in out and "lambda [%]" in out
    line = next(ln for ln in out.splitlines() if ln.strip().startswith("a2 "))
    assert line.split()[1:] == ["mm", "6", "+0.01", "+0.06", "+0.05", "+0.01", "+0.06"]
    # one unit per quantity (issue 25): stored in rad, shown in degrees (the plot and the JSON too)
    line = next(ln for ln in out.splitlines() if ln.strip().startswith("beta3 "))
    assert line.split()[1] == "deg" and float(line.split()[4]) == pytest.approx(float(np.degrees(12e-6)), rel=1e-3)


def test_cli_history_json_and_plot(history_db, tmp_path):
    png = tmp_path / "plots" / "kr150-cell3_drift.png"  # --plots DIR: <robot>_drift.png, as fleet status
    r = run_history("kr150-cell3", "--db", f"sqlite:///{history_db}", "--params", "a2", "--plots", tmp_path / "plots",
                    "--json")
    assert r.exit_code == 0, r.output
    out = json.loads(r.output)
    assert list(out["parameters"]) == ["a2"]
    assert out["parameters"]["a2"]["values"] == pytest.approx([0.01 * i for i in range(1, 7)])
    assert out["parameters"]["a2"]["times"][0] == "2024-05-01T07:00:00.000000Z"
    assert [c["status"] for c in out["cycles"]].count("failed") == 1
    assert out["metrics"]["lambda"]["unit"] == "%"
    assert png.read_bytes()[:4] == b"\x89PNG" and out["plot"] == str(png)


def test_cli_history_filters(history_db):
    r = run_history("kr150-cell3", "--db", history_db, "--kind", "thermal_compensation", "--since", "2024-05-01T10:00",
                    "--json")
    assert r.exit_code == 0, r.output
    out = json.loads(r.output)
    assert [c["started_at"][:16] for c in out["cycles"]] == ["2024-05-01T10:00", "2024-05-01T11:00", "2024-05-01T12:00"]
    assert len(out["parameters"]["a2"]["values"]) == 3


@pytest.mark.parametrize("args, message", [
    (("kr15",), "robot 'kr15' is not in the history database .*; known robots: kr150-cell3, ur10-lab"),
    (("kr150-cell3", "--params", "a2,a9"), "no parameter 'a9' stored for robot 'kr150-cell3'; stored: a2, beta3"),
    (("kr150-cell3", "--params", " , "), "--params: give one or more parameter names"),
    (("kr150-cell3", "--since", "last week"), "--since 'last week' is not an ISO 8601 time"),
])
def test_cli_history_errors_are_one_line(history_db, args, message):
    r = run_history(*args, "--db", history_db)
    assert r.exit_code == 1
    lines = r.output.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("Error: ")
    assert re.search(message, lines[0]), lines[0]


def test_cli_history_missing_database(tmp_path):
    r = run_history("r1", "--db", tmp_path / "nope.sqlite")
    assert r.exit_code == 1 and "no history database at" in r.output
    assert not (tmp_path / "nope.sqlite").exists()  # the command never creates one


def test_cli_history_default_database_from_environment(history_db, monkeypatch):
    monkeypatch.setenv("ROBOCAL_HISTORY_DB", str(history_db))
    r = run_history("ur10-lab")
    assert r.exit_code == 0, r.output
    assert "1 cycles" in r.output


def test_version_1_database_is_migrated_lambda_to_percent_and_demo_truth_errors_renamed(tmp_path):
    """Issue 25: a version-1 history (lambda as a fraction, the demo's truth errors stored as residuals)
    opened by this robocal: lambda x 100 in %, the demo's two metrics renamed, others untouched."""
    from robocal.store import _schema

    db = tmp_path / "v1.sqlite"
    v2 = _schema.MIGRATIONS
    try:
        _schema.MIGRATIONS, _schema.SCHEMA_VERSION = v2[:1], 1
        with HistoryStore.open(db) as s:
            with s.cycle("kr", "geometric_calibration", notes="robocal demo (simulated time): campaign") as c:
                c.add_metric("residual_rms_before", 1.5, "mm")
                c.add_metric("residual_rms_after", 0.05, "mm")
            with s.cycle("kr", "geometric_calibration", notes="a real calibration") as c:
                c.add_metric("residual_rms_after", 0.02, "mm")
            with s.cycle("kr", "thermal_compensation") as c:
                c._metrics.clear()
                c._write(c._tx.insert, "metrics", {"cycle_id": c.id, "name": "lambda", "value": 0.9, "unit": "1"})
    finally:
        _schema.MIGRATIONS, _schema.SCHEMA_VERSION = v2, v2[-1].version
    with HistoryStore.open(db) as s:
        assert s.schema_version == _schema.SCHEMA_VERSION
        demo, real, thermal = s.cycles("kr")
        assert set(demo.metrics) == {"workspace_error_nominal_rms", "workspace_error_calibrated_rms"}
        assert demo.metrics["workspace_error_nominal_rms"].value == 1.5
        assert set(real.metrics) == {"residual_rms_after"}
        assert thermal.metrics["lambda"].value == pytest.approx(90.0) and thermal.metrics["lambda"].unit == "%"


def test_cli_history_old_plot_file_option_works_with_a_warning(history_db, tmp_path):
    """`--plot FILE` (before `--plots DIR`, issue 26) still writes the file it names, with one warning."""
    from robocal.cli import main

    png = tmp_path / "old.png"
    r = CliRunner().invoke(main, ["history", "kr150-cell3", "--db", str(history_db), "--plot", str(png)])
    assert r.exit_code == 0, r.output
    assert png.read_bytes()[:4] == b"\x89PNG"
    assert [ln for ln in r.stderr.splitlines() if ln.startswith("Warning:")] == [
        "Warning: --plot FILE is deprecated, use --plots DIR"]
    r = CliRunner().invoke(main, ["history", "kr150-cell3", "--db", str(history_db), "--plot", str(png), "--plots",
                                  str(tmp_path)])
    assert r.exit_code == 2 and "not both" in r.output
    assert "--plot " not in CliRunner().invoke(main, ["history", "--help"]).output  # hidden
