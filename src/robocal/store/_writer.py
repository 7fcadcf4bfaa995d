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
        self._iso_keys = set()
        self._verified = False
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

    # -- performance tests and verifications (schema version 3) --------------------------------
    def add_iso_figures(self, figures) -> int:
        """ISO 9283 figures of one performance test: an iterable of dicts with ``symbol`` (``AP``,
        ``RP``, ``AP_x``, ``AP_a``, ``vAP``, ``AD``, ``RD``, ``dAP``, ``dRP``, ``AT``, ``RT``, ...),
        ``pose`` (``P1``..``P5``, ``line``, ``circle``; ``""`` for the run's worst value), ``value``,
        ``unit`` (``mm`` or ``rad``) and optionally ``uncertainty`` (same unit) and ``adequate``
        (bool: the instrument is good enough to state the figure). Returns the number of rows."""
        self._check_open()
        rows, keys = [], set()
        for i, f in enumerate(figures):
            if not isinstance(f, dict):
                raise HistoryInputError(f"iso figure {i}: expected a dict, got {f!r}")
            sym = check_name(f.get("symbol"), f"iso figure {i} symbol")
            pose = f.get("pose") or ""
            if not isinstance(pose, str) or len(pose) > 255:
                raise HistoryInputError(f"iso figure {sym!r}: pose must be a name, got {pose!r}")
            unit = check_unit(f.get("unit"), f"iso figure {sym!r}")
            if unit not in ("mm", "rad"):
                raise HistoryInputError(f"iso figure {sym!r}: unit must be 'mm' or 'rad', got {unit!r}")
            val = check_number(f.get("value"), f"iso figure {sym!r} {pose!r} value")
            u = check_number(f.get("uncertainty"), f"iso figure {sym!r} {pose!r} uncertainty", allow_none=True)
            ad = f.get("adequate")
            if ad is not None and not isinstance(ad, bool):
                raise HistoryInputError(f"iso figure {sym!r}: adequate must be True, False or None, got {ad!r}")
            key = (sym, pose)
            if key in keys or key in self._iso_keys:
                raise HistoryInputError(f"iso figure {sym!r} of pose {pose!r} was already added to this cycle")
            keys.add(key)
            rows.append({"cycle_id": self.id, "symbol": sym, "pose": pose, "value": val, "unit": unit,
                         "uncertainty": u, "adequate": None if ad is None else int(ad)})
        self._write(self._tx.insert_many, "iso9283_figures", rows)
        self._iso_keys |= keys
        self.counts["iso9283_figures"] = self.counts.get("iso9283_figures", 0) + len(rows)
        return len(rows)

    def add_verification(self, *, decision: str, statistic, dof: int, threshold, false_alarm_rate, n_poses: int,
                         rms_mm=None, max_mm=None, suspect: str | None = None, suspect_value=None,
                         suspect_unit: str | None = None, instrument: str | None = None, temperature_c=None,
                         model: str | None = None) -> None:
        """The outcome of one quick verification (``robocal verify``): the decision (``ok``,
        ``recalibrate``, ``mechanical fault suspected``), the chi-square statistic, its degrees of
        freedom and threshold [1], the false-alarm rate [1], the number of poses, residual RMS and
        max [mm], the suspected cause (``"J3 offset"``, ``"J2 backlash"``) with its size in
        ``suspect_unit`` (rad or mm), the instrument, the temperature [degC] and the calibration
        checked against. One per cycle."""
        self._check_open()
        if decision not in ("ok", "recalibrate", "mechanical fault suspected"):
            raise HistoryInputError(f"verification decision {decision!r} is not known")
        if self._verified:
            raise HistoryInputError("a verification was already added to this cycle")
        if isinstance(dof, bool) or not isinstance(dof, int) or dof < 1:
            raise HistoryInputError(f"verification dof must be a positive integer, got {dof!r}")
        if isinstance(n_poses, bool) or not isinstance(n_poses, int) or n_poses < 1:
            raise HistoryInputError(f"verification n_poses must be a positive integer, got {n_poses!r}")
        if suspect_unit is not None and suspect_unit not in ("rad", "mm"):
            raise HistoryInputError(f"verification suspect_unit must be 'rad' or 'mm', got {suspect_unit!r}")
        for name, text in (("suspect", suspect), ("instrument", instrument), ("model", model)):
            if text is not None and (not isinstance(text, str) or len(text) > 1000):
                raise HistoryInputError(f"verification {name} must be a string, got {text!r}")
        row = {"cycle_id": self.id, "decision": decision,
               "statistic": check_number(statistic, "verification statistic"), "dof": dof,
               "threshold": check_number(threshold, "verification threshold"),
               "false_alarm_rate": check_number(false_alarm_rate, "verification false_alarm_rate"),
               "n_poses": n_poses, "rms_mm": check_number(rms_mm, "verification rms_mm", allow_none=True),
               "max_mm": check_number(max_mm, "verification max_mm", allow_none=True), "suspect": suspect,
               "suspect_value": check_number(suspect_value, "verification suspect_value", allow_none=True),
               "suspect_unit": suspect_unit, "instrument": instrument,
               "temperature_c": check_number(temperature_c, "verification temperature_c", allow_none=True),
               "model": model}
        self._write(self._tx.insert, "verifications", row)
        self._verified = True
        self.counts["verifications"] = 1
