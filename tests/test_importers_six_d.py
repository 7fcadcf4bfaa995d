"""Issue 31, item 2 and 6 at the importer level: SpatialAnalyzer frames and its 15-column export
(--name-fields), controller log column names (UR RTDE, KUKA, ABB, --joint-columns), vendors' time
stamps, and the warnings / numbers / tables the user sees."""

import numpy as np
import pytest
from click.testing import CliRunner

from robocal.cli import main
from robocal.cli.calibrate_table import parameter_table, statistics_table
from robocal.io.importers import read_joint_log, read_spatialanalyzer, read_tracker_csv
from robocal.io.importers.timestamps import parse_time
from robocal.transforms import euler_from_matrix, matrix_from_euler, so3_exp

R = so3_exp(np.array([[0.1, 0.2, 0.3], [-0.5, 0.4, 2.0], [1.0, -0.2, 0.1]]))
P = np.array([[1523.412, -402.118, 987.004], [1611.9034, -310.5002, 1102.25], [1420.0, -510.75, 1250.5]])


def _write(tmp_path, name, text, encoding="utf-8"):
    path = tmp_path / name
    path.write_text(text, encoding=encoding)
    return path


def test_spatialanalyzer_frames_with_declared_convention(tmp_path):
    rpy = np.degrees(euler_from_matrix(R, "rpy"))
    lines = ["// Units: Millimeters"] + [
        "\t".join(["A", "Frames", f"F{k + 1}"] + [f"{v:.6f}" for v in (*P[k], *rpy[k])]) for k in range(3)]
    path = _write(tmp_path, "frames.txt", "\n".join(lines) + "\n")
    pts = read_spatialanalyzer(path, orientation="rpy")
    assert pts.ids == ("F1", "F2", "F3") and pts.orientation == "rpy"
    np.testing.assert_allclose(pts.rotations, R, atol=1e-7)
    np.testing.assert_allclose(pts.points, P, atol=1e-6)
    assert any("taken as degrees" in n for n in pts.notes)


def test_spatialanalyzer_fifteen_columns_with_name_fields(tmp_path):
    """SA's 15-column export: 3 name fields, X Y Z and 9 more values (tolerances, uncertainties)."""
    lines = ["\t".join(["A", "G", f"P{k}"] + [f"{v:.4f}" for v in P[k]] + ["0.01"] * 9) for k in range(3)]
    path = _write(tmp_path, "sa15.txt", "// Units: Millimeters\n" + "\n".join(lines) + "\n")
    pts = read_spatialanalyzer(path, name_fields=3)
    np.testing.assert_allclose(pts.points, P)
    assert any("9 field(s) after X Y Z ignored" in n for n in pts.notes)
    r = CliRunner().invoke(main, ["import", str(path), "--format", "sa-text", "--name-fields", "3", "--joints",
                                  str(_write(tmp_path, "j.csv", "J1;J2;J3;J4;J5;J6\n" + "0;0;0;0;0;0\n" * 3)),
                                  "--angle-unit", "deg", "--robot", "ur10", "--out", str(tmp_path / "m.csv")])
    assert r.exit_code == 0, r.output


def test_quaternion_columns_need_no_convention_and_are_checked(tmp_path):
    from robocal.transforms import quaternion_from_matrix

    qs = quaternion_from_matrix(R)
    rows = ["Point,X,Y,Z,Q0,Q1,Q2,Q3"] + [",".join([f"P{k}"] + [repr(float(v)) for v in (*P[k], *qs[k])])
                                          for k in range(3)]
    pts = read_tracker_csv(_write(tmp_path, "q.csv", "\n".join(rows) + "\n"), length_unit="mm")
    assert pts.orientation == "quaternion"
    np.testing.assert_allclose(pts.rotations, R, atol=1e-12)


def test_angles_within_2_pi_without_a_unit_are_refused(tmp_path):
    rows = ["Name;X;Y;Z;Rx;Ry;Rz"] + [f"P{k};{P[k][0]};{P[k][1]};{P[k][2]};0.1;0.2;0.3" for k in range(3)]
    path = _write(tmp_path, "small.csv", "\n".join(rows) + "\n")
    with pytest.raises(ValueError, match="degrees and radians both possible"):
        read_tracker_csv(path, length_unit="mm", orientation="rpy")
    pts = read_tracker_csv(path, length_unit="mm", orientation="rpy", orientation_unit="rad")
    np.testing.assert_allclose(pts.rotations[0], matrix_from_euler([0.1, 0.2, 0.3], "rpy"))


@pytest.mark.parametrize("header, unit_opt", [
    ("timestamp actual_q_0 actual_q_1 actual_q_2 actual_q_3 actual_q_4 actual_q_5", None),  # UR RTDE: rad
    ("Time;$AXIS_ACT.A1;$AXIS_ACT.A2;$AXIS_ACT.A3;$AXIS_ACT.A4;$AXIS_ACT.A5;$AXIS_ACT.A6", "rad"),  # KUKA
    ("time,rob1_j1,rob1_j2,rob1_j3,rob1_j4,rob1_j5,rob1_j6", "rad"),  # ABB
])
def test_controller_log_column_names(tmp_path, header, unit_opt):
    sep = " " if " " in header else (";" if ";" in header else ",")
    q = np.array([[0.1, -0.2, 0.3, 0.4, -0.5, 0.6], [0.2, -0.1, 0.35, 0.1, -0.4, 0.7]])
    rows = [header] + [sep.join([f"{k}.5"] + [repr(float(v)) for v in row]) for k, row in enumerate(q)]
    log = read_joint_log(_write(tmp_path, "log.csv", "\n".join(rows) + "\n"), angle_unit=unit_opt)
    np.testing.assert_allclose(log.joints, q)
    assert len(log.joint_names) == 6


def test_joint_columns_option_for_anything_else(tmp_path):
    rows = ["t;shoulder;elbow;wrist"] + [f"{k};{k}0;{k}1;{k}2" for k in range(1, 4)]
    path = _write(tmp_path, "odd.csv", "\n".join(rows) + "\n")
    with pytest.raises(ValueError, match="--joint-columns"):
        read_joint_log(path, angle_unit="deg")
    log = read_joint_log(path, angle_unit="deg", joint_columns=["shoulder", "elbow", "wrist"])
    np.testing.assert_allclose(np.degrees(log.joints[0]), [10.0, 11.0, 12.0])


@pytest.mark.parametrize("cell, slash, expected", [
    ("'11.10.2022 15:06:48.043", "dmy", "2022-10-11T15:06:48.043"),
    ('"2022-10-11 15:06:48.043"', "dmy", "2022-10-11T15:06:48.043"),
    ("10/11/2022 3:06:48.043 PM", "mdy", "2022-10-11T15:06:48.043"),
    ("11/10/2022 15:06:48,043", "dmy", "2022-10-11T15:06:48.043"),
])
def test_vendor_time_stamps(cell, slash, expected):
    from datetime import datetime, timezone

    want = datetime.fromisoformat(expected).replace(tzinfo=timezone.utc).timestamp()
    got = parse_time(cell, slash=slash)
    assert got is not None and got[1] == "datetime" and got[0] == pytest.approx(want, abs=1e-6)


def test_unit_assumption_warning_is_one_line_without_a_source_path(tmp_path):
    pts = "Name;X;Y;Z\n" + "\n".join(f"P{k};{P[k][0] / 1000};{P[k][1] / 1000};{P[k][2] / 1000}" for k in range(3))
    joints = "J1;J2;J3;J4;J5;J6\n" + "0;0;0;0;0;0\n" * 3
    r = CliRunner().invoke(main, ["import", str(_write(tmp_path, "p.csv", pts + "\n")), "--joints",
                                  str(_write(tmp_path, "j.csv", joints)), "--angle-unit", "deg", "--robot", "ur10",
                                  "--out", str(tmp_path / "m.csv")])
    assert r.exit_code == 0, r.output
    warn = [x for x in r.output.splitlines() if "assumed metres" in x and not x.startswith("note:")]
    assert len(warn) == 1 and warn[0].startswith("Warning: "), r.output
    assert ".py" not in r.output and "UnitAssumptionWarning" not in r.output


def test_console_tables_keep_their_columns_for_any_magnitude():
    big = {"rms": 12345.6789, "mean": 23456.789, "p95": 123456.7891, "max": 1234567.891}
    lines = statistics_table("position error [mm]", [("calibration poses, before", big)])
    assert len(lines[1].split()) == 4 + 3  # label words + four numbers, none run together
    params = [{"name": "a2", "unit": "mm", "value": 123456.123456, "change": -98765.4321, "std": 12345.6789,
               "identifiable": True, "block": "geometry"}]
    row = parameter_table({"parameters": params})[2]
    assert row.split()[2:] == ["123456.12346", "-98765.43210", "12345.67890"]
