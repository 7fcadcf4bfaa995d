"""Reading the history: robots, cycles with their metrics, parameter and metric time series,
everything one cycle stored.

:class:`HistoryQueries` is the reading half of :class:`robocal.store.HistoryStore`; it needs
``self._backend`` (see :mod:`._backends`) and ``self.url``. Only committed cycles enter the time
series; times are UTC.
"""

from __future__ import annotations

import json

import numpy as np

from . import _schema
from ._backends import HistoryError
from ._records import (
    CycleRecord, HistoryLookupError, ParameterRow, Quantity, Series, StoredCycle, UnknownRobotError,
)
from ._validate import HistoryInputError, check_kind, check_robot_id, format_time, parse_time

__all__ = ["HistoryQueries"]


class HistoryQueries:
    """Read-only queries of a history database (mixed into :class:`robocal.store.HistoryStore`)."""

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

    def iso_figure_history(self, robot: str, symbol: str, pose: str = "", *, since=None, until=None) -> Series:
        """An ISO 9283 figure (``AP``, ``RP``, ``vAP``, ``AT``, ...) of one pose (``""``: the
        run's worst value over the poses) over the robot's committed performance tests, oldest
        first; ``std`` holds the instrument's uncertainty U/2 where it was stated (NaN otherwise).
        Empty when none was stored."""
        self._require_robot(robot)
        where, params = self._filters(robot, None, since, until, True)
        rows = self._read(
            "SELECT c.id, c.kind, c.started_at, f.value AS v, f.uncertainty / 2.0 AS std, f.unit FROM iso9283_figures f "
            "JOIN cycles c ON c.id = f.cycle_id JOIN robots r ON r.id = c.robot_id "
            f"WHERE {where} AND f.symbol = :sym AND f.pose = :pose ORDER BY c.started_at, c.id",
            params | {"sym": symbol, "pose": pose or ""})
        return self._series(symbol if not pose else f"{symbol}.{pose}", rows)

    def iso_figures(self, cycle_id: int) -> list:
        """Every ISO 9283 figure one cycle stored: dicts with symbol, pose, value, unit,
        uncertainty (or None) and adequate (True, False or None)."""
        rows = self._read("SELECT symbol, pose, value, unit, uncertainty, adequate FROM iso9283_figures "
                          "WHERE cycle_id = :id ORDER BY id", {"id": int(cycle_id)})
        for r in rows:
            r["adequate"] = None if r["adequate"] is None else bool(r["adequate"])
        return rows

    def verifications(self, robot: str, *, since=None, until=None) -> list:
        """The robot's quick verifications (committed), oldest first: dicts with the cycle's id and
        start time (``time``, UTC datetime), ``decision``, ``statistic``, ``dof``, ``threshold``,
        ``false_alarm_rate``, ``n_poses``, ``rms_mm``, ``max_mm``, ``suspect``, ``suspect_value``,
        ``suspect_unit``, ``instrument``, ``temperature_c``, ``model``."""
        self._require_robot(robot)
        where, params = self._filters(robot, None, since, until, True)
        rows = self._read(
            "SELECT c.id AS cycle_id, c.started_at, v.decision, v.statistic, v.dof, v.threshold, v.false_alarm_rate, "
            "v.n_poses, v.rms_mm, v.max_mm, v.suspect, v.suspect_value, v.suspect_unit, v.instrument, "
            "v.temperature_c, v.model FROM verifications v JOIN cycles c ON c.id = v.cycle_id "
            f"JOIN robots r ON r.id = c.robot_id WHERE {where} ORDER BY c.started_at, c.id", params)
        for r in rows:
            r["time"] = parse_time(r.pop("started_at"))
        return rows

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
