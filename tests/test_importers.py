"""Importers for tracker exports and controller joint logs (robocal.io.importers)."""

import warnings

import numpy as np
import pytest

from robocal.io import read_measurements, write_measurements
from robocal.io.header import FileFormatError
from robocal.io.importers import (
    UnitAssumptionWarning,
    pair_by_id,
    pair_by_index,
    pair_by_time,
    read_joint_log,
    read_spatialanalyzer,
    read_tracker_csv,
)
from robocal.io.importers.text import split_name_unit
from robocal.io.importers.timestamps import parse_time

POINTS_MM = np.array([
    [1523.412, -402.118, 987.004],
    [1611.9034, -310.5002, 1102.25],
    [1420.0, -510.75, 1250.5],
    [1388.2511, -95.447, 1404.118],
])

SA_TAB = "\n".join([
    "// SA Version 2023.1.0412.3",
    "// Working Frame: A::Roboterbasis",
    "// Units: Millimeters",
    "A\tKalibrierung\tP001\t1523.4120\t-402.1180\t987.0040",
    "A\tKalibrierung\tP002\t1611.9034\t-310.5002\t1102.2500",
    "A\tKalibrierung\tP003\t1420.0000\t-510.7500\t1250.5000",
    "A\tKalibrierung\tP004\t1388.2511\t-95.4470\t1404.1180",
    "",
])

SA_SPACES_METRES = "\n".join([
    "// SA Version 2022.2",
    "Kalibrierung   P001    1,5234120   -0,4021180    0,9870040",
    "Kalibrierung   P002    1,6119034   -0,3105002    1,1022500",
    "Kalibrierung   P003    1,4200000   -0,5107500    1,2505000",
    "Kalibrierung   P004    1,3882511   -0,0954470    1,4041180",
    "",
])

LEICA = "\r\n".join([
    "Leica Tracker Pilot Export",
    "Job: Zelle 4, Messung über Nacht",
    "Datum: 12.03.2024",
    "Name;X [mm];Y [mm];Z [mm];Zeit",
    "P001;1523,412;-402,118;987,004;12.03.2024 10:15:02,125",
    "P002;1611,9034;-310,5002;1102,25;12.03.2024 10:15:09,900",
    "P003;1420,0;-510,75;1250,5;12.03.2024 10:15:17,400",
    "P004;1388,2511;-95,447;1404,118;12.03.2024 10:15:25,050",
    "",
])

FARO_METRES = "\n".join([
    "Point,X,Y,Z,RMS",
    "1,1.523412,-0.402118,0.987004,0.000012",
    "2,1.6119034,-0.3105002,1.10225,0.000010",
    "3,1.42,-0.51075,1.2505,0.000011",
    "4,1.3882511,-0.095447,1.404118,0.000015",
    "",
])

JOINT_LOG = "\n".join([
    "Pose;Zeit;A1 [deg];A2 [deg];A3 [deg];A4 [deg];A5 [deg];A6 [deg]",
    "1;12.03.2024 10:15:02,000;10,5;-90;95;0;30;0",
    "2;12.03.2024 10:15:10,000;12,5;-85;92;1;31;2",
    "3;12.03.2024 10:15:17,500;8,0;-95;97;-1;29;-2",
    "5;12.03.2024 10:15:40,000;8,0;-95;97;-1;29;-2",
    "",
])
JOINTS_DEG = np.array([[10.5, -90, 95, 0, 30, 0], [12.5, -85, 92, 1, 31, 2], [8.0, -95, 97, -1, 29, -2]])


def _file(tmp_path, name, text, encoding="utf-8"):
    path = tmp_path / name
    path.write_bytes(text.encode(encoding))
    return path


# ---------------------------------------------------------------------------------------------
# SpatialAnalyzer
# ---------------------------------------------------------------------------------------------


def test_spatialanalyzer_tab_export_with_units_line(tmp_path):
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        pts = read_spatialanalyzer(_file(tmp_path, "sa.txt", SA_TAB))
    assert pts.ids == ("P001", "P002", "P003", "P004")
    assert pts.groups == ("A::Kalibrierung",) * 4
    assert pts.lines == (4, 5, 6, 7)
    np.testing.assert_array_equal(pts.points, POINTS_MM)
    assert pts.length_unit == "mm" and pts.notes == ("length unit 'mm' as declared in the units line (line 3)",)


def test_spatialanalyzer_metres_with_decimal_comma_detected_and_said(tmp_path):
    with pytest.warns(UnitAssumptionWarning, match="assumed metres"):
        pts = read_spatialanalyzer(_file(tmp_path, "sa_m.txt", SA_SPACES_METRES, "latin-1"))
    np.testing.assert_allclose(pts.points, POINTS_MM, rtol=0, atol=1e-9)
    assert pts.length_unit == "m" and pts.groups == ("Kalibrierung",) * 4
    assert "the points span 0.4171 units" in pts.notes[0]  # z: 1.404118 - 0.987004


def test_spatialanalyzer_malformed_rows(tmp_path):
    bad = SA_TAB.replace("-310.5002", "-310.5O02")
    with pytest.raises(FileFormatError) as info:
        read_spatialanalyzer(_file(tmp_path, "bad.txt", bad))
    assert (info.value.line, info.value.column) == (5, "Y")
    assert "'-310.5O02' is not a number; expected a number (decimal point" in str(info.value)
    short = SA_TAB.replace("\tP003", "")
    with pytest.raises(FileFormatError, match="pass name_fields="):
        read_spatialanalyzer(_file(tmp_path, "short.txt", short))
    # with extra columns (uncertainties) the user names the name fields
    extra = "\n".join(line + "\t0.012\t0.015" if not line.startswith("//") and line else line
                      for line in SA_TAB.splitlines())
    pts = read_spatialanalyzer(_file(tmp_path, "extra.txt", extra), name_fields=3)
    np.testing.assert_array_equal(pts.points, POINTS_MM)


# ---------------------------------------------------------------------------------------------
# tracker CSV
# ---------------------------------------------------------------------------------------------


def test_leica_semicolon_latin1_decimal_comma(tmp_path):
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        pts = read_tracker_csv(_file(tmp_path, "leica.csv", LEICA, "latin-1"))
    np.testing.assert_array_equal(pts.points, POINTS_MM)
    assert pts.ids == ("P001", "P002", "P003", "P004") and pts.lines == (5, 6, 7, 8)
    assert pts.time_kind == "datetime"
    np.testing.assert_allclose(np.diff(pts.times), [7.775, 7.5, 7.65], atol=1e-6)
    assert "decoded as latin-1" in pts.notes
    assert "length unit 'mm' as declared in the header (line 4)" in pts.notes


def test_faro_comma_metres_detected_or_declared(tmp_path):
    path = _file(tmp_path, "faro.csv", FARO_METRES)
    with pytest.warns(UnitAssumptionWarning, match=r"assumed metres \(the points span 0.4171 units"):
        pts = read_tracker_csv(path)
    np.testing.assert_allclose(pts.points, POINTS_MM, rtol=0, atol=1e-9)
    assert pts.ids == ("1", "2", "3", "4") and pts.length_unit == "m"
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        declared = read_tracker_csv(path, length_unit="m")
    assert declared.notes == ()
    np.testing.assert_array_equal(declared.points, pts.points)
    # the same numbers as mm: detected from the spread (417.1 units), said in a note
    mm = FARO_METRES.replace("1.", "1").replace("-0.", "-0")
    with pytest.warns(UnitAssumptionWarning, match="assumed millimetres"):
        assert read_tracker_csv(_file(tmp_path, "faro_mm.csv", mm)).length_unit == "mm"


def test_header_found_case_insensitively_after_a_preamble(tmp_path):
    text = "Export from API Tracker\tSoftware 4.2\nunits = meters\n\nPOINT NAME\tx (m)\ty (m)\tz (m)\n" + "\n".join(
        f"Punkt {i + 1}\t{x / 1000!r}\t{y / 1000!r}\t{z / 1000!r}" for i, (x, y, z) in enumerate(POINTS_MM.tolist()))
    pts = read_tracker_csv(_file(tmp_path, "api.txt", text))
    assert pts.ids[0] == "Punkt 1" and pts.length_unit == "m"
    np.testing.assert_allclose(pts.points, POINTS_MM, rtol=1e-15)
    without_header_units = text.replace(" (m)", "")
    pts = read_tracker_csv(_file(tmp_path, "api2.txt", without_header_units))
    assert pts.notes == ("length unit 'm' as declared in the units line (line 2)",)


def test_implausible_or_ambiguous_units(tmp_path):
    # the header says mm but the points span 0.5 mm: metres labelled as mm
    wrong = FARO_METRES.replace("Point,X,Y,Z", "Point,X [mm],Y [mm],Z [mm]")
    with pytest.raises(FileFormatError, match=r"declares length unit 'mm', but then the points span 0.4171 mm"):
        read_tracker_csv(_file(tmp_path, "wrong.csv", wrong))
    with pytest.warns(UnitAssumptionWarning, match="check the unit"):
        read_tracker_csv(_file(tmp_path, "wrong.csv", wrong), length_unit="mm")
    ambiguous = "Name,X,Y,Z\nA,10,0,0\nB,60,0,0\n"  # 50 units: neither mm of a workspace nor metres
    with pytest.raises(FileFormatError, match="declare the length unit"):
        read_tracker_csv(_file(tmp_path, "amb.csv", ambiguous))
    assert read_tracker_csv(_file(tmp_path, "amb.csv", ambiguous), length_unit="mm").points[1, 0] == 60.0


def test_tracker_csv_malformed_rows(tmp_path):
    bad = LEICA.replace("-510,75", "-51O,75")
    with pytest.raises(FileFormatError) as info:
        read_tracker_csv(_file(tmp_path, "bad.csv", bad, "latin-1"))
    err = info.value
    assert (err.line, err.column) == (7, "Y [mm]")
    assert str(err).endswith("line 7, column 'Y [mm]': '-51O,75' is not a number; expected a number "
                             "(decimal comma, e.g. 1234,56)")
    short = LEICA.replace("P003;1420,0;", "P003;")
    with pytest.raises(FileFormatError, match=r"line 7: 4 fields, expected 5 \(one per column of the header on "
                                              r"line 4\)"):
        read_tracker_csv(_file(tmp_path, "short.csv", short, "latin-1"))
    with pytest.raises(FileFormatError, match=r"no header row naming the columns .* starts with '1,2,3'"):
        read_tracker_csv(_file(tmp_path, "nohead.csv", "1,2,3\n4,5,6\n"))
    bad_time = LEICA.replace("10:15:17,400", "10:1x:17")
    with pytest.raises(FileFormatError) as info:
        read_tracker_csv(_file(tmp_path, "t.csv", bad_time, "latin-1"))
    assert info.value.column == "Zeit" and "expected seconds" in str(info.value)


# ---------------------------------------------------------------------------------------------
# joint logs and pairing
# ---------------------------------------------------------------------------------------------


def test_joint_log_units_declared_never_guessed(tmp_path):
    log = read_joint_log(_file(tmp_path, "log.csv", JOINT_LOG))
    assert log.joint_names == ("A1", "A2", "A3", "A4", "A5", "A6") and log.ids == ("1", "2", "3", "5")
    np.testing.assert_allclose(log.joints[:3], np.radians(JOINTS_DEG), rtol=1e-15)
    plain = JOINT_LOG.replace(" [deg]", "")
    with pytest.raises(FileFormatError, match="pass angle_unit='deg' or 'rad'"):
        read_joint_log(_file(tmp_path, "plain.csv", plain))
    with pytest.raises(FileFormatError, match="look like degrees") as info:
        read_joint_log(_file(tmp_path, "plain.csv", plain), angle_unit="rad")
    assert (info.value.line, info.value.column) == (2, "A2")
    with pytest.raises(FileFormatError, match="angle_unit='rad' given, but the header says 'deg'"):
        read_joint_log(_file(tmp_path, "log.csv", JOINT_LOG), angle_unit="rad")
    track = "Step,Time [s],J1,J2,J3,J4,J5,J6,E1 [mm]\n1,0.0,0.1,0.2,0.3,0.4,0.5,0.6,1200.5\n"
    log = read_joint_log(_file(tmp_path, "track.csv", track), angle_unit="rad",
                         joint_columns=["J1", "J2", "J3", "J4", "J5", "J6", "E1"])
    assert log.prismatic.tolist() == [False] * 6 + [True]
    np.testing.assert_array_equal(log.joints[0], [0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 1200.5])
    assert log.time_kind == "seconds" and log.times[0] == 0.0


def test_pair_by_time_with_tolerance_reports_leftovers(tmp_path):
    pts = read_tracker_csv(_file(tmp_path, "leica.csv", LEICA, "latin-1"))
    log = read_joint_log(_file(tmp_path, "log.csv", JOINT_LOG))
    pairing = pair_by_time(pts, log, tolerance=0.5)
    meas = pairing.measurements
    assert meas.pose_ids == ("P001", "P002", "P003")
    np.testing.assert_allclose(pairing.time_differences, [-0.125, 0.1, 0.1], atol=1e-6)
    np.testing.assert_array_equal(meas.points[:, 0], POINTS_MM[:3])
    np.testing.assert_allclose(meas.joints, np.radians(JOINTS_DEG), rtol=1e-15)
    left = {(u.source, u.id): u for u in pairing.unmatched}
    assert set(left) == {("points", "P004"), ("joints", "5")}
    assert "nearest joint row (line 4) is -7.550 s away (tolerance 0.5 s)" in left["points", "P004"].reason
    assert "line 5: joint row '5' not paired: no point within 0.5 s" in pairing.report()
    tight = pair_by_time(pts, log, tolerance=0.11)
    assert tight.measurements.pose_ids == ("P002", "P003")
    shifted = pair_by_time(pts, log, tolerance=0.05, offset=-0.1)  # the controller clock runs 0.1 s ahead
    assert shifted.measurements.pose_ids == ("P002", "P003")


def test_pair_by_time_conflict_and_clock_kinds(tmp_path):
    pts = read_tracker_csv(_file(tmp_path, "p.csv", "Name;X;Y;Z;Time [s]\nA;0;0;0;1.0\nB;500;0;0;1.2\n"),
                           length_unit="mm")
    log = read_joint_log(_file(tmp_path, "j.csv", "id;time;A1;A2\n1;1.15;10;20\n"), angle_unit="deg")
    pairing = pair_by_time(pts, log, tolerance=0.5)
    assert pairing.measurements.pose_ids == ("B",)
    assert "paired with closer point 'B'" in pairing.unmatched[0].reason
    clock = read_joint_log(_file(tmp_path, "c.csv", "id;time;A1\n1;10:15:02;10\n"), angle_unit="deg")
    with pytest.raises(ValueError, match="seconds time stamps but .* has clock"):
        pair_by_time(pts, clock, tolerance=0.5)


def test_pair_by_id_and_by_index(tmp_path):
    pts = read_spatialanalyzer(_file(tmp_path, "sa.txt", SA_TAB))
    log = read_joint_log(_file(tmp_path, "log.csv", JOINT_LOG))
    with pytest.raises(ValueError, match="no point .* paired"):
        pair_by_id(pts, log)  # 'P001' is not '1' unless numbers are compared
    pairing = pair_by_id(pts, log, match="number")
    assert pairing.measurements.pose_ids == ("P001", "P002", "P003")
    assert [(u.source, u.id, u.line) for u in pairing.unmatched] == [("points", "P004", 7), ("joints", "5", 5)]
    by_index = pair_by_index(pts, log)
    assert by_index.measurements.n_poses == 4 and by_index.unmatched == ()
    np.testing.assert_allclose(by_index.measurements.joints[3], np.radians([8.0, -95, 97, -1, 29, -2]))
    dup = JOINT_LOG.replace("\n5;", "\n3;")
    with pytest.raises(FileFormatError, match="id '3' also on line 4") as info:
        pair_by_id(pts, read_joint_log(_file(tmp_path, "dup.csv", dup)), match="number")
    assert info.value.line == 5


def test_imported_campaign_round_trips_through_a_measurement_file(tmp_path):
    pts = read_tracker_csv(_file(tmp_path, "leica.csv", LEICA, "latin-1"))
    log = read_joint_log(_file(tmp_path, "log.csv", JOINT_LOG))
    meas = pair_by_time(pts, log, tolerance=0.5, robot="kuka_kr150_r3100").measurements
    out = write_measurements(tmp_path / "cell4.csv", meas)
    back = read_measurements(out)
    np.testing.assert_array_equal(back.points, meas.points)
    np.testing.assert_allclose(back.joints, meas.joints, rtol=1e-15, atol=1e-15)
    assert back.pose_ids == meas.pose_ids and back.robot == "kuka_kr150_r3100"
    assert "paired by time stamp (tolerance 0.5 s, offset 0 s)" in back.metadata["note"]


def test_header_less_csv_given_as_measurement_file_says_how_to_declare(tmp_path):
    for name, text in (("plain.csv", "Name;X;Y;Z\nP1;1523,4;-402,1;987,0\n"), ("bare.csv", "1,2,3\n")):
        with pytest.raises(FileFormatError) as info:
            read_measurements(_file(tmp_path, name, text))
        message = str(info.value)
        assert "'# format: robocal-measurements/1'" in message and "robocal import" in message
        assert "missing column" not in message and info.value.line == 1


# ---------------------------------------------------------------------------------------------
# helpers
# ---------------------------------------------------------------------------------------------


@pytest.mark.parametrize("cell, decimal, unit, expected", [
    ("12.5", ".", None, (12.5, "seconds")),
    ("1250", ".", "ms", (1.25, "seconds")),
    ("12,5", ",", None, (12.5, "seconds")),
    ("10:15:02.125", ".", None, (36902.125, "clock")),
    ("10:15:02,125", ",", None, (36902.125, "clock")),
    ("1970-01-01 00:01:40.5", ".", None, (100.5, "datetime")),
    ("01.01.1970 0:01:40,5", ",", None, (100.5, "datetime")),
    ("1970-01-01T01:01:40+01:00", ".", None, (100.0, "datetime")),
    ("13.13.2024 10:00:00", ".", None, None),
    ("P17", ".", None, None),
])
def test_parse_time(cell, decimal, unit, expected):
    assert parse_time(cell, decimal, unit) == expected


@pytest.mark.parametrize("header, expected", [
    ("X [mm]", ("x", "mm")), ("Y (m)", ("y", "m")), ("Z/mm", ("z", "mm")), ("A1 [°]", ("a1", "°")),
    ("Date/Time", ("date/time", None)), ("Point Name", ("point name", None)),
])
def test_split_name_unit(header, expected):
    assert split_name_unit(header) == expected


def test_utf16_export_is_decoded(tmp_path):
    path = tmp_path / "sa16.txt"
    path.write_bytes(SA_TAB.encode("utf-16"))
    pts = read_spatialanalyzer(path)
    np.testing.assert_array_equal(pts.points, POINTS_MM)
    assert "decoded as utf-16" in pts.notes
