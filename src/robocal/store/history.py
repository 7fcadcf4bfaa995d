"""The history of calibration and maintenance cycles in a real database.

One cycle (a geometric calibration, a thermal compensation, a tool recalibration, a plain
measurement) is one database transaction::

    store = HistoryStore.open("history.sqlite")           # or "sqlite:///path", "postgresql://..."
    with store.cycle("cell3-kr150", "thermal_compensation") as c:
        c.add_measurements(joints_rad, sphere_mm, target="sphere", sensor="stereo")
        c.add_parameters(["a2", "beta2"], [0.031, 2.1e-5], units=["mm", "rad"])
        c.add_metric("lambda", 0.96, "1")
        c.add_corrections(q_taught, q_corrected, program="body_side")
    # committed here, all rows at once; an exception inside the block rolls all of them back

Every number is stored in millimetres or radians with its unit; every time is UTC. A process
killed inside the block leaves nothing of that cycle behind and every committed cycle intact
(SQLite's write-ahead log is rolled back on the next open). Readers never see a cycle that is
still being written.
"""

from __future__ import annotations

import json
import warnings
from contextlib import contextmanager
from dataclasses import dataclass, field
from datetime import datetime
from typing import NamedTuple

import numpy as np

from . import _schema
from ._backends import HistoryBusyError, HistoryError, open_backend
from ._validate import (
    HistoryInputError, check_array, check_joints, check_kind, check_name, check_number,
    check_points_mm, check_robot_id, check_unit, format_time, parse_time, utc_now,
)

__all__ = [
    "CycleRecord", "CycleWriter", "HistoryBusyError", "HistoryError", "HistoryInputError", "HistoryLookupError",
    "HistoryStore", "ParameterRow", "Quantity", "Series", "StoredCycle", "UnknownRobotError",
]


class HistoryLookupError(HistoryError, LookupError):
    """A robot, cycle, parameter or metric asked for is not in the database."""


class UnknownRobotError(HistoryLookupError):
    """The robot id is not in the database; ``known`` lists the ids that are."""

    def __init__(self, robot: str, known: list, where: str):
        self.robot = robot
        self.known = list(known)
        listing = f"known robots: {', '.join(self.known)}" if self.known else "the database has no robots yet"
        super().__init__(f"robot {robot!r} is not in the history database {where}; {listing}")


class Quantity(NamedTuple):
    value: float
    unit: str


class ParameterRow(NamedTuple):
    delta: float
    value: float | None
    std: float | None
    unit: str


@dataclass(frozen=True)
class CycleRecord:
    """One cycle as listed by :meth:`HistoryStore.cycles`. Times are UTC."""

    id: int
    robot: str
    kind: str
    status: str
    started_at: datetime
    finished_at: datetime | None
    notes: str | None
    meta: dict
    metrics: dict = field(default_factory=dict)  # name -> Quantity
    n_measurements: int = 0
    n_parameters: int = 0
    n_corrections: int = 0


@dataclass(frozen=True)
class Series:
    """A time series over committed cycles, oldest first.

    ``times`` are ``datetime64[us]`` in UTC (numpy keeps no zone); ``values`` shape (N,) in
    ``unit``; ``std`` shape (N,), NaN where no uncertainty was stored; ``cycle_ids`` and
    ``kinds`` say which cycle each value comes from.
    """

    name: str
    unit: str
    times: np.ndarray
    values: np.ndarray
    std: np.ndarray
    cycle_ids: np.ndarray
    kinds: tuple

    def __len__(self) -> int:
        return int(self.values.shape[0])


@dataclass(frozen=True)
class StoredCycle:
    """Everything one cycle stored (:meth:`HistoryStore.load_cycle`).

    Measurements: ``pose_index`` (N,), ``targets``/``sensors`` (N,) labels, ``joints`` (N, n) in
    ``joint_units`` (rad revolute, mm prismatic), ``points_mm`` (N, 3). Corrections:
    ``corrections_joints_before``/``_after`` (M, n), ``correction_programs``/``_point_names`` (M,),
    ``correction_point_index`` (M,).
    """

    record: CycleRecord
    pose_index: np.ndarray
    targets: tuple
    sensors: tuple
    joints: np.ndarray
    joint_units: tuple
    points_mm: np.ndarray
    parameters: dict  # name -> ParameterRow
    correction_programs: tuple
    correction_point_index: np.ndarray
    correction_point_names: tuple
    corrections_joints_before: np.ndarray
    corrections_joints_after: np.ndarray


def _labels(x, n: int, what: str) -> list:
    """``None``, one string for all rows, or one string (or None) per row."""
    if x is None or isinstance(x, str):
        out = [x] * n
    else:
        out = list(x)
        if len(out) != n:
            raise HistoryInputError(f"{what}: {len(out)} labels for {n} rows")
    for i, s in enumerate(out):
        if s is not None and (not isinstance(s, str) or len(s) > 255):
            raise HistoryInputError(f"{what} row {i}: expected a string of at most 255 characters, got {s!r}")
    return out


def _indices(x, n: int, what: str) -> list:
    if x is None:
        return list(range(n))
    arr = np.asarray(x)
    if arr.shape != (n,) or not (np.issubdtype(arr.dtype, np.integer) or arr.size == 0):
        raise HistoryInputError(f"{what} must be {n} integers, got {arr.dtype} array of shape {arr.shape}")
    if arr.size and arr.min() < 0:
        raise HistoryInputError(f"{what} row {int(np.argmin(arr))} is negative")
    return [int(v) for v in arr]


def _json(obj, what: str) -> str:
    try:
        return json.dumps(obj, allow_nan=False, sort_keys=True)
    except (TypeError, ValueError) as exc:
        raise HistoryInputError(f"{what} must be JSON data (numbers finite): {exc}") from None


def _units_list(units, n: int, what: str) -> list:
    if units is None:
        raise HistoryInputError(f"{what}: units are required (mm, rad, ...)")
    if isinstance(units, str):
        units = [units] * n
    units = list(units)
    if len(units) != n:
        raise HistoryInputError(f"{what}: {len(units)} units for {n} values")
    return units


class CycleWriter:
    """Adds rows to one open cycle (from :meth:`HistoryStore.cycle`); every call validates all its
    inputs before writing anything. Rows become visible to others only when the cycle commits."""

    def __init__(self, store, tx, cycle_id, robot, kind, started_at, finished_at, notes):
        self._store = store
        self._tx = tx
        self.id = cycle_id
        self.robot = robot
        self.kind = kind
        self.started_at = started_at
        self._finished_at = finished_at
        self.notes = notes
        self.status = "running"
        self._n_joints = None
        self._seq = 0
        self._params = set()
        self._metrics = set()
        self._corr_keys = set()
        self.counts = {"measurements": 0, "parameters": 0, "metrics": 0, "corrections": 0}

    # -- times ---------------------------------------------------------------------------------
    @property
    def finished_at(self) -> datetime | None:
        return self._finished_at

    @finished_at.setter
    def finished_at(self, t) -> None:
        self._finished_at = parse_time(t, "finished_at")

    def _check_open(self) -> None:
        if self.status != "running":
            raise HistoryError(f"cycle {self.id} is closed ({self.status}); open a new one with store.cycle(...)")

    def _check_joint_count(self, n: int, what: str) -> None:
        if self._n_joints is None:
            self._n_joints = n
        elif n != self._n_joints:
            raise HistoryInputError(f"{what} has {n} joints, earlier rows of this cycle had {self._n_joints}")

    def _write(self, fn, *args):
        try:
            return fn(*args)
        except self._store._backend.errors as exc:
            raise HistoryError(f"cannot write to history database {self._store.url}: {str(exc).splitlines()[0]}") from exc

    # -- rows ----------------------------------------------------------------------------------
    def add_measurements(self, joints, points_mm, *, pose_index=None, target=None, sensor=None, joint_units=None) -> int:
        """Measured 3-D points with the robot joints they were measured at.

        joints shape (N, n) [rad revolute, mm prismatic; ``joint_units`` per joint, default all
        rad]; points_mm shape (N, 3) [mm]; pose_index (N,) non-negative ints (default 0..N-1);
        target, sensor: a label for all rows or one per row (e.g. ``"sphere"``, ``"stereo"``).
        Returns the number of rows added.
        """
        self._check_open()
        q, units = check_joints(joints, "measurements: joints", joint_units)
        p = check_points_mm(points_mm, "measurements: points_mm")
        n = q.shape[0]
        if p.shape[0] != n:
            raise HistoryInputError(f"measurements: {n} joint rows but {p.shape[0]} points")
        self._check_joint_count(q.shape[1], "measurements: joints")
        idx = _indices(pose_index, n, "measurements: pose_index")
        tg = _labels(target, n, "measurements: target")
        se = _labels(sensor, n, "measurements: sensor")
        ju = json.dumps(units)
        rows = [{"cycle_id": self.id, "seq": self._seq + i, "pose_index": idx[i], "target": tg[i], "sensor": se[i],
                 "joints": json.dumps(q[i].tolist()), "joint_units": ju,
                 "x": float(p[i, 0]), "y": float(p[i, 1]), "z": float(p[i, 2]), "unit": "mm"} for i in range(n)]
        self._write(self._tx.insert_many, "measurements", rows)
        self._seq += n
        self.counts["measurements"] += n
        return n

    def add_parameter(self, name: str, delta, unit: str, *, value=None, std=None) -> None:
        """One identified parameter: its change ``delta`` from nominal (required), the identified
        ``value`` and standard uncertainty ``std`` where known, all in ``unit`` (mm or rad)."""
        self.add_parameters([name], [delta], units=unit, values=None if value is None else [value],
                            std=None if std is None else [std])

    def add_parameters(self, names, deltas, *, units, values=None, std=None) -> int:
        """Identified parameters by name (``a2``, ``beta2``, ``base.rx``): ``deltas`` (N,) change
        from nominal, ``values`` (N,) identified values or None, ``std`` (N,) standard
        uncertainties or None (entries may be None); ``units`` one unit for all or (N,)."""
        self._check_open()
        names = [names] if isinstance(names, str) else list(names)
        n = len(names)
        for nm in names:
            check_name(nm, "parameter")
        d = check_array(deltas, "parameters: deltas", ndim=1)
        if d.shape[0] != n:
            raise HistoryInputError(f"parameters: {n} names but {d.shape[0]} deltas")
        us = [check_unit(u, f"parameter {nm!r}") for nm, u in zip(names, _units_list(units, n, "parameters"))]

        def optional(arr, what):
            if arr is None:
                return [None] * n
            arr = list(arr)
            if len(arr) != n:
                raise HistoryInputError(f"parameters: {n} names but {len(arr)} {what}")
            return [check_number(v, f"parameter {nm!r} {what[:-1]}", allow_none=True) for nm, v in zip(names, arr)]

        vals = optional(values, "values")
        sds = optional(std, "stds")
        for nm, s in zip(names, sds):
            if s is not None and s < 0:
                raise HistoryInputError(f"parameter {nm!r} std is negative ({s!r})")
        seen = set()
        for nm in names:
            if nm in self._params or nm in seen:
                raise HistoryInputError(f"parameter {nm!r} was already added to this cycle")
            seen.add(nm)
        rows = [{"cycle_id": self.id, "name": nm, "value": v, "delta": float(dv), "std": s, "unit": u}
                for nm, dv, v, s, u in zip(names, d, vals, sds, us)]
        self._write(self._tx.insert_many, "parameters", rows)
        self._params |= seen
        self.counts["parameters"] += n
        return n

    def add_metric(self, name: str, value, unit: str) -> None:
        """One number describing the cycle: ``residual_rms_before``/``_after`` [mm], ``lambda`` [1],
        ``cycle_time`` [s], ``condition_number`` [1], ... (see docs/history.md)."""
        self._check_open()
        check_name(name, "metric")
        v = check_number(value, f"metric {name!r}")
        u = check_unit(unit, f"metric {name!r}")
        if name in self._metrics:
            raise HistoryInputError(f"metric {name!r} was already added to this cycle")
        self._write(self._tx.insert, "metrics", {"cycle_id": self.id, "name": name, "value": v, "unit": u})
        self._metrics.add(name)
        self.counts["metrics"] += 1

    def add_metrics(self, metrics: dict) -> None:
        """Several metrics: ``{name: (value, unit)}``."""
        items = []
        for name, vu in dict(metrics).items():
            if not (isinstance(vu, tuple) and len(vu) == 2):
                raise HistoryInputError(f"metric {name!r}: give (value, unit), got {vu!r}")
            items.append((name, *vu))
        for name, v, u in items:  # validate everything first
            check_name(name, "metric")
            check_number(v, f"metric {name!r}")
            check_unit(u, f"metric {name!r}")
        for name, v, u in items:
            self.add_metric(name, v, u)

    def add_corrections(self, joints_before, joints_after, *, program=None, point_index=None, point_names=None,
                        joint_units=None) -> int:
        """Corrected joint targets sent to the controller: joints_before/joints_after shape (M, n)
        [rad revolute, mm prismatic] for the points of ``program`` (a name); point_index (M,)
        (default 0..M-1), point_names (M,) optional labels."""
        self._check_open()
        qb, units = check_joints(joints_before, "corrections: joints_before", joint_units)
        qa, _ = check_joints(joints_after, "corrections: joints_after", joint_units)
        if qa.shape != qb.shape:
            raise HistoryInputError(f"corrections: joints_before has shape {qb.shape}, joints_after {qa.shape}")
        self._check_joint_count(qb.shape[1], "corrections: joints")
        m = qb.shape[0]
        if program is not None and (not isinstance(program, str) or len(program) > 255):
            raise HistoryInputError(f"corrections: program must be a name (string), got {program!r}")
        idx = _indices(point_index, m, "corrections: point_index")
        names = _labels(point_names, m, "corrections: point_names")
        keys = {(program, i) for i in idx}
        if len(keys) != m or keys & self._corr_keys:
            raise HistoryInputError(f"corrections: a point index of program {program!r} appears twice in this cycle")
        ju = json.dumps(units)
        rows = [{"cycle_id": self.id, "program": program, "point_index": idx[i], "point_name": names[i],
                 "joints_before": json.dumps(qb[i].tolist()), "joints_after": json.dumps(qa[i].tolist()),
                 "joint_units": ju} for i in range(m)]
        self._write(self._tx.insert_many, "corrections", rows)
        self._corr_keys |= keys
        self.counts["corrections"] += m
        return m


class HistoryStore:
    """The history database. Open with :meth:`open`; not shared between threads (open one store
    per thread or process: each has its own connection)."""

    def __init__(self, backend):
        self._backend = backend
        self._open_cycle = None
        self.url = backend.display
        self._migrate()

    # -- opening -------------------------------------------------------------------------------
    @classmethod
    def open(cls, target, *, create: bool = True, timeout: float = 30.0) -> "HistoryStore":
        """Open (and by default create) a history database.

        target: a file path (``history.sqlite``, a ``Path``) or ``sqlite:///relative.sqlite``,
        ``sqlite:////absolute.sqlite``, ``sqlite:///:memory:`` (standard library sqlite3, WAL
        journal); any other URL (``postgresql+psycopg://user:pw@host/db``,
        ``sqlite+pysqlite:///x.sqlite``) goes through SQLAlchemy Core (the ``db`` extra).
        create=False refuses a missing SQLite file. timeout [s]: how long a writer waits for
        another writer's transaction before :class:`HistoryBusyError`.
        """
        timeout = check_number(timeout, "timeout")
        return cls(open_backend(target, create=create, timeout=timeout))

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def close(self) -> None:
        self._backend.close()

    def __repr__(self) -> str:
        return f"HistoryStore({self.url!r})"

    def _migrate(self) -> None:
        b = self._backend
        try:
            names = b.table_names()
        except b.errors as exc:
            b.close()
            raise HistoryError(f"cannot read history database {self.url}: {str(exc).splitlines()[0]}") from None
        # an SQLite file belongs to one application; a server database may hold other tables, just
        # not ones with our names
        clash = names if b.dialect == "sqlite" else names & set(_schema.ALL_TABLES)
        if "schema_version" not in names and clash:
            b.close()
            raise HistoryError(f"{self.url} is not a robocal history database (it has tables {', '.join(sorted(clash))} "
                               "but no schema_version)")
        if "schema_version" in names and self._stored_version() >= _schema.SCHEMA_VERSION:
            self._check_version_not_newer()
            return
        tx = b.begin()
        try:
            tx.create_tables([_schema.SCHEMA_VERSION_TABLE])
            rows = tx.query("SELECT MAX(version) AS v FROM schema_version")
            have = rows[0]["v"] or 0
            for m in _schema.MIGRATIONS:
                if m.version > have:
                    tx.create_tables(m.tables)
                    for stmt in m.extra:
                        tx.execute(stmt)
                    tx.insert("schema_version", {"version": m.version, "applied_at": format_time(utc_now()),
                                                 "description": m.description})
            tx.commit()
        except BaseException:
            tx.rollback()
            b.close()
            raise
        self._check_version_not_newer()

    def _stored_version(self) -> int:
        return int(self._backend.read("SELECT MAX(version) AS v FROM schema_version")[0]["v"] or 0)

    def _check_version_not_newer(self) -> None:
        v = self._stored_version()
        if v > _schema.SCHEMA_VERSION:
            self._backend.close()
            raise HistoryError(f"history database {self.url} has schema version {v}, newer than this robocal "
                               f"understands ({_schema.SCHEMA_VERSION}); upgrade robocal")

    @property
    def schema_version(self) -> int:
        return self._stored_version()

    def check(self) -> list:
        """Problems found by the database's own integrity and foreign-key checks (empty: healthy;
        for server databases, always empty: they check themselves)."""
        return self._backend.integrity_problems()

    # -- writing -------------------------------------------------------------------------------
    @contextmanager
    def cycle(self, robot: str, kind: str, *, started_at=None, finished_at=None, notes: str | None = None,
              meta: dict | None = None, robot_model: str | None = None, record_failure: bool = True):
        """One calibration or maintenance cycle as one transaction (a context manager yielding a
        :class:`CycleWriter`).

        kind: one of ``geometric_calibration``, ``thermal_compensation``, ``tool_recalibration``,
        ``measurement``. started_at: when it started (aware datetime or ISO string with offset;
        default now); finished_at: when it ended (default: the time it commits; the writer's
        ``finished_at`` may be set inside the block, e.g. for simulated time). meta: JSON data
        (settings, software version, file names). robot_model: the robot's model name, recorded with
        the robot the first time and checked afterwards.

        On leaving the block normally every row is committed at once. On an exception nothing of
        the cycle stays; with ``record_failure`` a row with status ``failed`` and the error in its
        notes is recorded instead (and the exception propagates).
        """
        robot = check_robot_id(robot)
        kind = check_kind(kind)
        t0 = utc_now() if started_at is None else parse_time(started_at, "started_at")
        t1 = None if finished_at is None else parse_time(finished_at, "finished_at")
        if notes is not None and not isinstance(notes, str):
            raise HistoryInputError(f"notes must be a string, got {type(notes).__name__}")
        if meta is not None and not isinstance(meta, dict):
            raise HistoryInputError(f"meta must be a dict, got {type(meta).__name__}")
        meta_json = _json({} if meta is None else meta, "meta")
        if robot_model is not None and (not isinstance(robot_model, str) or not robot_model or len(robot_model) > 255):
            raise HistoryInputError(f"robot_model must be a non-empty string, got {robot_model!r}")
        if self._open_cycle is not None:
            raise HistoryError(f"cycle {self._open_cycle.id} is still open on this store; finish it before starting another")

        b = self._backend
        tx = b.begin()
        try:
            robot_id = self._robot_id(tx, robot, robot_model)
            cid = tx.insert("cycles", {"robot_id": robot_id, "kind": kind, "status": "running",
                                       "started_at": format_time(t0), "finished_at": None, "notes": notes,
                                       "meta": meta_json})
        except BaseException as exc:
            tx.rollback()
            if isinstance(exc, b.errors):
                raise HistoryError(f"cannot start a cycle in {self.url}: {str(exc).splitlines()[0]}") from exc
            raise
        w = CycleWriter(self, tx, cid, robot, kind, t0, t1, notes)
        self._open_cycle = w
        try:
            yield w
            w._check_open()
            t1 = w.finished_at or utc_now()
            if t1 < t0:
                raise HistoryInputError(f"cycle finished_at {format_time(t1)} is before started_at {format_time(t0)}")
            if w.notes is not None and not isinstance(w.notes, str):
                raise HistoryInputError(f"notes must be a string, got {type(w.notes).__name__}")
            try:
                tx.execute("UPDATE cycles SET status = :s, finished_at = :f, notes = :n WHERE id = :id",
                           {"s": "committed", "f": format_time(t1), "n": w.notes, "id": cid})
                tx.commit()
            except b.errors as exc:
                raise HistoryError(f"cannot commit cycle to {self.url}: {str(exc).splitlines()[0]}") from exc
            w.status = "committed"
        except BaseException as exc:
            w.status = "failed"
            try:
                tx.rollback()
            except b.errors:
                pass
            if record_failure and isinstance(exc, (Exception, KeyboardInterrupt)) and not isinstance(exc, HistoryBusyError):
                w.id = self._record_failed(robot, robot_model, kind, t0, notes, meta_json, exc)
            raise
        finally:
            self._open_cycle = None

    def _robot_id(self, tx, robot: str, model: str | None) -> int:
        rows = tx.query("SELECT id, model FROM robots WHERE name = :n", {"n": robot})
        if rows:
            stored = rows[0]["model"]
            if model is not None and stored is not None and stored != model:
                raise HistoryInputError(f"robot {robot!r} is recorded as model {stored!r}, not {model!r}")
            if model is not None and stored is None:
                tx.execute("UPDATE robots SET model = :m WHERE id = :id", {"m": model, "id": rows[0]["id"]})
            return int(rows[0]["id"])
        return tx.insert("robots", {"name": robot, "model": model, "created_at": format_time(utc_now()), "notes": None})

    def _record_failed(self, robot, model, kind, t0, notes, meta_json, exc) -> int | None:
        msg = f"failed: {type(exc).__name__}: {exc}"
        b = self._backend
        try:
            tx = b.begin()
        except (HistoryError, *b.errors):
            return None
        try:
            rid = self._robot_id(tx, robot, None)
            cid = tx.insert("cycles", {"robot_id": rid, "kind": kind, "status": "failed", "started_at": format_time(t0),
                                       "finished_at": format_time(max(utc_now(), t0)),
                                       "notes": msg if not notes else f"{notes}\n{msg}", "meta": meta_json})
            tx.commit()
            return cid
        except Exception as exc2:  # the original error matters more; say why this one was lost
            try:
                tx.rollback()
            except Exception:
                pass
            warnings.warn(f"could not record the failed cycle in {self.url}: {exc2}", RuntimeWarning, stacklevel=3)
            return None

    # -- reading -------------------------------------------------------------------------------
    def _read(self, sql: str, params: dict | None = None) -> list:
        b = self._backend
        try:
            return b.read(sql, params)
        except b.errors as exc:
            raise HistoryError(f"cannot read history database {self.url}: {str(exc).splitlines()[0]}") from None

    def robots(self) -> list:
        """Robot ids in the database, sorted."""
        return [r["name"] for r in self._read("SELECT name FROM robots ORDER BY name")]

    def _require_robot(self, robot: str) -> None:
        robot = check_robot_id(robot)
        if not self._read("SELECT id FROM robots WHERE name = :n", {"n": robot}):
            raise UnknownRobotError(robot, self.robots(), self.url)

    def _filters(self, robot, kind, since, until, committed_only: bool, status=None):
        where = ["r.name = :robot"]
        params = {"robot": robot}
        if kind is not None:
            kinds = [kind] if isinstance(kind, str) else list(kind)
            for i, k in enumerate(kinds):
                params[f"k{i}"] = check_kind(k)
            where.append("(" + " OR ".join(f"c.kind = :k{i}" for i in range(len(kinds))) + ")")
        if since is not None:
            params["since"] = format_time(parse_time(since, "since"))
            where.append("c.started_at >= :since")
        if until is not None:
            params["until"] = format_time(parse_time(until, "until"))
            where.append("c.started_at <= :until")
        if committed_only:
            status = "committed"
        if status is not None:
            if status not in _schema.CYCLE_STATUSES:
                raise HistoryInputError(f"status {status!r} is not known; valid: {', '.join(_schema.CYCLE_STATUSES)}")
            params["status"] = status
            where.append("c.status = :status")
        return " AND ".join(where), params

    def cycles(self, robot: str, kind=None, since=None, until=None, status: str | None = None) -> list:
        """The robot's cycles, oldest first, as :class:`CycleRecord` (with their metrics).

        kind: a kind or a list of kinds; since/until: bounds on the start time (inclusive);
        status: ``committed`` or ``failed`` (default both)."""
        self._require_robot(robot)
        where, params = self._filters(robot, kind, since, until, False, status)
        rows = self._read(
            "SELECT c.id, c.kind, c.status, c.started_at, c.finished_at, c.notes, c.meta, "
            "(SELECT COUNT(*) FROM measurements m WHERE m.cycle_id = c.id) AS n_meas, "
            "(SELECT COUNT(*) FROM parameters p WHERE p.cycle_id = c.id) AS n_par, "
            "(SELECT COUNT(*) FROM corrections k WHERE k.cycle_id = c.id) AS n_corr "
            f"FROM cycles c JOIN robots r ON r.id = c.robot_id WHERE {where} ORDER BY c.started_at, c.id", params)
        metrics = {}
        for m in self._read("SELECT m.cycle_id, m.name, m.value, m.unit FROM metrics m JOIN cycles c ON c.id = m.cycle_id "
                            f"JOIN robots r ON r.id = c.robot_id WHERE {where} ORDER BY m.id", params):
            metrics.setdefault(m["cycle_id"], {})[m["name"]] = Quantity(float(m["value"]), m["unit"])
        return [self._record(r, robot, metrics.get(r["id"], {})) for r in rows]

    @staticmethod
    def _record(r, robot, metrics) -> CycleRecord:
        return CycleRecord(
            id=int(r["id"]), robot=robot, kind=r["kind"], status=r["status"],
            started_at=parse_time(r["started_at"]),
            finished_at=None if r["finished_at"] is None else parse_time(r["finished_at"]),
            notes=r["notes"], meta=json.loads(r["meta"]) if r["meta"] else {}, metrics=metrics,
            n_measurements=int(r.get("n_meas", 0) or 0), n_parameters=int(r.get("n_par", 0) or 0),
            n_corrections=int(r.get("n_corr", 0) or 0))

    def parameter_names(self, robot: str) -> list:
        """Names of the parameters stored for the robot's committed cycles, sorted."""
        self._require_robot(robot)
        return [r["name"] for r in self._read(
            "SELECT DISTINCT p.name FROM parameters p JOIN cycles c ON c.id = p.cycle_id JOIN robots r ON r.id = c.robot_id "
            "WHERE r.name = :robot AND c.status = 'committed' ORDER BY p.name", {"robot": robot})]

    def metric_names(self, robot: str) -> list:
        """Names of the metrics stored for the robot's committed cycles, sorted."""
        self._require_robot(robot)
        return [r["name"] for r in self._read(
            "SELECT DISTINCT m.name FROM metrics m JOIN cycles c ON c.id = m.cycle_id JOIN robots r ON r.id = c.robot_id "
            "WHERE r.name = :robot AND c.status = 'committed' ORDER BY m.name", {"robot": robot})]

    def parameter_history(self, robot: str, names=None, *, kind=None, since=None, until=None,
                          field: str = "delta") -> dict:
        """``{name: Series}`` of a parameter over the robot's committed cycles, oldest first.

        names: a name, a list, or None for every stored parameter; field: ``delta`` (change from
        nominal, default) or ``value`` (identified value; NaN where none was stored). A name never
        stored for the robot is an error listing the stored ones."""
        if field not in ("delta", "value"):
            raise HistoryInputError(f"field must be 'delta' or 'value', got {field!r}")
        known = self.parameter_names(robot)
        if names is None:
            names = known
        names = [names] if isinstance(names, str) else list(names)
        missing = [n for n in names if n not in known]
        if missing:
            listing = ", ".join(known) if known else "none"
            raise HistoryLookupError(
                f"no parameter {', '.join(map(repr, missing))} stored for robot {robot!r}; stored: {listing}")
        where, params = self._filters(robot, kind, since, until, True)
        out = {}
        for name in names:
            rows = self._read(
                f"SELECT c.id, c.kind, c.started_at, p.{field} AS v, p.std, p.unit FROM parameters p "
                f"JOIN cycles c ON c.id = p.cycle_id JOIN robots r ON r.id = c.robot_id "
                f"WHERE {where} AND p.name = :pname ORDER BY c.started_at, c.id", params | {"pname": name})
            out[name] = self._series(name, rows)
        return out

    def metric_history(self, robot: str, name: str, *, kind=None, since=None, until=None) -> Series:
        """A metric (``residual_rms_after``, ``lambda``, ...) over the robot's committed cycles."""
        known = self.metric_names(robot)
        if name not in known:
            raise HistoryLookupError(f"no metric {name!r} stored for robot {robot!r}; stored: {', '.join(known) or 'none'}")
        where, params = self._filters(robot, kind, since, until, True)
        rows = self._read(
            "SELECT c.id, c.kind, c.started_at, m.value AS v, NULL AS std, m.unit FROM metrics m "
            "JOIN cycles c ON c.id = m.cycle_id JOIN robots r ON r.id = c.robot_id "
            f"WHERE {where} AND m.name = :mname ORDER BY c.started_at, c.id", params | {"mname": name})
        return self._series(name, rows)

    @staticmethod
    def _series(name, rows) -> Series:
        units = sorted({r["unit"] for r in rows})
        if len(units) > 1:
            raise HistoryError(f"{name!r} is stored in several units ({', '.join(units)}); cannot make one series")
        times = np.array([np.datetime64(parse_time(r["started_at"]).replace(tzinfo=None), "us") for r in rows],
                         dtype="datetime64[us]")
        f = [np.nan if r["v"] is None else float(r["v"]) for r in rows]
        s = [np.nan if r["std"] is None else float(r["std"]) for r in rows]
        return Series(name=name, unit=units[0] if units else "", times=times, values=np.array(f, dtype=float),
                      std=np.array(s, dtype=float), cycle_ids=np.array([int(r["id"]) for r in rows], dtype=np.int64),
                      kinds=tuple(r["kind"] for r in rows))

    def load_cycle(self, cycle_id: int) -> StoredCycle:
        """Everything one cycle stored: measurements, parameters, metrics, corrections."""
        if isinstance(cycle_id, bool) or not isinstance(cycle_id, (int, np.integer)):
            raise HistoryInputError(f"cycle id must be an integer, got {cycle_id!r}")
        cid = int(cycle_id)
        rows = self._read("SELECT c.*, r.name AS robot FROM cycles c JOIN robots r ON r.id = c.robot_id WHERE c.id = :id",
                          {"id": cid})
        if not rows:
            raise HistoryLookupError(f"no cycle {cid} in history database {self.url}")
        metrics = {m["name"]: Quantity(float(m["value"]), m["unit"]) for m in
                   self._read("SELECT name, value, unit FROM metrics WHERE cycle_id = :id ORDER BY id", {"id": cid})}
        meas = self._read("SELECT * FROM measurements WHERE cycle_id = :id ORDER BY seq", {"id": cid})
        pars = self._read("SELECT * FROM parameters WHERE cycle_id = :id ORDER BY id", {"id": cid})
        corr = self._read("SELECT * FROM corrections WHERE cycle_id = :id ORDER BY id", {"id": cid})
        rec = self._record(rows[0] | {"n_meas": len(meas), "n_par": len(pars), "n_corr": len(corr)}, rows[0]["robot"], metrics)

        def joints(col, rs):
            arrs = [json.loads(r[col]) for r in rs]
            return np.array(arrs, dtype=float) if arrs else np.zeros((0, 0))

        units_src = meas or corr
        return StoredCycle(
            record=rec,
            pose_index=np.array([r["pose_index"] for r in meas], dtype=np.int64),
            targets=tuple(r["target"] for r in meas), sensors=tuple(r["sensor"] for r in meas),
            joints=joints("joints", meas),
            joint_units=tuple(json.loads(units_src[0]["joint_units"])) if units_src else (),
            points_mm=np.array([[r["x"], r["y"], r["z"]] for r in meas], dtype=float).reshape(-1, 3),
            parameters={p["name"]: ParameterRow(float(p["delta"]), p["value"], p["std"], p["unit"]) for p in pars},
            correction_programs=tuple(r["program"] for r in corr),
            correction_point_index=np.array([r["point_index"] for r in corr], dtype=np.int64),
            correction_point_names=tuple(r["point_name"] for r in corr),
            corrections_joints_before=joints("joints_before", corr),
            corrections_joints_after=joints("joints_after", corr),
        )

