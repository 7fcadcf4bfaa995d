"""`robocal import`: a Leica-style export (semicolon, decimal comma, metres, Latin-1) and a
controller joint log with its own joint names become a measurement file that calibrates to the
same result as the original campaign."""

from __future__ import annotations

import json

import numpy as np
import pytest
from click.testing import CliRunner

from robocal.cli import main
from robocal.io.measurements import read_measurements
from robocal.robots import load_robot


def _run(args):
    result = CliRunner().invoke(main, [str(a) for a in args])
    return result.exit_code, result.output


@pytest.fixture(scope="module")
def campaign(tmp_path_factory):
    d = tmp_path_factory.mktemp("import")
    code, out = _run(["simulate", "tracker", "ur10", "--poses", 40, "--seed", 3, "--out", d / "orig.csv"])
    assert code == 0, out
    meas = read_measurements(d / "orig.csv", load_robot("ur10"))
    ids = [f"P{int(p):03d}" for p in meas.pose_ids]
    pts_m = meas.points[:, 0] / 1000.0
    lines = ["Leica Tracker Pilot export", "Einheit: m", "", "Name;X [m];Y [m];Z [m]"]
    lines += [f"{i};" + ";".join(f"{v:.9f}".replace(".", ",") for v in p) for i, p in zip(ids, pts_m)]
    (d / "leica.csv").write_bytes(("\r\n".join(lines) + "\r\n").encode("latin-1"))
    q_deg = np.degrees(meas.joints)
    log = ["id,A1,A2,A3,A4,A5,A6"] + [f"{int(p)}," + ",".join(f"{v:.10f}" for v in q) for p, q in zip(meas.pose_ids, q_deg)]
    (d / "log.csv").write_text("\n".join(log) + "\n", encoding="utf-8")
    return d, meas


def test_import_then_calibrate_matches_the_original(campaign):
    d, meas = campaign
    code, out = _run(["import", "ur10", d / "leica.csv", "--joints", d / "log.csv", "--angle-unit", "deg",
                      "--pair", "id", "--id-match", "number", "--out", d / "imported.csv"])
    assert code == 0, out
    assert "40 pose(s) paired" in out
    assert "A1, A2, A3, A4, A5, A6 taken as J1, J2, J3, J4, J5, J6" in out
    imported = read_measurements(d / "imported.csv", load_robot("ur10"))
    assert np.max(np.abs(imported.points - meas.points)) < 1e-5          # mm, from 1e-9 m in the export
    assert np.max(np.abs(imported.joints - meas.joints)) < 1e-9          # rad
    results = {}
    for name in ("orig", "imported"):
        code, out = _run(["calibrate", "ur10", d / f"{name}.csv", "--out", d / f"cal-{name}", "--holdout", 0.2,
                          "--seed", 1])
        assert code == 0, out
        results[name] = json.loads((d / f"cal-{name}" / "result.json").read_text())
    a, b = (results[k]["validation"]["after"]["rms"] for k in ("orig", "imported"))
    assert a < 0.1 and abs(a - b) < 1e-4


def test_import_errors_name_the_problem(campaign):
    d, _ = campaign
    code, out = _run(["import", "ur10", d / "leica.csv", "--joints", d / "log.csv", "--angle-unit", "deg",
                      "--pair", "time", "--out", d / "x.csv"])
    assert code != 0 and "Error:" in out and "time" in out
    code, out = _run(["import", "ur10", d / "leica.csv", "--joints", d / "log.csv", "--angle-unit", "deg",
                      "--out", d / "orig.csv"])
    assert code != 0 and "exists" in out
