"""Issue 29, the fleet's trust boundary: database credentials never travel in task payloads or
appear in JSON and errors (query-string passwords masked like user:pass@), the password comes
from the environment or a file where the database is opened; --scheduler takes Dask TLS
settings; robot ids from the data never build a path outside the output folder."""

from __future__ import annotations

import sqlite3
from datetime import datetime, timedelta, timezone

import pytest
from click.testing import CliRunner

from robocal.cli.main import main
from robocal.io.output_paths import PathEscapeError, path_under, safe_file_stem
from robocal.store import (
    PASSWORD_ENV,
    PASSWORD_FILE_ENV,
    HistoryInputError,
    HistoryStore,
    redact_url,
    strip_credentials,
    url_password,
    with_credentials,
)

URL = "postgresql+psycopg://cal@db.plant:5432/history"


@pytest.mark.parametrize("url", ["postgresql+psycopg://cal:s3cr%40t@db.plant:5432/history?sslmode=require",
                                 f"{URL}?password=s3cr%40t&sslmode=require",
                                 f"{URL}?sslmode=require&PWD=s3cr%40t"])
def test_passwords_are_masked_and_stripped_wherever_they_sit(url):
    assert url_password(url) == "s3cr@t"
    shown = redact_url(url)
    assert "s3cr" not in shown and "***" in shown and "sslmode=require" in shown
    bare = strip_credentials(url)
    assert "s3cr" not in bare and "***" not in bare and url_password(bare) is None
    assert bare.startswith("postgresql+psycopg://cal@db.plant:5432/history") and "sslmode=require" in bare


def test_the_password_comes_from_the_environment_or_a_file(tmp_path, monkeypatch):
    monkeypatch.delenv(PASSWORD_ENV, raising=False)
    monkeypatch.delenv(PASSWORD_FILE_ENV, raising=False)
    assert with_credentials(URL) == URL
    (tmp_path / "pw").write_text("fr0m f1le\n")
    monkeypatch.setenv(PASSWORD_FILE_ENV, str(tmp_path / "pw"))
    assert url_password(with_credentials(URL)) == "fr0m f1le"
    monkeypatch.setenv(PASSWORD_ENV, "env:pw")
    assert url_password(with_credentials(URL)) == "env:pw"
    assert with_credentials(f"{URL}?password=given") == f"{URL}?password=given"  # an explicit one stays


def test_a_password_in_the_url_never_goes_to_a_remote_cluster(tmp_path):
    (tmp_path / "fleet.toml").write_text('[[robot]]\nid = "a"\nmodel = "ur10"\nmeasurements = "m.csv"\n')
    r = CliRunner().invoke(main, ["fleet", "calibrate", str(tmp_path / "fleet.toml"), "--out", str(tmp_path / "o"),
                                  "--scheduler", "tcp://127.0.0.1:9", "--db", f"{URL}?password=s3cret"])
    assert r.exit_code == 1 and "ROBOCAL_DB_PASSWORD" in r.output and "s3cret" not in r.output


def test_the_library_refuses_a_password_bound_for_workers(tmp_path):
    from robocal.workflows.fleet.calibrate import run_fleet_calibration

    (tmp_path / "fleet.toml").write_text('[[robot]]\nid = "a"\nmodel = "ur10"\nmeasurements = "m.csv"\n')
    with pytest.raises(ValueError, match="ROBOCAL_DB_PASSWORD") as info:
        run_fleet_calibration(tmp_path / "fleet.toml", tmp_path / "o", client=object(), db=f"{URL}?password=s3cret")
    assert "s3cret" not in str(info.value)


def test_tls_settings_for_the_scheduler(tmp_path):
    from robocal.workflows.fleet.cluster import FleetClusterError, fleet_client, tls_security

    assert tls_security() is None
    for name in ("ca.pem", "client.pem", "client.key"):
        (tmp_path / name).write_text("-----BEGIN CERTIFICATE-----\n")
    with pytest.raises(FleetClusterError, match="no such file"):
        tls_security(ca_file=tmp_path / "missing.pem", cert=tmp_path / "client.pem")
    (tmp_path / "security.toml").write_text('[tls]\nca_file = "ca.pem"\ncert = "client.pem"\nkey = "client.key"\n')
    sec = tls_security(security_file=tmp_path / "security.toml")
    assert sec.require_encryption and sec.tls_ca_file == str(tmp_path / "ca.pem")
    assert sec.tls_client_key == str(tmp_path / "client.key")
    with pytest.raises(FleetClusterError, match="tls://"):
        with fleet_client("tcp://127.0.0.1:9", security=sec):
            pass
    r = CliRunner().invoke(main, ["fleet", "study", "pose-sets", "ur10", "--scheduler", "tcp://127.0.0.1:9",
                                  "--security", str(tmp_path / "security.toml")])
    assert r.exit_code == 1 and "tls://" in r.output and "Traceback" not in r.output


def test_ids_from_the_data_never_leave_the_plot_folder(tmp_path):
    """A history whose robot names were written by other software: '../escaped' and 'line1/cell3'.
    The status run completes, every plot lands inside --plots."""
    from robocal.workflows.fleet.status import fleet_status

    db = tmp_path / "h.sqlite"
    now = datetime(2026, 6, 1, tzinfo=timezone.utc)
    with HistoryStore.open(db) as store:
        for robot in ("r1", "r2", "line1/cell3"):
            for d, v in ((300, 0.1), (250, 0.5), (200, 0.9)):
                t = now - timedelta(days=d)
                with store.cycle(robot, "geometric_calibration", started_at=t, finished_at=t) as c:
                    c.add_parameters(["a2"], [v], units=["mm"])
    with sqlite3.connect(db) as conn:
        conn.execute("UPDATE robots SET name = '../escaped' WHERE name = 'r2'")
    r = fleet_status(str(db), now=now, plot_dir=tmp_path / "plots")
    rows = {row["robot"]: row for row in r["robots"]}
    assert "cannot be checked" in rows["../escaped"]["reasons"][0] and "../escaped" in r["flagged"]
    plots = [row["plot"] for row in r["robots"] if row.get("plot")]
    assert len(plots) == 2 and not (tmp_path / "escaped_drift.png").exists()
    assert all((tmp_path / "plots") in __import__("pathlib").Path(p).parents for p in plots)
    with pytest.raises(HistoryInputError, match="'..'"):
        with HistoryStore.open(db) as store, store.cycle("a/../b", "geometric_calibration"):
            pass
    assert safe_file_stem("line1/cell3") != safe_file_stem("line1_cell3")
    with pytest.raises(PathEscapeError):
        path_under(tmp_path / "plots", "../x.png")
