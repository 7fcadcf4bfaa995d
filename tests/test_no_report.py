"""``robocal calibrate --no-report``: the same results without report.html (batch runs)."""

import json

from click.testing import CliRunner

from robocal.cli import main


def test_no_report_writes_the_results_but_no_report(tmp_path):
    data = tmp_path / "m.csv"
    r = CliRunner().invoke(main, ["simulate", "tracker", "abb_irb140", "--poses", "40", "--out", str(data)])
    assert r.exit_code == 0, r.output
    (tmp_path / "out").mkdir()
    (tmp_path / "out" / "report.html").write_text("an earlier report, left alone")
    r = CliRunner().invoke(main, ["calibrate", "abb_irb140", str(data), "--out", str(tmp_path / "out"), "--no-report"])
    assert r.exit_code == 0, r.output
    assert "report.html" not in r.output
    assert (tmp_path / "out" / "report.html").read_text() == "an earlier report, left alone"
    res = json.loads((tmp_path / "out" / "result.json").read_text())
    assert res["solver"]["converged"]
