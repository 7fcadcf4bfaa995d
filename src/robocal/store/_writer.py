"""Rows of one open cycle: :class:`CycleWriter` validates every input of a call before writing
any of it, inside the cycle's transaction (see :meth:`robocal.store.HistoryStore.cycle`).

Joints in rad (revolute) or mm (prismatic), points in mm, every number with its unit.
"""

from __future__ import annotations

import json
from datetime import datetime

from ._backends import HistoryError
from ._validate import (
    HistoryInputError, METRIC_UNITS, check_array, check_indices, check_joints, check_labels, check_name, check_number,
    check_points_mm, check_unit, check_units_list, parse_time,
)

__all__ = ["CycleWriter"]


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
        idx = check_indices(pose_index, n, "measurements: pose_index")
        tg = check_labels(target, n, "measurements: target")
        se = check_labels(sensor, n, "measurements: sensor")
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
        us = [check_unit(u, f"parameter {nm!r}") for nm, u in zip(names, check_units_list(units, n, "parameters"))]

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
        """One number describing the cycle: ``residual_rms_before``/``_after`` [mm] (the
        calibration's own residuals), ``lambda`` [%], ``cycle_time`` [s], ``condition_number`` [1],
        ... (see docs/history.md)."""
        self._check_open()
        check_name(name, "metric")
        v = check_number(value, f"metric {name!r}")
        u = check_unit(unit, f"metric {name!r}")
        if name in METRIC_UNITS and u != METRIC_UNITS[name]:
            raise HistoryInputError(f"metric {name!r} is stored in {METRIC_UNITS[name]!r}, got {u!r}"
                                    + (" (multiply a fraction by 100)" if METRIC_UNITS[name] == "%" else ""))
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
        idx = check_indices(point_index, m, "corrections: point_index")
        names = check_labels(point_names, m, "corrections: point_names")
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
