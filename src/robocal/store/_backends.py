"""Two thin database drivers behind one small interface, so the store has one code path.

* :class:`SqliteBackend`: the standard library's ``sqlite3`` (no extra dependency): WAL journal,
  foreign keys on, ``synchronous=FULL``, writes under ``BEGIN IMMEDIATE``.
* :class:`SqlAlchemyBackend`: SQLAlchemy Core for server databases by URL (``postgresql://...``,
  ``mysql+pymysql://...``) and for ``sqlite+pysqlite://`` URLs; needs the ``db`` extra.

Both speak the same SQL: plain ``SELECT``/``UPDATE`` text with ``:name`` parameters (no dialect
features), inserts through :meth:`Tx.insert`, tables created from one schema description.
"""

from __future__ import annotations
from ..errors import RobocalError

import sqlite3
import time
from pathlib import Path
from . import _schema
from ._credentials import redact_url, with_credentials

__all__ = ["HistoryError", "HistoryBusyError", "open_backend", "redact_url"]

DB_EXTRA_HINT = "pip install 'robocal[db]'"


class HistoryError(RobocalError, RuntimeError):
    """The history database cannot be opened, read or written (the message says which database)."""


class HistoryBusyError(HistoryError):
    """Another writer held the database longer than the timeout."""


def _sqlite_path_from_url(url: str) -> str:
    """``sqlite:///rel.db`` -> ``rel.db``, ``sqlite:////abs.db`` -> ``/abs.db``, ``sqlite://`` and
    ``sqlite:///:memory:`` -> ``:memory:`` (SQLAlchemy's forms)."""
    rest = url[len("sqlite://"):]
    if "?" in rest:
        raise HistoryError(f"options in sqlite URLs are not supported: {url!r}")
    if rest in ("", "/", "/:memory:"):
        return ":memory:"
    if not rest.startswith("/"):
        raise HistoryError(f"sqlite URL {url!r} has a host part; write sqlite:///relative/path or sqlite:////absolute/path")
    return rest[1:]


def open_backend(target, *, create: bool, timeout: float):
    """A backend for a path or URL (see :meth:`robocal.store.HistoryStore.open`)."""
    if isinstance(target, Path):
        return SqliteBackend(str(target), create=create, timeout=timeout)
    if not isinstance(target, str) or not target:
        raise HistoryError(f"history database must be a path or a URL, got {target!r}")
    if "://" not in target:
        return SqliteBackend(target, create=create, timeout=timeout)
    scheme = target.split("://", 1)[0].lower()
    if scheme == "sqlite":
        return SqliteBackend(_sqlite_path_from_url(target), create=create, timeout=timeout)
    return SqlAlchemyBackend(target, create=create, timeout=timeout)


# -- sqlite3 -------------------------------------------------------------------------------------

class _SqliteTx:
    def __init__(self, backend):
        self.b = backend
        self.conn = backend.conn

    def insert(self, table: str, row: dict) -> int | None:
        cols = list(row)
        cur = self.conn.execute(
            f"INSERT INTO {table} ({', '.join(cols)}) VALUES ({', '.join(':' + c for c in cols)})", row)
        return int(cur.lastrowid)

    def insert_many(self, table: str, rows: list) -> None:
        if not rows:
            return
        cols = list(rows[0])
        self.conn.executemany(
            f"INSERT INTO {table} ({', '.join(cols)}) VALUES ({', '.join(':' + c for c in cols)})", rows)

    def execute(self, sql: str, params: dict | None = None) -> int:
        return self.conn.execute(sql, params or {}).rowcount

    def query(self, sql: str, params: dict | None = None) -> list:
        return [dict(r) for r in self.conn.execute(sql, params or {}).fetchall()]

    def create_tables(self, tabs) -> None:
        for tab in tabs:
            for stmt in _schema.sqlite_ddl(tab):
                self.conn.execute(stmt)

    def commit(self) -> None:
        self.conn.execute("COMMIT")

    def rollback(self) -> None:
        if self.conn.in_transaction:
            self.conn.execute("ROLLBACK")


def _is_busy(exc: sqlite3.Error) -> bool:
    """True for SQLITE_BUSY (any extended code): another connection holds a lock we need."""
    code = getattr(exc, "sqlite_errorcode", None)
    if code is not None:
        return code & 0xFF == sqlite3.SQLITE_BUSY
    return "database is locked" in str(exc)


def switch_to_wal(conn, timeout: float) -> str:
    """``PRAGMA journal_mode = WAL`` on the DB-API ``sqlite3`` connection ``conn``, retried while
    SQLITE_BUSY for up to ``timeout`` [s]; returns the journal mode now in force.

    Switching a database that is not in WAL mode yet (a fresh file) writes its header from
    inside a read transaction; when another connection holds the file's write lock (another
    first open doing the same switch, fleet workers racing), SQLite returns SQLITE_BUSY at once,
    WITHOUT calling the busy handler, since waiting while holding a read lock could deadlock.
    SQLite's remedy is to end the statement and try again, which this does with a short
    back-off until ``timeout`` has passed (then the last SQLITE_BUSY is raised).
    """
    deadline = time.monotonic() + timeout
    pause = 0.001
    while True:
        try:
            return conn.execute("PRAGMA journal_mode = WAL").fetchone()[0]
        except sqlite3.OperationalError as exc:
            left = deadline - time.monotonic()
            if not _is_busy(exc) or left <= 0:
                raise
        time.sleep(min(pause, left))
        pause = min(2 * pause, 0.05)


class SqliteBackend:
    """``sqlite3`` in autocommit mode; each write transaction is an explicit ``BEGIN IMMEDIATE``."""

    dialect = "sqlite"
    errors = (sqlite3.Error,)

    def __init__(self, path: str, *, create: bool, timeout: float):
        self.path = path
        self.display = path
        if path != ":memory:":
            p = Path(path)
            if p.is_dir():
                raise HistoryError(f"history database {path} is a folder, not a file")
            if not create and p.is_file() and p.stat().st_size == 0:  # reading must not write a schema into it
                raise HistoryError(f"history database {path} is an empty file: no history recorded yet")
            if not p.exists():
                if not create:
                    raise HistoryError(f"no history database at {path}")
                if not p.parent.exists():
                    raise HistoryError(f"cannot create history database {path}: folder {p.parent} does not exist")
        try:
            self.conn = sqlite3.connect(path, timeout=timeout, isolation_level=None)
        except sqlite3.Error as exc:
            raise HistoryError(f"cannot open history database {path}: {exc}") from None
        self.conn.row_factory = sqlite3.Row
        try:
            self.conn.execute("PRAGMA foreign_keys = ON")
            self.journal_mode = switch_to_wal(self.conn, timeout)
            self.conn.execute("PRAGMA synchronous = FULL")
        except sqlite3.DatabaseError as exc:
            self.conn.close()
            if _is_busy(exc):
                raise HistoryBusyError(f"history database {path} stayed locked by another connection for "
                                       f"{timeout:g} s while being opened ({exc})") from None
            raise HistoryError(f"{path} is not an SQLite database ({exc})") from None

    def begin(self) -> _SqliteTx:
        try:
            self.conn.execute("BEGIN IMMEDIATE")
        except sqlite3.OperationalError as exc:
            if "locked" in str(exc) or "busy" in str(exc):
                raise HistoryBusyError(
                    f"history database {self.display} is being written by another process (waited for it: {exc})") from None
            raise HistoryError(f"cannot write history database {self.display}: {exc}") from None
        return _SqliteTx(self)

    def read(self, sql: str, params: dict | None = None) -> list:
        return [dict(r) for r in self.conn.execute(sql, params or {}).fetchall()]

    def table_names(self) -> set:
        return {r["name"] for r in self.read("SELECT name FROM sqlite_master WHERE type = 'table'")}

    def integrity_problems(self) -> list:
        rows = self.conn.execute("PRAGMA integrity_check").fetchall()
        problems = [r[0] for r in rows if r[0] != "ok"]
        problems += [f"foreign key: {tuple(r)}" for r in self.conn.execute("PRAGMA foreign_key_check").fetchall()]
        return problems

    def close(self) -> None:
        self.conn.close()


# -- SQLAlchemy Core -----------------------------------------------------------------------------

def _import_sqlalchemy(url_display: str):
    try:
        import sqlalchemy as sa
    except ImportError:
        raise HistoryError(
            f"history database {url_display} needs SQLAlchemy (the 'db' extra: {DB_EXTRA_HINT}); "
            "without it only SQLite files (a path or sqlite:///path) are supported") from None
    if int(sa.__version__.split(".")[0]) < 2:
        raise HistoryError(f"history database {url_display} needs SQLAlchemy >= 2.0, found {sa.__version__} ({DB_EXTRA_HINT})")
    return sa


class _SaTx:
    def __init__(self, backend, conn, trans):
        self.b = backend
        self.conn = conn
        self.trans = trans

    def insert(self, table: str, row: dict) -> int | None:
        res = self.conn.execute(self.b.tables[table].insert().values(**row))
        pk = res.inserted_primary_key
        return int(pk[0]) if pk and pk[0] is not None else None

    def insert_many(self, table: str, rows: list) -> None:
        if rows:
            self.conn.execute(self.b.tables[table].insert(), rows)

    def execute(self, sql: str, params: dict | None = None) -> int:
        return self.conn.execute(self.b.sa.text(sql), params or {}).rowcount

    def query(self, sql: str, params: dict | None = None) -> list:
        return [dict(r) for r in self.conn.execute(self.b.sa.text(sql), params or {}).mappings().all()]

    def create_tables(self, tabs) -> None:
        tables = _schema.sqlalchemy_tables(self.b.sa, self.b.metadata, tabs)
        self.b.metadata.create_all(self.conn, tables=list(tables.values()))

    def commit(self) -> None:
        try:
            self.trans.commit()
        finally:
            self.conn.close()

    def rollback(self) -> None:
        try:
            if self.trans.is_active:
                self.trans.rollback()
        finally:
            self.conn.close()


class SqlAlchemyBackend:
    """SQLAlchemy Core engine; one pooled connection per write transaction and per read."""

    def __init__(self, url: str, *, create: bool, timeout: float):
        self.display = redact_url(url)
        sa = self.sa = _import_sqlalchemy(self.display)
        self.errors = (sa.exc.SQLAlchemyError,)
        try:
            self.engine = sa.create_engine(with_credentials(url), pool_pre_ping=True)
        except sa.exc.NoSuchModuleError:
            raise HistoryError(f"history database {self.display}: SQLAlchemy knows no database kind "
                               f"{url.split('://', 1)[0]!r} (e.g. postgresql+psycopg://, mysql+pymysql://)") from None
        except ImportError as exc:
            raise HistoryError(f"history database {self.display}: its database driver is not installed ({exc}); "
                               "install the driver package for this URL") from None
        except (sa.exc.ArgumentError, ValueError) as exc:
            raise HistoryError(f"history database URL {self.display} is not valid ({exc})") from None
        self.dialect = self.engine.dialect.name
        if self.dialect == "sqlite":
            self._sqlite_setup(timeout)
        self.metadata = sa.MetaData()
        self.tables = _schema.sqlalchemy_tables(sa, self.metadata, _schema.ALL_TABLES.values())
        try:
            with self.engine.connect():
                pass
        except sa.exc.SQLAlchemyError as exc:
            raise HistoryError(f"cannot connect to history database {self.display}: {str(exc).splitlines()[0]}") from None

    def _sqlite_setup(self, timeout: float) -> None:
        # SQLAlchemy's documented recipe: let the driver stay in autocommit and emit BEGIN ourselves,
        # so a write transaction takes the lock up front (BEGIN IMMEDIATE) as in the sqlite3 backend.
        sa = self.sa

        @sa.event.listens_for(self.engine, "connect")
        def _connect(dbapi_conn, _record):
            dbapi_conn.isolation_level = None
            cur = dbapi_conn.cursor()
            cur.execute("PRAGMA foreign_keys = ON")
            cur.execute(f"PRAGMA busy_timeout = {int(timeout * 1000)}")
            if self.engine.url.database not in (None, "", ":memory:"):
                switch_to_wal(dbapi_conn, timeout)  # a fresh file's first opens race (SQLITE_BUSY, no busy handler)
                cur.execute("PRAGMA synchronous = FULL")
            cur.close()

        @sa.event.listens_for(self.engine, "begin")
        def _begin(conn):
            conn.exec_driver_sql("BEGIN IMMEDIATE" if conn.info.get("robocal_write") else "BEGIN")

    def begin(self) -> _SaTx:
        sa = self.sa
        conn = None
        try:
            conn = self.engine.connect()
            conn.info["robocal_write"] = True
            trans = conn.begin()
            conn.info["robocal_write"] = False
        except sa.exc.OperationalError as exc:
            if conn is not None:
                conn.info["robocal_write"] = False
                conn.close()
            msg = str(exc).splitlines()[0]
            if "locked" in msg or "busy" in msg:
                raise HistoryBusyError(f"history database {self.display} is being written by another process ({msg})") from None
            raise HistoryError(f"cannot write history database {self.display}: {msg}") from None
        return _SaTx(self, conn, trans)

    def read(self, sql: str, params: dict | None = None) -> list:
        with self.engine.connect() as conn:
            return [dict(r) for r in conn.execute(self.sa.text(sql), params or {}).mappings().all()]

    def table_names(self) -> set:
        return set(self.sa.inspect(self.engine).get_table_names())

    def integrity_problems(self) -> list:
        if self.dialect != "sqlite":
            return []
        rows = self.read("PRAGMA integrity_check")
        problems = [next(iter(r.values())) for r in rows if next(iter(r.values())) != "ok"]
        problems += [f"foreign key: {tuple(r.values())}" for r in self.read("PRAGMA foreign_key_check")]
        return problems

    def close(self) -> None:
        self.engine.dispose()
