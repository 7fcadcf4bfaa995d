"""Bringing a history database to this robocal's schema on open (see :mod:`._schema`).

An empty database gets every table; an older one the migrations it lacks, in one transaction; a
database of another application, or of a newer robocal, is refused with :class:`HistoryError`.
"""

from __future__ import annotations

from . import _schema
from ._backends import HistoryError
from ._validate import format_time, utc_now

__all__ = ["migrate", "stored_version"]

#: PostgreSQL advisory lock key taken while migrating (an arbitrary constant: "robocal" in ASCII).
_MIGRATION_LOCK = 0x726F626F63616C


def stored_version(backend) -> int:
    """The highest schema version recorded in the database (0 if none)."""
    return int(backend.read("SELECT MAX(version) AS v FROM schema_version")[0]["v"] or 0)


def _check_version_not_newer(backend, url: str) -> None:
    v = stored_version(backend)
    if v > _schema.SCHEMA_VERSION:
        backend.close()
        raise HistoryError(f"history database {url} has schema version {v}, newer than this robocal "
                           f"understands ({_schema.SCHEMA_VERSION}); upgrade robocal")


def _table_names(backend, url: str) -> set:
    try:
        return backend.table_names()
    except backend.errors as exc:
        backend.close()
        raise HistoryError(f"cannot read history database {url}: {str(exc).splitlines()[0]}") from None


def _apply_missing(backend) -> None:
    """Create the version table and apply every migration newer than the stored version, in one
    transaction (closed and re-raised on any error)."""
    tx = backend.begin()
    try:
        if backend.dialect == "postgresql":
            # concurrent first opens (fleet workers) must not both create the tables: a lock held to
            # the end of this transaction serialises them (SQLite's BEGIN IMMEDIATE already does)
            tx.execute("SELECT pg_advisory_xact_lock(:key)", {"key": _MIGRATION_LOCK})
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
        backend.close()
        raise


def migrate(backend, url: str) -> None:
    """Check that ``backend`` holds a robocal history database (or none yet) and bring it to
    :data:`~._schema.SCHEMA_VERSION`. ``url`` (for messages) is the redacted target."""
    names = _table_names(backend, url)
    # an SQLite file belongs to one application; a server database may hold other tables, just
    # not ones with our names
    clash = names if backend.dialect == "sqlite" else names & set(_schema.ALL_TABLES)
    if "schema_version" not in names and clash:
        backend.close()
        raise HistoryError(f"{url} is not a robocal history database (it has tables {', '.join(sorted(clash))} "
                           "but no schema_version)")
    if "schema_version" in names and stored_version(backend) >= _schema.SCHEMA_VERSION:
        _check_version_not_newer(backend, url)
        return
    _apply_missing(backend)
    _check_version_not_newer(backend, url)
