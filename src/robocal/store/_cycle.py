"""The transaction around one cycle: its checked start arguments, the ``cycles`` row inserted at
the start, the commit at the end, and the ``failed`` row recorded when the block raised.

Used by :meth:`robocal.store.HistoryStore.cycle`; the rows inside the cycle are written by
:class:`~._writer.CycleWriter`. Times are UTC.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from datetime import datetime

from ._backends import HistoryError
from ._validate import HistoryInputError, check_kind, check_robot_id, format_time, parse_time, to_json, utc_now

__all__ = ["CycleStart", "check_cycle_start", "begin_cycle", "commit_cycle", "record_failed"]


@dataclass(frozen=True)
class CycleStart:
    """The checked arguments of :meth:`HistoryStore.cycle`: robot id, kind, start time ``t0``,
    end time ``t1`` (None: at commit), notes, metadata as JSON text, robot model name."""

    robot: str
    kind: str
    t0: datetime
    t1: datetime | None
    notes: str | None
    meta_json: str
    robot_model: str | None


def check_cycle_start(robot, kind, started_at, finished_at, notes, meta, robot_model) -> CycleStart:
    """Validate the arguments of a new cycle (raises :class:`HistoryInputError` naming the bad one)."""
    robot = check_robot_id(robot)
    kind = check_kind(kind)
    t0 = utc_now() if started_at is None else parse_time(started_at, "started_at")
    t1 = None if finished_at is None else parse_time(finished_at, "finished_at")
    if notes is not None and not isinstance(notes, str):
        raise HistoryInputError(f"notes must be a string, got {type(notes).__name__}")
    if meta is not None and not isinstance(meta, dict):
        raise HistoryInputError(f"meta must be a dict, got {type(meta).__name__}")
    meta_json = to_json({} if meta is None else meta, "meta")
    if robot_model is not None and (not isinstance(robot_model, str) or not robot_model or len(robot_model) > 255):
        raise HistoryInputError(f"robot_model must be a non-empty string, got {robot_model!r}")
    return CycleStart(robot, kind, t0, t1, notes, meta_json, robot_model)


def robot_row_id(tx, robot: str, model: str | None) -> int:
    """The id of the robot's row, inserted if new; the model name is recorded the first time it
    is given and must match afterwards."""
    rows = tx.query("SELECT id, model FROM robots WHERE name = :n", {"n": robot})
    if rows:
        stored = rows[0]["model"]
        if model is not None and stored is not None and stored != model:
            raise HistoryInputError(f"robot {robot!r} is recorded as model {stored!r}, not {model!r}")
        if model is not None and stored is None:
            tx.execute("UPDATE robots SET model = :m WHERE id = :id", {"m": model, "id": rows[0]["id"]})
        return int(rows[0]["id"])
    return tx.insert("robots", {"name": robot, "model": model, "created_at": format_time(utc_now()), "notes": None})


def begin_cycle(backend, url: str, start: CycleStart):
    """Open a transaction and insert the cycle's row with status ``running``; returns ``(tx,
    cycle id)``. On any error the transaction is rolled back."""
    tx = backend.begin()
    try:
        robot_id = robot_row_id(tx, start.robot, start.robot_model)
        cid = tx.insert("cycles", {"robot_id": robot_id, "kind": start.kind, "status": "running",
                                   "started_at": format_time(start.t0), "finished_at": None, "notes": start.notes,
                                   "meta": start.meta_json})
    except BaseException as exc:
        tx.rollback()
        if isinstance(exc, backend.errors):
            raise HistoryError(f"cannot start a cycle in {url}: {str(exc).splitlines()[0]}") from exc
        raise
    return tx, cid


def commit_cycle(backend, url: str, tx, cycle_id: int, writer, t0: datetime) -> None:
    """Check the writer's end time and notes, mark the cycle ``committed`` and commit."""
    writer._check_open()
    t1 = writer.finished_at or utc_now()
    if t1 < t0:
        raise HistoryInputError(f"cycle finished_at {format_time(t1)} is before started_at {format_time(t0)}")
    if writer.notes is not None and not isinstance(writer.notes, str):
        raise HistoryInputError(f"notes must be a string, got {type(writer.notes).__name__}")
    try:
        tx.execute("UPDATE cycles SET status = :s, finished_at = :f, notes = :n WHERE id = :id",
                   {"s": "committed", "f": format_time(t1), "n": writer.notes, "id": cycle_id})
        tx.commit()
    except backend.errors as exc:
        raise HistoryError(f"cannot commit cycle to {url}: {str(exc).splitlines()[0]}") from exc
    writer.status = "committed"


def record_failed(backend, url: str, start: CycleStart, exc) -> int | None:
    """Record a cycle with status ``failed`` and the error ``exc`` in its notes, in a transaction
    of its own; returns its id, or None (with a ``RuntimeWarning``) if that fails too."""
    msg = f"failed: {type(exc).__name__}: {exc}"
    try:
        tx = backend.begin()
    except (HistoryError, *backend.errors):
        return None
    try:
        rid = robot_row_id(tx, start.robot, None)
        notes = start.notes
        cid = tx.insert("cycles", {"robot_id": rid, "kind": start.kind, "status": "failed",
                                   "started_at": format_time(start.t0),
                                   "finished_at": format_time(max(utc_now(), start.t0)),
                                   "notes": msg if not notes else f"{notes}\n{msg}", "meta": start.meta_json})
        tx.commit()
        return cid
    except Exception as exc2:  # the original error matters more; say why this one was lost
        try:
            tx.rollback()
        except Exception:
            pass
        warnings.warn(f"could not record the failed cycle in {url}: {exc2}", RuntimeWarning, stacklevel=3)
        return None
