"""Measurement files (robocal-measurements/1): round trips and clear errors on bad input."""

from __future__ import annotations

import math

import numpy as np
import pytest

from robocal.io import (
    DEFAULT_TARGET,
    MeasurementFileError,
    Measurements,
    read_measurements,
    write_measurements,
)
from robocal.robots import load_robot
from robocal.transforms import so3_exp

KUKA = "kuka_kr150_r3100"
KUKA_JOINTS = ("A1", "A2", "A3", "A4", "A5", "A6")


@pytest.fixture(scope="module")
def kuka():
    return load_robot(KUKA)


def _meas(rng, n=7, targets=("r1", "r2", "r3"), rotations=True, joint_names=KUKA_JOINTS, robot=KUKA,
          prismatic=None):
    k = len(targets)
    return Measurements(
        joints=rng.uniform(-2.0, 2.0, size=(n, len(joint_names))),
        points=rng.uniform(-3000.0, 3000.0, size=(n, k, 3)),
        targets=targets,
        joint_names=joint_names,
        pose_ids=[f"P{i}" for i in range(n)],
        rotations=so3_exp(rng.normal(size=(n, 3))) if rotations else None,
        prismatic=prismatic,
        metadata={"robot": robot, "instrument": "tracker", "frame": "tracker", "note": "line one\nline two"},
    )


def _write(tmp_path, text, name="m.csv"):
    p = tmp_path / name
    p.write_text(text)
    return p


HEADER = "# format: robocal-measurements/1\n# robot: kuka_kr150_r3100\n# length_unit: mm\n# angle_unit: deg\n"
COLS = "pose,A1,A2,A3,A4,A5,A6,x,y,z\n"
ROW1 = "1,10,-90,90,0,30,0,2500.5,-800.25,1400.125\n"
ROW2 = "2,-10,-80,80,5,20,10,2400.5,-700.25,1500.125\n"


# ------------------------------------------------------------------ round trips


@pytest.mark.parametrize("orientation", ["quaternion", "kuka_abc", "fanuc_wpr", "zxz", "rotvec"])
@pytest.mark.parametrize("units", [("mm", "deg"), ("m", "rad")])
def test_round_trip_exact(tmp_path, kuka, orientation, units):
    rng = np.random.default_rng(1)
    m = _meas(rng)
    path = tmp_path / "m.csv"
    write_measurements(path, m, orientation=orientation, length_unit=units[0], angle_unit=units[1])
    r = read_measurements(path, robot=kuka)
    assert r.targets == ("r1", "r2", "r3")
    assert r.joint_names == KUKA_JOINTS
    assert r.pose_ids == m.pose_ids
    # shortest-repr writing: exact up to the unit conversion's rounding
    np.testing.assert_allclose(r.joints, m.joints, rtol=0, atol=1e-14)
    np.testing.assert_allclose(r.points, m.points, rtol=1e-15, atol=1e-12)
    np.testing.assert_allclose(r.rotations, m.rotations, rtol=0, atol=1e-12)
    assert r.metadata["orientation"] == orientation
    assert r.metadata["length_unit"] == units[0] and r.metadata["angle_unit"] == units[1]
    assert r.metadata["instrument"] == "tracker"
    assert r.metadata["note"] == "line one\nline two"


def test_round_trip_mm_deg_is_bit_exact_for_points(tmp_path):
    m = _meas(np.random.default_rng(2), rotations=False)
    write_measurements(tmp_path / "m.csv", m)
    r = read_measurements(tmp_path / "m.csv")
    assert np.array_equal(r.points, m.points)
    assert r.rotations is None and "orientation" not in r.metadata


def test_round_trip_printed_precision(tmp_path):
    m = _meas(np.random.default_rng(3))
    write_measurements(tmp_path / "m.csv", m, float_format=".4f", orientation="kuka_abc")
    r = read_measurements(tmp_path / "m.csv")
    np.testing.assert_allclose(r.points, m.points, rtol=0, atol=0.5e-4 + 1e-9)
    np.testing.assert_allclose(r.joints, m.joints, rtol=0, atol=math.radians(0.5e-4) + 1e-12)
    np.testing.assert_allclose(r.rotations, m.rotations, rtol=0, atol=1e-5)


def test_single_target_uses_plain_xyz(tmp_path):
    m = _meas(np.random.default_rng(4), targets=(DEFAULT_TARGET,), rotations=False)
    write_measurements(tmp_path / "m.csv", m)
    text = (tmp_path / "m.csv").read_text()
    assert "pose,A1,A2,A3,A4,A5,A6,x,y,z\n" in text
    r = read_measurements(tmp_path / "m.csv")
    assert r.targets == (DEFAULT_TARGET,) and r.points.shape == (7, 1, 3)


def test_prismatic_joint_in_length_unit(tmp_path):
    hilti = load_robot("hilti_trailblazer")
    names = hilti.controller_joints
    rng = np.random.default_rng(5)
    prism = np.array([True] + [False] * 6)
    m = _meas(rng, targets=(DEFAULT_TARGET,), rotations=False, joint_names=names, robot="hilti_trailblazer",
              prismatic=prism)
    q = m.joints.copy()
    q[:, 0] = rng.uniform(1500.0, 3900.0, size=len(q))
    m = Measurements(q, m.points, m.targets, names, m.pose_ids, None, prism, m.metadata)
    write_measurements(tmp_path / "m.csv", m, length_unit="m", angle_unit="deg")
    text = (tmp_path / "m.csv").read_text()
    assert "# prismatic: column_prismatic_joint" in text
    row = text.splitlines()[-1].split(",")
    assert float(row[1]) == pytest.approx(q[-1, 0] / 1000.0)  # metres in the file
    assert float(row[2]) == pytest.approx(math.degrees(q[-1, 1]))
    for robot in (None, hilti):
        r = read_measurements(tmp_path / "m.csv", robot=robot)
        np.testing.assert_allclose(r.joints, q, rtol=1e-15, atol=1e-12)
        assert list(r.prismatic) == list(prism)


def test_reader_reorders_joint_columns_to_model(tmp_path, kuka):
    text = HEADER + "pose,A6,A5,A4,A3,A2,A1,x,y,z\n1,6,5,4,3,-90,1,2500,0,1000\n"
    r = read_measurements(_write(tmp_path, text), robot=kuka)
    np.testing.assert_allclose(np.degrees(r.joints[0]), [1, -90, 3, 4, 5, 6])


def test_comments_blank_lines_and_free_text(tmp_path):
    text = HEADER + "# ----- made by hand\n#\n\n" + COLS + ROW1 + "\n# a comment row\n" + ROW2
    r = read_measurements(_write(tmp_path, text))
    assert r.n_poses == 2 and r.pose_ids == ("1", "2")


def test_existing_file_not_overwritten(tmp_path):
    m = _meas(np.random.default_rng(6))
    path = _write(tmp_path, "precious\n")
    with pytest.raises(FileExistsError, match="overwrite=True"):
        write_measurements(path, m)
    assert path.read_text() == "precious\n"
    write_measurements(path, m, overwrite=True)
    assert read_measurements(path).n_poses == 7
    assert [p.name for p in tmp_path.iterdir()] == ["m.csv"]  # no temp files left


# ------------------------------------------------------------------ bad input


def _err(tmp_path, text, robot=None, **kw):
    path = _write(tmp_path, text)
    with pytest.raises(MeasurementFileError) as info:
        read_measurements(path, robot=robot, **kw)
    assert str(path) in str(info.value)
    return info.value


def test_nan_cell_names_line_and_column(tmp_path):
    e = _err(tmp_path, HEADER + COLS + ROW1 + "2,-10,-80,80,5,nan,10,2400,-700,1500\n")
    assert e.line == 7 and e.column == "A5"
    assert "line 7" in str(e) and "'A5'" in str(e) and "finite" in str(e)


def test_empty_cell(tmp_path):
    e = _err(tmp_path, HEADER + COLS + ROW1 + "2,-10,-80,80,5,20,10,2400,,1500\n")
    assert (e.line, e.column) == (7, "y") and "empty cell" in str(e)


def test_text_in_number_cell(tmp_path):
    e = _err(tmp_path, HEADER + COLS + ROW1 + "2,-10,-80,80,5,20,10,2400.5,-700.25,12OO.5\n")
    assert (e.line, e.column) == (7, "z")
    assert "'12OO.5' is not a number" in str(e) and "line 7" in str(e) and "column 10" in str(e)


def test_missing_point_column(tmp_path):
    e = _err(tmp_path, HEADER + "pose,A1,A2,A3,A4,A5,A6,x,y\n1,0,-90,90,0,30,0,2500,10\n")
    assert e.line == 5 and "'z'" in str(e)


def test_missing_joint_column_with_robot(tmp_path, kuka):
    e = _err(tmp_path, HEADER + "pose,A1,A2,A3,A4,A5,x,y,z\n1,0,-90,90,0,30,2500,10,1000\n", robot=kuka)
    assert e.column == "A6" and "missing joint column" in str(e)


def test_wrong_joint_names(tmp_path, kuka):
    text = HEADER + "pose,J1,J2,J3,J4,J5,J6,x,y,z\n1,0,-90,90,0,30,0,2500,10,1000\n"
    e = _err(tmp_path, text, robot=kuka)
    assert "A1" in str(e) and "J1" in str(e)
    # a single misspelt joint gets a suggestion
    text = HEADER + "pose,A1,A2,A3,A4,A5,A6,A7,x,y,z\n1,0,-90,90,0,30,0,0,2500,10,1000\n"
    e = _err(tmp_path, text, robot=kuka)
    assert e.column == "A7" and "unknown column" in str(e)


def test_missing_pose_column(tmp_path):
    e = _err(tmp_path, HEADER + "A1,A2,A3,A4,A5,A6,x,y,z\n0,-90,90,0,30,0,2500,10,1000\n")
    assert "pose" in str(e) and e.line == 5


def test_wrong_number_of_fields(tmp_path):
    e = _err(tmp_path, HEADER + COLS + ROW1 + "2,-10,-80,80,5,20,10,2400,-700\n")
    assert e.line == 7 and "9 fields, expected 10" in str(e)


@pytest.mark.parametrize("key,value,needle", [
    ("length_unit", "inch", "unknown length_unit 'inch'"),
    ("angle_unit", "grad", "unknown angle_unit 'grad'"),
])
def test_unknown_units(tmp_path, key, value, needle):
    text = HEADER.replace(f"# {key}: " + ("mm" if key == "length_unit" else "deg"), f"# {key}: {value}")
    e = _err(tmp_path, text + COLS + ROW1)
    assert needle in str(e) and e.line == (3 if key == "length_unit" else 4)


def test_missing_header_key(tmp_path):
    e = _err(tmp_path, HEADER.replace("# angle_unit: deg\n", "") + COLS + ROW1)
    assert "angle_unit" in str(e)


def test_wrong_format(tmp_path):
    e = _err(tmp_path, HEADER.replace("robocal-measurements/1", "robocal-measurements/9") + COLS + ROW1)
    assert e.line == 1 and "not supported" in str(e)


def test_too_few_rows(tmp_path):
    e = _err(tmp_path, HEADER + COLS)
    assert "0 data row(s)" in str(e)
    e = _err(tmp_path, HEADER + COLS + ROW1 + ROW2, min_rows=3)
    assert "2 data row(s); at least 3" in str(e)


def test_metres_declared_as_mm(tmp_path):
    text = HEADER + COLS + "1,10,-90,90,0,30,0,2.5005,-0.80025,1.400125\n2,-10,-80,80,5,20,10,2.4,-0.7,1.5\n"
    e = _err(tmp_path, text)
    assert "length_unit: m" in str(e) and "metres" in str(e)
    r = read_measurements(_write(tmp_path, text.replace("length_unit: mm", "length_unit: m"), "ok.csv"))
    np.testing.assert_allclose(r.points[0, 0], [2500.5, -800.25, 1400.125])


def test_mm_declared_as_metres(tmp_path):
    e = _err(tmp_path, HEADER.replace("length_unit: mm", "length_unit: m") + COLS + ROW1.replace("2500.5", "2500500.5"))
    assert "length_unit: mm" in str(e) and e.line == 6


def test_degrees_declared_as_radians(tmp_path):
    e = _err(tmp_path, HEADER.replace("angle_unit: deg", "angle_unit: rad") + COLS + ROW1)
    assert (e.line, e.column) == (6, "A2") and "angle_unit: deg" in str(e)
    # radians declared as degrees is allowed (small numbers are legal degrees)
    r = read_measurements(_write(tmp_path, HEADER + COLS + "1,0.1,-1.5,1.5,0,0.5,0,2500,0,1000\n", "ok.csv"))
    assert r.n_poses == 1


def test_orientation_columns_need_declaration(tmp_path):
    e = _err(tmp_path, HEADER + "pose,A1,A2,A3,A4,A5,A6,x,y,z,qw,qx,qy,qz\n1,0,-90,90,0,30,0,2500,0,1000,1,0,0,0\n")
    assert "orientation" in str(e)
    e = _err(tmp_path, HEADER + "# orientation: kuka_abc\n" + COLS + ROW1)
    assert "rx" in str(e)
    e = _err(tmp_path, HEADER + "# orientation: quaternion\n" + "pose,A1,A2,A3,A4,A5,A6,x,y,z,qw,qx,qy,qz\n"
             "1,0,-90,90,0,30,0,2500,0,1000,0.5,0.5,0.5,0.9\n")
    assert (e.line, e.column) == (7, "qw") and "norm" in str(e)
    e = _err(tmp_path, HEADER + "# orientation: kuka_xyz\n" + COLS + ROW1)
    assert "unknown orientation convention" in str(e) and e.line == 5


def test_robot_name_mismatch(tmp_path):
    e = _err(tmp_path, HEADER + COLS + ROW1, robot=load_robot("ur10"))
    assert "kuka_kr150_r3100" in str(e) and "ur10" in str(e)


def test_missing_file(tmp_path):
    with pytest.raises(FileNotFoundError, match="nope.csv"):
        read_measurements(tmp_path / "nope.csv")


def test_measurements_validate_shapes():
    with pytest.raises(ValueError, match="points"):
        Measurements(joints=np.zeros((3, 6)), points=np.zeros((2, 1, 3)))
    with pytest.raises(ValueError, match="NaN"):
        Measurements(joints=np.full((1, 6), np.nan), points=np.ones((1, 1, 3)))
    m = Measurements(joints=np.zeros((3, 6)), points=np.ones((3, 3)))
    assert m.points.shape == (3, 1, 3) and m.joint_names[0] == "J1" and m.pose_ids == ("1", "2", "3")
    assert m.subset([0, 2]).pose_ids == ("1", "3")
