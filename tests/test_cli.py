"""The command line: reference outputs and one-line errors with non-zero exit codes."""

import json

import numpy as np
import pytest
from click.testing import CliRunner

from robocal.cli import main


def run(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


def test_fk_json_bx200l_acceptance_command():
    r = run("fk", "kawasaki_bx200l", "--deg", 90, 0, 0, 0, 0, 0, "--json")
    assert r.exit_code == 0, r.output
    out = json.loads(r.output)
    assert np.allclose(out["position_mm"], [1675.0, 0.0, 1920.0], atol=1e-9)
    assert np.allclose(out["rotation"], [[0, 0, 1], [-1, 0, 0], [0, -1, 0]], atol=1e-12)


def test_fk_radians_and_euler():
    r = run("fk", "ur10", 0, 0, 0, 0, 0, 0, "--orientation", "kuka_abc", "--json")
    out = json.loads(r.output)
    assert np.allclose(out["position_mm"], [-1184.3, -256.141, 11.6])
    # zero-pose rotation of the UR10 is Rx(+90 deg): KUKA A, B, C = 0, 0, 90
    assert np.allclose(out["orientation"]["values"], [0.0, 0.0, 90.0], atol=1e-9)


@pytest.mark.parametrize("args, message", [
    (("fk", "ur01", 0, 0, 0, 0, 0, 0), "Did you mean: ur10"),
    (("fk", "ur10", 1, 2, 3), "ur10 has 6 joints"),
    (("fk", "ur10", 1, 2, "x", 3, 4, 5), "joint 3: 'x' is not a number"),
    (("fk", "ur10", 1, 2, "nan", 3, 4, 5), "joint 3: 'nan' is not a finite number"),
    (("fk", "kuka_kr150_r3100", "--deg", 0, -150, 0, 0, 0, 0), "joint A2 = -150 deg is outside its limits"),
    (("fk", "ur10", 0, 0, 0, 0, 0, 0, "--orientation", "kuka"), "kuka"),
    (("ik", "ur10", 1, 2, 3), "POSE needs 6 values"),
])
def test_bad_input_gives_one_clear_line(args, message):
    r = run(*args)
    assert r.exit_code != 0
    lines = [l for l in r.output.strip().splitlines() if l]
    assert len(lines) == 1 and lines[0].startswith("Error:"), r.output
    assert message in lines[0]


def test_ik_numeric_recovers_fk_pose():
    q = np.radians([20.0, -70.0, 80.0, 10.0, 30.0, -40.0])
    fk = json.loads(run("fk", "kuka_kr150_r3100", *q, "--orientation", "kuka_abc", "--json").output)
    pose = fk["position_mm"] + fk["orientation"]["values"]
    start = ",".join(str(v) for v in q + 0.05)
    r = run("ik", "kuka_kr150_r3100", *pose, "--start", start, "--json")
    assert r.exit_code == 0, r.output
    sol = json.loads(r.output)["solutions"][0]["joints"]
    assert np.allclose(sol, q, atol=1e-7)


def test_robots_lists_the_library():
    out = json.loads(run("robots", "--json").output)
    names = {r["name"] for r in out}
    assert {"ur10", "kawasaki_bx200l", "kuka_kr150_r3100", "abb_irb140", "fanuc_r2000ic_165f",
            "dlr_justin19", "hilti_trailblazer"} <= names


def test_demo_runs_the_maintenance_cycle(tmp_path):
    r = run("demo", "--out", tmp_path / "d", "--poses", 200, "--seed", 3)
    assert r.exit_code == 0, r.output
    res = json.loads((tmp_path / "d" / "demo_result.json").read_text())
    assert (tmp_path / "d" / "accuracy_map.png").stat().st_size > 10_000
    assert (tmp_path / "d" / "report.html").stat().st_size > 50_000
    acc, rep = res["accuracy_mm"], res["repeatability_mm"]
    # realistic tolerances give mm-level errors; repeatability stays below 0.1 mm
    assert 0.5 < acc["mean"] < 10.0
    assert rep["max_deviation"] < 0.1
    assert acc["mean"] > 10 * rep["max_deviation"]
    # calibration brings the model to the tracker's noise level over the whole workspace
    assert res["geometric_calibration"]["workspace_accuracy_mm"]["after"]["rms"] < 0.05
    # the bent tool is found again to a fraction of a millimetre, in under 15 s of robot time
    tool = res["tool_recalibration"]
    assert tool["tcp_error_mm"] < 0.2 and tool["cycle_time_s"] < 15.0
    # issue 32: the demo ends with the ISO 9283 test run by the true robot, nominal vs corrected
    # program: the calibration brings pose and path accuracy down, repeatability stays the robot's
    iso = {row["characteristic"]: row for row in res["iso9283"]["comparison"]}
    assert iso["AP_mm"]["after"] < 0.25 * iso["AP_mm"]["before"]
    assert iso["AT_mm_line"]["after"] < 0.5 * iso["AT_mm_line"]["before"]
    assert iso["RP_mm"]["after"] == pytest.approx(iso["RP_mm"]["before"], rel=0.5)
    assert (tmp_path / "d" / "iso9283" / "evaluation" / "report.html").is_file()
    # every cycle is in the history database
    from robocal.store import HistoryStore

    with HistoryStore.open(tmp_path / "d" / "history.sqlite", create=False) as store:
        kinds = [c.kind for c in store.cycles(res["robot"])]
    assert kinds[0] == "geometric_calibration" and kinds[-1] == "tool_recalibration"
    assert kinds.count("thermal_compensation") == len(res["thermal"]["cycles"]) >= 5
    # thermal: the screened parameters keep more monitored directions within 0.1 mm than the
    # traditional lengths on every evaluation run
    for row in res["thermal"]["rows"][1:]:
        assert row["screened"] > row["traditional"] > row["before"]
