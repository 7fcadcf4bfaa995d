"""Issue 29: no user file is replaced by accident. An output that resolves to an input of the same
command is refused even with --overwrite; an existing output is refused without --overwrite; the
demo writes all or nothing. Every case of the issue, through the command line; the file the user
had is byte-identical afterwards."""

from __future__ import annotations

import os
from pathlib import Path

import pytest
from click.testing import CliRunner

import robocal.workflows.demo as demo
from robocal.cli.main import main
from robocal.io.output_paths import OutputIsInputError, check_outputs, same_file
from robocal.robots.loader import robot_path

KEEP = b"the user's file, not to be replaced\n"


def run(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


def _file(path, data=KEEP):
    path.write_bytes(data)
    return path


def _refused(r, path, data=KEEP, phrase="is an input of this command"):
    assert r.exit_code == 1, r.output
    assert phrase in r.output and "Traceback" not in r.output
    assert path.read_bytes() == data


@pytest.fixture
def robot_file(tmp_path):
    p = tmp_path / "robot.toml"
    p.write_bytes(robot_path("ur10").read_bytes())
    return p


def test_the_helper_sees_links_and_skips_names_that_are_no_files(tmp_path):
    a = _file(tmp_path / "a.csv")
    os.symlink(a, tmp_path / "link.csv")
    os.link(a, tmp_path / "hard.csv")
    assert same_file(tmp_path / "link.csv", a) and same_file(tmp_path / "hard.csv", a)
    with pytest.raises(OutputIsInputError, match="--program"):
        check_outputs(tmp_path / "hard.csv", {"--program": a}, overwrite=True)
    check_outputs(tmp_path / "ur10", {"the robot": "ur10"})  # a shipped robot's name is no file
    with pytest.raises(FileExistsError, match="--overwrite"):
        check_outputs(a, {})


def test_import_never_replaces_the_tracker_export_or_the_joint_log(tmp_path):
    points, joints = _file(tmp_path / "points.csv"), _file(tmp_path / "joints.csv")
    for target in (points, joints):
        r = run("import", points, "--joints", joints, "--robot", "ur10", "--out", target, "--overwrite")
        _refused(r, target)


def test_correct_never_replaces_the_calibrated_robot(tmp_path, robot_file):
    data = robot_file.read_bytes()
    targets = _file(tmp_path / "targets.csv")
    r = run("correct", robot_file, targets, "--out", robot_file, "--overwrite")
    _refused(r, robot_file, data)


def test_plan_poses_and_ik_train_never_replace_the_robot_file(robot_file):
    data = robot_file.read_bytes()
    r = run("plan-poses", robot_file, "--count", 10, "--out", robot_file, "--overwrite")
    _refused(r, robot_file, data)
    r = run("ik-train", robot_file, "--samples", 500, "--out", robot_file, "--overwrite")
    _refused(r, robot_file, data)


def test_thermal_commands_never_replace_their_inputs(tmp_path):
    sphere = _file(tmp_path / "sphere.csv")
    r = run("thermal", "calibrate-sensor", "kuka_kr150_r3100", sphere, "--out", sphere, "--overwrite")
    _refused(r, sphere)
    program, sensor = _file(tmp_path / "p.csv"), _file(tmp_path / "sensor.json")
    r = run("thermal", "compensate", "kuka_kr150_r3100", "--sensor", sensor, "--sphere", sphere, "--params", "a2",
            "--program", program, "--out", program, "--overwrite")
    _refused(r, program)


def test_writers_without_overwrite_refuse_an_existing_file(tmp_path):
    (tmp_path / "sim").mkdir()
    for name in ("events.csv", "sensor.json"):  # tcp simulate --out DIR writes both
        f = _file(tmp_path / "sim" / name)
        r = run("tcp", "simulate", "--collisions", 1, "--out", tmp_path / "sim")
        _refused(r, f, phrase="pass --overwrite")
        f.unlink()
    plot = _file(tmp_path / "ur10_drift.png")
    r = run("history", "ur10", "--db", tmp_path / "h.sqlite", "--plots", tmp_path)
    _refused(r, plot, phrase="pass --overwrite")


def test_fleet_study_json_never_replaces_its_own_poses(tmp_path):
    poses = _file(tmp_path / "poses.csv")
    r = run("fleet", "study", "monte-carlo", "ur10", poses, "--json", poses, "--overwrite")
    _refused(r, poses)


def test_demo_writes_all_or_nothing(tmp_path, monkeypatch):
    """A failure in the last step (the report; a full disk, a kill) leaves no demo file behind."""
    def fail(*args, **kwargs):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(demo, "_write_report", fail)
    out = tmp_path / "d"
    r = run("demo", "--out", out, "--poses", 10)
    assert r.exit_code == 1 and "Traceback" not in r.output
    assert not any(p.name in demo.DEMO_OUTPUTS for p in out.iterdir()) if out.exists() else True


def test_check_not_inputs_agrees_with_same_file_on_every_pair(tmp_path):
    """The check looks inputs up by resolved path and file identity (linear in the count: a fleet of
    100 robots has ~1000 outputs and ~200 inputs; the pairwise loop cost the fleet's client ~30 ms per
    robot): its verdict equals any(same_file(output, input)) over existing inputs, for symbolic and
    hard links, missing files and names that are no file (seeded random sets)."""
    import numpy as np

    from robocal.io.output_paths import check_not_inputs

    files = []
    for k in range(12):
        f = tmp_path / f"f{k}.csv"
        f.write_text(str(k))
        files.append(f)
    os.symlink(files[0], tmp_path / "sym0.csv")
    os.link(files[1], tmp_path / "hard1.csv")
    (tmp_path / "sub").mkdir()
    pool = files + [tmp_path / "sym0.csv", tmp_path / "hard1.csv", tmp_path / "missing.csv",
                    tmp_path / "sub" / ".." / "f2.csv", "ur10"]
    rng = np.random.default_rng(7)
    outcomes = set()
    for _ in range(200):
        outs = [pool[i] for i in rng.choice(len(pool), size=rng.integers(1, 6), replace=False)]
        ins = {f"in{i}": pool[i] for i in rng.choice(len(pool), size=rng.integers(1, 4), replace=False)}
        expected = any(Path(i).exists() and same_file(o, i) for o in outs for i in ins.values())
        try:
            check_not_inputs(outs, ins)
            refused = False
        except OutputIsInputError:
            refused = True
        assert refused == expected, (outs, ins)
        outcomes.add(refused)
    assert outcomes == {True, False}
