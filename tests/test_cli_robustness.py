"""Issue 9: every failure of the command line is one ``Error:`` line, never a traceback.

Every subcommand is enumerated from the click group (a new command is covered automatically)
and driven with a binary file for every file argument, a read-only output folder and a corrupted
history database. Then the input classes of the issue: duplicates, joint ranges, number syntax,
huge numbers, units declared wrongly in TCP and robot files, an empty history file, disk full,
and ``demo`` over existing files.
"""

import errno
import os
import re
import sqlite3
import warnings
from pathlib import Path

import click
import numpy as np
import pytest
from click.testing import CliRunner

from robocal.cli import main

ROOT = Path(__file__).resolve().parents[1]


def run(*args, **kw):
    return CliRunner().invoke(main, [str(a) for a in args], **kw)


def leaf_commands(group=main, prefix=()):
    """Every leaf command, through the group's public listing (which loads lazy commands too)."""
    ctx = click.Context(group)
    for name in group.list_commands(ctx):
        cmd = group.get_command(ctx, name)
        if isinstance(cmd, click.Group):
            yield from leaf_commands(cmd, prefix + (name,))
        else:
            yield prefix + (name,), cmd


COMMANDS = list(leaf_commands())


def _is_output(p) -> bool:
    return p.name in ("out_dir", "out_file", "out", "plot_path") or bool(p.opts and "out" in p.opts[0])


def _args(path, cmd, binary, out_dir, db):
    """Arguments filling every required parameter of ``cmd``: ``binary`` for inputs, ``out_dir``
    (or a file in it) for outputs, ``db`` for a history database."""
    args = list(path)
    for p in cmd.params:
        if isinstance(p, click.Argument):
            if isinstance(p.type, click.Choice):
                args += [p.type.choices[0]]  # a valid choice: the hostile part is the files
            elif p.nargs == -1:
                if isinstance(p.type, click.Path) and not p.type.file_okay:
                    args += [binary.parent]  # folders expected: a folder of junk
                else:
                    args += ["0"] * 6 if p.name in ("joints", "pose") else [binary, binary]
            else:
                args += [binary]
        elif p.required or p.name in ("db", "history"):
            value = db if p.name in ("db", "history") else binary
            if _is_output(p):
                value = out_dir if p.name == "out_dir" or getattr(p.type, "file_okay", True) is False else \
                    out_dir / "x.out"
            if p.name == "params":
                value = "a2"
            if isinstance(p.type, (click.types.IntParamType, click.types.FloatParamType)):
                value = "10"  # a number where a number is required: the hostile part is the files
            args += [p.opts[0], value]
    return args


def _no_traceback(r):
    assert r.exception is None or isinstance(r.exception, SystemExit), repr(r.exception)
    assert "Traceback" not in r.output
    if r.exit_code not in (0, 2):  # 2: click's usage errors ("Usage: ... Error: ...")
        lines = [ln for ln in r.output.splitlines() if ln.strip()]
        assert lines and lines[-1].startswith("Error:"), r.output


@pytest.fixture(scope="module")
def bad_inputs(tmp_path_factory):
    d = tmp_path_factory.mktemp("hostile")
    binary = d / "binary.csv"
    binary.write_bytes(bytes(range(256)) * 8)
    db = d / "corrupt.sqlite"
    with sqlite3.connect(db) as c:
        c.execute("CREATE TABLE t (x)")
        c.executemany("INSERT INTO t VALUES (?)", [("y" * 500,)] * 200)
    data = bytearray(db.read_bytes())
    data[100:4096] = b"\xff" * (4096 - 100)  # header and first page destroyed
    db.write_bytes(bytes(data))
    ro = d / "readonly"
    ro.mkdir()
    os.chmod(ro, 0o555)
    if os.access(ro, os.W_OK):  # root ignores permissions: a read-only file system instead
        ro = Path("/sys/robocal-readonly")
    return binary, db, ro


def test_commands_are_enumerated():
    names = {" ".join(p) for p, _ in COMMANDS}
    assert {"calibrate", "correct", "demo", "history", "import", "tcp four-point", "thermal compensate"} <= names


@pytest.mark.parametrize("path,cmd", COMMANDS, ids=[" ".join(p) for p, _ in COMMANDS])
def test_no_traceback_on_hostile_input(path, cmd, bad_inputs, tmp_path):
    binary, db, ro = bad_inputs
    takes_input = any(isinstance(p, click.Argument) or (p.required and not _is_output(p)) or p.name == "db"
                      for p in cmd.params)
    if not takes_input and not any(_is_output(p) for p in cmd.params) and path != ("robots",):
        pytest.skip(f"robocal {' '.join(path)} reads no file and writes none: a simulation study, nothing hostile to feed")
    if path in (("demo",), ("tcp", "simulate"), ("thermal", "simulate")):
        args = _args(path, cmd, binary, ro, db)
        if "--out" not in args:
            args += ["--out", ro / "x"]
    else:
        args = _args(path, cmd, binary, ro, db)
    # handeye solve ROBOT DATA: the robot is read only with --joints (else a usage error, exit 2)
    extra = ["--joints", binary, "--board", "checkerboard:9x6:25mm"] if path == ("handeye", "solve") else []
    r = run(*args, *extra)
    _no_traceback(r)
    assert r.exit_code != 0 or path == ("robots",), (args, r.output)
    if any(isinstance(p, click.Argument) or (p.required and not _is_output(p)) for p in cmd.params):
        # the same with a writable output folder: still one error line (the inputs are bad)
        r = run(*_args(path, cmd, binary, tmp_path / "out", db), *extra)
        _no_traceback(r)
        assert r.exit_code == 1, r.output


def test_read_only_output_names_the_path(bad_inputs, tmp_path):
    _, _, ro = bad_inputs
    r = run("simulate", "tracker", "ur10", "--poses", 10, "--out", ro / "m.csv")
    _no_traceback(r)
    assert r.exit_code == 1 and str(ro) in r.output
    r = run("demo", "--out", ro / "demo", "--poses", 10)
    assert r.exit_code == 1 and str(ro) in r.output and "Error:" in r.output


def test_corrupted_and_empty_history_databases(bad_inputs, tmp_path):
    _, db, _ = bad_inputs
    r = run("history", "ur10", "--db", db)
    _no_traceback(r)
    assert r.exit_code == 1 and str(db) in r.output
    empty = tmp_path / "empty.sqlite"
    empty.touch()
    r = run("history", "ur10", "--db", empty)
    assert r.exit_code == 1 and "empty file" in r.output
    assert empty.stat().st_size == 0  # no schema written into it


def test_binary_robot_file_is_one_error_line(bad_inputs):
    binary, _, _ = bad_inputs
    toml = binary.with_suffix(".toml")
    toml.write_bytes(binary.read_bytes())
    r = run("fk", toml, "0", "0", "0", "0", "0", "0")
    assert r.exit_code == 1 and r.output.startswith("Error:") and "not a UTF-8 text file" in r.output


# ------------------------------------------------------------------------------------ measurement rows
@pytest.fixture(scope="module")
def campaign(tmp_path_factory):
    d = tmp_path_factory.mktemp("rows")
    csv = d / "ur10.csv"
    assert run("simulate", "tracker", "ur10", "--poses", 30, "--seed", 4, "--out", csv).exit_code == 0
    return d, csv


def _edit(csv, dst, fn):
    lines = csv.read_text().splitlines()
    dst.write_text("\n".join(fn(lines)) + "\n")
    return dst


def _calibrate_error(d, f, *needles, extra=()):
    r = run("calibrate", "ur10", f, "--out", d / f"out_{f.stem}", *extra)
    assert r.exit_code == 1, r.output
    line = r.output.strip().splitlines()[-1]
    assert line.startswith("Error:"), r.output
    for n in needles:
        assert n in line, line
    return line


def test_duplicate_pose_ids_and_rows(campaign):
    d, csv = campaign
    first = 7  # header lines before the first data row
    dup_id = _edit(csv, d / "dup_id.csv", lambda ls: ls + [re.sub(r"^\d+,", "3,", ls[first + 5])])
    _calibrate_error(d, dup_id, "duplicate pose id '3'", "--drop-duplicates")
    dup_row = _edit(csv, d / "dup_row.csv", lambda ls: ls + [re.sub(r"^\d+,", "999,", ls[first + 2])])
    _calibrate_error(d, dup_row, "duplicate row", "pose '3'")
    r = run("calibrate", "ur10", dup_row, "--out", d / "dropped", "--drop-duplicates")
    assert r.exit_code == 0, r.output
    assert "dropped duplicate poses: line 38 (pose 999)" in r.output


def test_joint_ranges_number_syntax_and_huge_numbers(campaign):
    d, csv = campaign
    row = 7 + 4  # data row of pose 5: line 12
    huge = _edit(csv, d / "huge_joint.csv", lambda ls: [*ls[:row], re.sub(r"^(\d+),[^,]+,", r"\1,1000000,", ls[row]),
                                                        *ls[row + 1:]])
    _calibrate_error(d, huge, "line 12", "column 'J1'", "beyond one turn")
    under = _edit(csv, d / "underscore.csv", lambda ls: [*ls[:row], re.sub(r",[^,]+$", ",1_000", ls[row]),
                                                         *ls[row + 1:]])
    _calibrate_error(d, under, "line 12", "'1_000' is not a number")
    big = _edit(csv, d / "big.csv", lambda ls: [*ls[:row], re.sub(r",[^,]+$", ",1e308", ls[row]), *ls[row + 1:]])
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no NumPy overflow warning on the way to the error
        _calibrate_error(d, big, "line 12", "implausibly large")
    metres = _edit(csv, d / "big_m.csv", lambda ls: [ln.replace("length_unit: mm", "length_unit: m") for ln in ls])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        _calibrate_error(d, metres, "look like millimetres")


def test_row_limit_is_stated(campaign):
    from robocal.io.measurements import MeasurementFileError, read_measurements

    d, csv = campaign
    with pytest.raises(MeasurementFileError, match="more than 20 data rows, the limit"):
        read_measurements(csv, max_rows=20)


def test_disk_full_leaves_nothing_half_written(campaign, monkeypatch):
    import robocal.report.html as html

    d, csv = campaign

    def full(path, *a, **k):
        raise OSError(errno.ENOSPC, "No space left on device", str(path))

    monkeypatch.setattr(html, "atomic_write_text", full)
    out = d / "full"
    r = run("calibrate", "ur10", csv, "--out", out)
    assert r.exit_code == 1 and "no space left on device (disk full)" in r.output and str(out) in r.output
    assert sorted(p.name for p in out.iterdir()) == []  # result.json and the robot files were not moved in


# ------------------------------------------------------------------------------------ units in other files
def _flange_file(path, T, length_unit="mm", angle_unit="deg", scale=1.0, angles_in_rad=False):
    from robocal.transforms import pose_from_transform

    v = pose_from_transform(T, "kuka_abc", length_unit="mm", angle_unit="deg")
    v[:, :3] *= scale
    if angles_in_rad:
        v[:, 3:] = np.radians(v[:, 3:])
    rows = [f"P{i + 1}," + ",".join(repr(float(x)) for x in r) for i, r in enumerate(v)]
    path.write_text(f"# orientation: kuka_abc\n# length_unit: {length_unit}\n# angle_unit: {angle_unit}\n"
                    "pose,x,y,z,A,B,C\n" + "\n".join(rows) + "\n")
    return path


@pytest.fixture
def touch_poses():
    from robocal.transforms import matrix_from_euler

    rng = np.random.default_rng(3)
    tcp, ref = np.array([10.0, -5.0, 180.0]), np.array([1200.0, 300.0, 400.0])
    T = np.tile(np.eye(4), (6, 1, 1))
    T[:, :3, :3] = matrix_from_euler(np.radians(rng.uniform([-40, 140, -40], [40, 220, 40], (6, 3))), "rpy")
    T[:, :3, 3] = ref - T[:, :3, :3] @ tcp
    return T


def test_four_point_file_in_metres_under_mm(tmp_path, touch_poses):
    ok = run("tcp", "four-point", _flange_file(tmp_path / "ok.csv", touch_poses))
    assert ok.exit_code == 0, ok.output
    r = run("tcp", "four-point", _flange_file(tmp_path / "m.csv", touch_poses, scale=1e-3))
    assert r.exit_code == 1 and "look like metres" in r.output and "length_unit: m" in r.output


def test_four_point_radians_declared_as_degrees(tmp_path, touch_poses):
    r = run("tcp", "four-point", _flange_file(tmp_path / "rad.csv", touch_poses, angles_in_rad=True))
    assert r.exit_code == 1 and "look like radians" in r.output and "angle_unit: rad" in r.output


def test_robot_file_units(tmp_path):
    text = (ROOT / "src/robocal/robots/data/ur10.toml").read_text()
    m_label = tmp_path / "m_label.toml"
    m_label.write_text(text.replace('length_unit = "mm"', 'length_unit = "m"'))
    r = run("fk", m_label, *["0"] * 6)
    assert r.exit_code == 1 and "look like millimetres" in r.output and 'length_unit = "mm"' in r.output
    metres = tmp_path / "metres.toml"
    metres.write_text(re.sub(r"^(d|a) = (-?[0-9.]+)$", lambda m: f"{m[1]} = {float(m[2]) / 1000}", text,
                             flags=re.M))
    r = run("fk", metres, *["0"] * 6)
    assert r.exit_code == 1 and "look like metres" in r.output and "below 50 mm" in r.output
    rad = tmp_path / "rad.toml"
    rad.write_text(text.replace("[-360.0, 360.0]", "[-6.283, 6.283]"))
    r = run("fk", rad, *["0"] * 6)
    assert r.exit_code == 1 and "look like radians" in r.output


def test_demo_refuses_to_replace_files(tmp_path):
    out = tmp_path / "demo"
    out.mkdir()
    (out / "report.html").write_text("mine")
    r = run("demo", "--out", out, "--poses", 10)
    assert r.exit_code == 1 and "report.html" in r.output and "--overwrite" in r.output
    assert (out / "report.html").read_text() == "mine"


def test_disk_full_on_a_single_file_names_it(tmp_path, monkeypatch):
    import robocal.io.atomic as atomic

    def full(fd):
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(atomic.os, "fsync", full)
    out = tmp_path / "m.csv"
    r = run("simulate", "tracker", "ur10", "--poses", 10, "--seed", 1, "--out", out)
    _no_traceback(r)
    assert r.exit_code == 1 and str(out) in r.output and "no space left on device" in r.output.lower()
    assert not out.exists() and not list(tmp_path.glob(".m.csv.*"))
