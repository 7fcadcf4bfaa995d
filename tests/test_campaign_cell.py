"""Issue 28 acceptance: planned and simulated campaigns a real robot can drive. Over 20 seeds, no
planned or simulated pose, and no sampled point of the move between consecutive poses, puts a link
below the mounting plane or into another link (UR10, KR 150, IRB 140); the plan's program
round-trips through the reader of its language."""

from __future__ import annotations

import numpy as np
import pytest
from click.testing import CliRunner

from robocal.calib.cell import path_points, pose_feasibility
from robocal.cli import main
from robocal.io.programs import read_joint_program, read_program
from robocal.robots import load_robot
from robocal.sim import LaserTracker, VirtualRobot
from robocal.workflows.calibration.plan_poses import plan_cell, plan_in_cell

ROBOTS = ("ur10", "kuka_kr150_r3100", "abb_irb140")


def _driven_points(q):
    return np.vstack([path_points(a, b) for a, b in zip(q[:-1], q[1:])])


def _check(model, q, cell):
    pts = _driven_points(q)
    # independent of the capsule model: every link frame origin stays above the floor
    F = model.replace(T_world_base=np.eye(4)).link_frames(pts)
    assert F[:, :, 2, 3].min() > 0.0, F[:, :, 2, 3].min()
    f = pose_feasibility(cell, model, pts)
    assert not f["mounting_plane"].any() and not f["self_collision"].any() and not f["joint_range"].any()


@pytest.mark.parametrize("robot", ROBOTS)
def test_planned_and_simulated_campaigns_stay_clear_over_20_seeds(robot):
    model = load_robot(robot)
    for seed in range(20):
        cell = plan_cell(model, None, (2500.0, 800.0, 1200.0), (0.0, 0.0, 100.0))
        plan = plan_in_cell(model, cell, count=8, candidates=40, seed=seed, efficiency=False)
        _check(model, plan["q"], cell)
        f = pose_feasibility(cell, model, plan["q"])
        assert not (f["acceptance"] | f["line_of_sight"] | f["range"]).any()
        virtual = VirtualRobot.perturbed(model, seed)
        tracker = LaserTracker.placed(100 + seed, 1)
        q = tracker.feasible_poses(virtual, 8, np.random.default_rng(seed), tracker.cell_for(virtual))
        _check(model, q, tracker.cell_for(virtual))


@pytest.mark.parametrize("language, suffix", [("krl", ".dat"), ("rapid", ".mod"), ("tp", ".ls"),
                                              ("urscript", ".script")])
def test_plan_program_round_trips_through_its_reader(tmp_path, language, suffix):
    out = tmp_path / "plan.csv"
    r = CliRunner().invoke(main, ["plan-poses", "ur10", "--count", "8", "--candidates", "60", "--tracker-at",
                                  "2500,800,1200", "--language", language, "--out", str(out)])
    assert r.exit_code == 0, r.output
    eff = float(r.output.split("D-efficiency against the plan without the cell: ")[1].split()[0])
    assert 0.3 < eff <= 1.5, eff  # reported, and a cell costs some but not all of the information
    model = load_robot("ur10")
    table = read_joint_program(out, model).joints
    prog = read_program(out.with_suffix(suffix))
    q = np.array([t.joints for t in prog.targets])
    assert q.shape == table.shape == (8, 6)
    np.testing.assert_allclose(q, table, atol=np.radians(0.001) if language != "urscript" else 1e-5)
    text = out.with_suffix(".src").read_text() if language == "krl" else prog.text
    assert text.count("measure P0") == 8  # a wait/trigger comment at every measurement point
    if language == "krl":
        assert text.count("PTP XP0") == 8


CELL = """
format = "robocal-cell/1"
length_unit = "mm"
angle_unit = "deg"
[mounting]
kind = "floor"
[[box]]
name = "table"
min = [500.0, -600.0, 0.0]
max = [1300.0, 600.0, 700.0]
[instrument]
position = [-2200.0, 1500.0, 1400.0]
acceptance = 30
[tool]
points = [[0.0, 0.0, 80.0], [20.0, 0.0, 120.0]]
[joints]
J6 = [-180.0, 180.0]
"""


def test_cell_file_drives_plan_and_simulation(tmp_path):
    from robocal.io.cell_file import read_cell
    from robocal.io.measurements import read_measurements

    cell_file = tmp_path / "cell.toml"
    cell_file.write_text(CELL, encoding="utf-8")
    model = load_robot("ur10")
    cell = read_cell(cell_file, model)
    r = CliRunner().invoke(main, ["plan-poses", "ur10", "--count", "10", "--candidates", "60", "--cell", str(cell_file),
                                  "--out", str(tmp_path / "p.csv")])
    assert r.exit_code == 0, r.output
    q = read_joint_program(tmp_path / "p.csv", model).joints
    f = pose_feasibility(cell, model, _driven_points(q))
    assert not any(v.any() for k, v in f.items() if k in ("box", "mounting_plane", "self_collision", "joint_range"))
    assert not any(pose_feasibility(cell, model, q)[k].any() for k in ("acceptance", "line_of_sight", "range"))
    r = CliRunner().invoke(main, ["simulate", "tracker", "ur10", "--poses", "12", "--cell", str(cell_file),
                                  "--out", str(tmp_path / "m.csv")])
    assert r.exit_code == 0, r.output
    qs = read_measurements(tmp_path / "m.csv").joints
    f = pose_feasibility(cell, model, _driven_points(qs))
    assert not (f["box"] | f["mounting_plane"] | f["self_collision"] | f["joint_range"]).any()
    g = pose_feasibility(cell, model, qs)  # the simulated reflector is the cell's
    assert not (g["acceptance"] | g["line_of_sight"] | g["range"]).any()
    truth = __import__("json").loads((tmp_path / "m.truth.json").read_text())
    assert np.allclose(truth["reflectors_mm"], [[20.0, 0.0, 120.0]])


def test_outputs_never_replace_the_cell_file_or_clash(tmp_path):
    cell_file = tmp_path / "cell.toml"
    cell_file.write_text(CELL, encoding="utf-8")
    for args in (["plan-poses", "ur10", "--count", "5", "--cell", str(cell_file), "--out", str(cell_file), "--overwrite"],
                 ["simulate", "tracker", "ur10", "--cell", str(cell_file), "--out", str(cell_file), "--overwrite"],
                 ["plan-poses", "ur10", "--count", "5", "--language", "krl", "--out", str(tmp_path / "p.src")]):
        r = CliRunner().invoke(main, args)
        assert r.exit_code == 1 and r.output.startswith("Error:"), r.output
    assert cell_file.read_text(encoding="utf-8") == CELL
