"""Shared fixtures: a real PostgreSQL server for the history tests.

``server_db_url`` is ``$ROBOCAL_TEST_DB_URL`` when set (a server the user runs); otherwise the test
suite starts its own PostgreSQL server once per session from the ``pgserver`` package (a pip
wheel with the PostgreSQL binaries; the ``test`` extra), in a private temporary folder, reached over a
Unix socket, and stops it at the end. When neither works the tests that need it are skipped
with the reason.

``fresh_server_db`` gives each test its own, empty schema on that server (``CREATE SCHEMA``),
so tests never see each other's rows.

One BLAS thread for the whole session: the suite's linear algebra is on small matrices (tens of
columns), where OpenBLAS's thread pool costs more than it gains, and on the shared 2-core CI
machine it can turn a 10 ms QR into ~1 s under load (measured in the hand-eye tests: 68 s wall
against 11 s). Set before any test module imports numpy (pytest loads this file first); a user's
explicit setting is kept; numba's own threads (NUMBA_NUM_THREADS) are left alone.
"""

from __future__ import annotations

import itertools
import os
import shutil
import tempfile

import pytest

for _var in ("OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

_DRIVER = "postgresql+psycopg://"
_counter = itertools.count()


def _with_driver(url: str) -> str:
    """pgserver's ``postgresql://...`` URL with the psycopg (3) driver named for SQLAlchemy."""
    return _DRIVER + url.split("://", 1)[1] if url.startswith("postgresql://") else url


@pytest.fixture(scope="session")
def server_db_url():
    """URL of a running PostgreSQL server (see the module docstring); skips with the reason if none."""
    given = os.environ.get("ROBOCAL_TEST_DB_URL")
    if given:
        yield given
        return
    try:
        import pgserver
    except ImportError as exc:
        pytest.skip(f"no server database: set ROBOCAL_TEST_DB_URL or install pgserver (the test extra): {exc}")
    # a private folder, not pytest's numbered basetemp: concurrent pytest runs on a shared machine
    # rotate those folders away (and the server's files with them)
    data = tempfile.mkdtemp(prefix="robocal-pg-")
    try:
        server = pgserver.get_server(data, cleanup_mode="stop")
    except Exception as exc:  # any failure to start (binaries, permissions, sockets) skips with its reason
        shutil.rmtree(data, ignore_errors=True)
        pytest.skip(f"the PostgreSQL server from pgserver could not start: {type(exc).__name__}: {exc}")
    url = _with_driver(server.get_uri())
    try:
        _throwaway_settings(url)
        yield url
    finally:
        server.cleanup()
        shutil.rmtree(data, ignore_errors=True)


def _throwaway_settings(url: str) -> None:
    """The suite's own server holds nothing worth keeping: no fsync (halves the time per test)."""
    import sqlalchemy as sa

    engine = sa.create_engine(url, isolation_level="AUTOCOMMIT")
    try:
        with engine.connect() as conn:
            for setting in ("fsync = off", "synchronous_commit = off", "full_page_writes = off"):
                conn.execute(sa.text(f"ALTER SYSTEM SET {setting}"))
            conn.execute(sa.text("SELECT pg_reload_conf()"))
    finally:
        engine.dispose()


@pytest.fixture(scope="session")
def _server_admin(server_db_url):
    """One autocommit engine on the server for creating and dropping the tests' schemas."""
    import sqlalchemy as sa

    engine = sa.create_engine(server_db_url, isolation_level="AUTOCOMMIT")
    yield engine
    engine.dispose()


def _schema_url(url: str, schema: str) -> str:
    """``url`` whose connections work in ``schema`` (PostgreSQL ``search_path``; other query
    parameters, e.g. ``?host=/socket/dir``, kept)."""
    import sqlalchemy as sa

    u = sa.engine.make_url(url)
    return u.update_query_dict({"options": f"-csearch_path={schema}"}).render_as_string(hide_password=False)


@pytest.fixture
def fresh_server_db(_server_admin):
    """URL of a new, empty schema on the test server (a schema costs milliseconds, a database
    about a second); dropped with everything in it after the test."""
    import sqlalchemy as sa

    name = f"robocal_t{os.getpid()}_{next(_counter)}"
    admin = _server_admin
    try:
        with admin.connect() as conn:
            conn.execute(sa.text(f'CREATE SCHEMA "{name}"'))
    except sa.exc.SQLAlchemyError as exc:
        pytest.skip(f"cannot create a test schema on the server database: {str(exc).splitlines()[0]}")
    try:
        yield _schema_url(admin.url.render_as_string(hide_password=False), name)
    finally:
        with admin.connect() as conn:
            conn.execute(sa.text(f'DROP SCHEMA IF EXISTS "{name}" CASCADE'))


@pytest.fixture
def lm_one_iteration(monkeypatch):
    """Every Levenberg-Marquardt solve of the calibration core stops after one iteration: a fit that
    does not converge, for the tests of the convergence policy (exit code 4, no model file)."""
    from robocal.calib._iterate import DampedGaussNewton

    # the Python loop (the compiled loop's own cap is tested in tests/test_compiled_lm.py)
    monkeypatch.setenv("ROBOCAL_COMPILED_LM", "never")

    run_phase = DampedGaussNewton.run_phase
    monkeypatch.setattr(DampedGaussNewton, "run_phase", lambda self, first, _max: run_phase(self, first, 1))
