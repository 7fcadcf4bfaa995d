"""The history of calibration and maintenance cycles in a real database.

One cycle (a geometric calibration, a thermal compensation, a tool recalibration, a plain
measurement) is one database transaction::

    store = HistoryStore.open("history.sqlite")           # or "sqlite:///path", "postgresql://..."
    with store.cycle("cell3-kr150", "thermal_compensation") as c:
        c.add_measurements(joints_rad, sphere_mm, target="sphere", sensor="stereo")
        c.add_parameters(["a2", "beta2"], [0.031, 2.1e-5], units=["mm", "rad"])
        c.add_metric("lambda", 96.0, "%")
        c.add_corrections(q_taught, q_corrected, program="body_side")
    # committed here, all rows at once; an exception inside the block rolls all of them back

Every number is stored in millimetres or radians with its unit; every time is UTC. A process
killed inside the block leaves nothing of that cycle behind and every committed cycle intact
(SQLite's write-ahead log is rolled back on the next open). Readers never see a cycle that is
still being written.
"""

from __future__ import annotations

from contextlib import contextmanager

from ._backends import HistoryBusyError, HistoryError, open_backend
from ._cycle import begin_cycle, check_cycle_start, commit_cycle, record_failed
from ._migrate import migrate, stored_version
from ._queries import HistoryQueries
from ._records import (
    CycleRecord, HistoryLookupError, ParameterRow, Quantity, Series, StoredCycle, UnknownRobotError,
)
from ._validate import HistoryInputError, check_number
from ._writer import CycleWriter

__all__ = [
    "CycleRecord", "CycleWriter", "HistoryBusyError", "HistoryError", "HistoryInputError", "HistoryLookupError",
    "HistoryStore", "ParameterRow", "Quantity", "Series", "StoredCycle", "UnknownRobotError",
]


class HistoryStore(HistoryQueries):
    """The history database. Open with :meth:`open`; not shared between threads (open one store
    per thread or process: each has its own connection).

    Writing is :meth:`cycle`; reading (:meth:`robots`, :meth:`cycles`, :meth:`parameter_history`,
    :meth:`metric_history`, :meth:`load_cycle`, ...) comes from :class:`~._queries.HistoryQueries`.
    """

    def __init__(self, backend):
        self._backend = backend
        self._open_cycle = None
        self.url = backend.display
        migrate(backend, self.url)

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

    @property
    def schema_version(self) -> int:
        return stored_version(self._backend)

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
        start = check_cycle_start(robot, kind, started_at, finished_at, notes, meta, robot_model)
        if self._open_cycle is not None:
            raise HistoryError(f"cycle {self._open_cycle.id} is still open on this store; finish it before starting another")
        b = self._backend
        tx, cid = begin_cycle(b, self.url, start)
        w = CycleWriter(self, tx, cid, start.robot, start.kind, start.t0, start.t1, start.notes)
        self._open_cycle = w
        try:
            yield w
            commit_cycle(b, self.url, tx, cid, w, start.t0)
        except BaseException as exc:
            w.status = "failed"
            try:
                tx.rollback()
            except b.errors:
                pass
            if record_failure and isinstance(exc, (Exception, KeyboardInterrupt)) and not isinstance(exc, HistoryBusyError):
                w.id = record_failed(b, self.url, start, exc)
            raise
        finally:
            self._open_cycle = None
