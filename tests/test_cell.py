"""The cell model (docs/cells.md): capsule geometry against hand-derived distances, the feasibility
checks on poses whose answer is known by construction, and the robocal-cell/1 reader."""

from __future__ import annotations

import math

import numpy as np
import pytest

from robocal.calib.cell import Box, Instrument, default_cell, feasible, order_poses, path_feasible, \
    pose_feasibility, sample_feasible
from robocal.io.cell_file import CellFileError, read_cell
from robocal.kinematics.collision import link_segments, segment_box_distance, segment_plane_distance, \
    segment_segment_distance
from robocal.robots import load_robot


def test_segment_distances_by_hand():
    # parallel segments 5 mm apart, overlapping in x
    assert segment_segment_distance([0, 0, 0], [10, 0, 0], [5, 5, 0], [20, 5, 0]) == pytest.approx(5.0)
    # skew perpendicular segments crossing above each other, 3 mm apart
    assert segment_segment_distance([-1, 0, 0], [1, 0, 0], [0, -1, 3], [0, 1, 3]) == pytest.approx(3.0)
    # end points closest: (10,0,0) to (13,4,0) = 5
    assert segment_segment_distance([0, 0, 0], [10, 0, 0], [13, 4, 0], [13, 40, 0]) == pytest.approx(5.0)
    # a degenerate segment is a point
    assert segment_segment_distance([0, 0, 0], [0, 0, 0], [3, -4, 0], [3, 4, 0]) == pytest.approx(3.0)
    # batch over poses
    d = segment_segment_distance(np.zeros((4, 3)), [[1, 0, 0]] * 4, [[0, 1, 0]] * 4, [[0, 1, 0]] * 4)
    assert d.shape == (4,) and np.allclose(d, 1.0)


def test_plane_and_box_distances_by_hand():
    assert segment_plane_distance([0, 0, 5], [0, 0, -2], [0, 0, 0], [0, 0, 1]) == pytest.approx(-2.0)
    assert segment_plane_distance([0, 0, 5], [3, 0, 7], [0, 0, 1], [0, 0, 2]) == pytest.approx(4.0)
    # a segment passing 2 mm over the top face of a unit box, and one through it
    assert segment_box_distance([-5, 0.5, 3], [5, 0.5, 3], [0, 0, 0], [1, 1, 1]) == pytest.approx(2.0, abs=1e-6)
    assert segment_box_distance([-5, 0.5, 0.5], [5, 0.5, 0.5], [0, 0, 0], [1, 1, 1]) == pytest.approx(0.0, abs=1e-9)
    # closest to an edge: the box corner edge at (1, 1) in xy, the segment along z at (4, 5)
    assert segment_box_distance([4, 5, -3], [4, 5, 3], [0, 0, 0], [1, 1, 1]) == pytest.approx(5.0, abs=1e-6)


def test_ur10_chain_segments_are_the_dh_chain():
    ur = load_robot("ur10")
    s = link_segments(ur, np.zeros((1, 6)), tool_mm=[[0, 0, 100]])
    # d1, a2, a3, d4, d5, d6 of UR's table and the 100 mm tool (a1 = 0 gives no segment)
    assert np.allclose(s.lengths_mm, [127.3, 612.0, 572.3, 163.941, 115.7, 92.2, 100.0])
    assert s.is_tool.tolist() == [False] * 6 + [True]


def test_floor_and_self_collision_verdicts():
    ur = load_robot("ur10")
    cell = default_cell()
    deg = np.radians
    stretched = np.zeros(6)                           # arm horizontal at z ~ 127 mm, flange at 11.6 mm
    upright = deg([0, -90, 0, -90, 0, 0])            # arm pointing up
    below = deg([0, 45, 0, 0, 0, 0])                 # upper arm pointing down through the floor
    folded = deg([0, -90, 175, 0, 0, 0])             # elbow folded back onto the upper arm
    f = pose_feasibility(cell, ur, np.array([stretched, upright, below, folded]))
    assert f["mounting_plane"].tolist() == [True, False, True, False]
    assert f["self_collision"][3] and not f["self_collision"][1]
    assert feasible(cell, ur, upright[None]).tolist() == [True]


def test_instrument_acceptance_and_beam():
    ur = load_robot("ur10")
    up = np.radians([0, -90, 0, -90, 0, 0])
    T = ur.replace(T_world_base=np.eye(4)).fk(up)
    refl = T[:3, 3] + T[:3, :3] @ [0, 0, 100.0]
    axis = T[:3, :3] @ [0, 0, 1.0]
    facing = default_cell(instrument=Instrument(tuple(refl + 2000 * axis)))
    assert feasible(facing, ur, up[None]).tolist() == [True]
    side = np.cross(axis, [0, 0, 1.0]) if abs(axis[2]) < 0.9 else np.array([1.0, 0, 0])
    side /= np.linalg.norm(side)
    at_40 = refl + 2000 * (math.cos(math.radians(40)) * axis + math.sin(math.radians(40)) * side)
    assert pose_feasibility(default_cell(instrument=Instrument(tuple(at_40))), ur, up[None])["acceptance"][0]
    # the beam through the middle of the arm's own upper arm
    s = link_segments(ur, up[None])
    mid = 0.5 * (s.p0[0, 1] + s.p1[0, 1])
    behind = tuple(refl + 3.0 * (mid - refl))
    f = pose_feasibility(default_cell(instrument=Instrument(behind, acceptance_deg=180.0)), ur, up[None])
    assert f["line_of_sight"][0]


def test_box_and_path():
    ur = load_robot("ur10")
    cell = default_cell()
    a = np.radians([0, -45, 0, -90, 0, 0])     # flange at (-919, -256, 1047) mm
    b = np.radians([180, -45, 0, -90, 0, 0])   # flange at (919, 256, 1047) mm
    assert path_feasible(cell, ur, a, b[None]).tolist() == [True]
    # a pillar at (256, -919) where the flange passes half way (J1 = 90 deg)
    from dataclasses import replace

    fenced = replace(cell, boxes=(Box("pillar", (100.0, -1000.0, 0.0), (400.0, -850.0, 2000.0)),))
    assert feasible(fenced, ur, np.array([a, b])).tolist() == [True, True]
    mid = np.radians([90, -45, 0, -90, 0, 0])
    assert not feasible(fenced, ur, mid[None])[0]
    assert path_feasible(fenced, ur, a, b[None]).tolist() == [False]
    _, order, left = order_poses(cell, ur, np.array([a, b, mid]))
    assert order.tolist() == [0, 2, 1] and left.size == 0


CELL = """
format = "robocal-cell/1"
length_unit = "m"
angle_unit = "deg"
[mounting]
kind = "ceiling"
xyz = [0.0, 0.0, 3.0]
[[box]]
name = "table"
min = [0.5, -0.5, 0.0]
max = [1.5, 0.5, 0.8]
[instrument]
position = [3.0, 0.0, 1.0]
acceptance = 30
[tool]
points = [[0.0, 0.0, 0.12]]
[joints]
J4 = [-180, 180]
"""


def test_cell_file(tmp_path):
    ur = load_robot("ur10")
    p = tmp_path / "cell.toml"
    p.write_text(CELL, encoding="utf-8")
    c = read_cell(p, ur)
    assert c.mounting == "ceiling"
    assert np.allclose(c.T_cell_base[:3, 3], [0, 0, 3000]) and np.allclose(c.plane_normal, [0, 0, -1])
    assert c.boxes[0].hi == (1500.0, 500.0, 800.0)
    assert c.instrument.position == (3000.0, 0.0, 1000.0) and c.instrument.acceptance_deg == pytest.approx(30)
    assert np.allclose(c.tool_mm, [[0, 0, 120]])
    assert np.allclose(c.joint_ranges[3], np.radians([-180, 180]))
    # hanging arm pointing down is clear of the ceiling; pointing up it is not
    down = np.radians([0, -90, 0, -90, 0, 0])  # base z points down: "up" in the base frame is down
    assert not pose_feasibility(c, ur, down[None])["mounting_plane"][0]
    p.write_text(CELL.replace('kind = "ceiling"', 'kind = "roof"'), encoding="utf-8")
    with pytest.raises(CellFileError, match="roof"):
        read_cell(p, ur)
    p.write_text(CELL.replace("J4 =", "J9 ="), encoding="utf-8")
    with pytest.raises(CellFileError, match="J9"):
        read_cell(p, ur)


def test_link_radius_from_the_robot_file():
    import tomllib

    from robocal.robots.loader import parse_robot, robot_path

    data = tomllib.loads(robot_path("ur10").read_text(encoding="utf-8"))
    data["joints"][1]["link_radius"] = 80.0   # the upper arm (J2)
    data["joints"][2]["link_radius"] = 0.07   # in mm: 0.07 mm, not plausible but accepted as given
    ur = parse_robot(data, "ur10-with-radii")
    # per body: the base and J1 take the first radius given (J2's), J4..J6 their predecessor's
    assert ur.extra["link_radii_mm"] == [80.0, 80.0, 80.0, 0.07, 0.07, 0.07, 0.07]
    # upper arm tilted 5 deg down: the elbow and the level forearm 74 mm above the floor -- clear of
    # 49 mm default capsules + 10 mm clearance, not of an 80 mm upper arm
    q = np.radians([0, 5.0, -5.0, -90, 0, 0])[None]
    default = pose_feasibility(default_cell(), load_robot("ur10"), q)["mounting_plane"][0]
    thick = pose_feasibility(default_cell(), ur, q)["mounting_plane"][0]
    assert thick and not default


def _sample_whole_batches(cell, model, n, rng, margin=0.05, batch=2000):
    """sample_feasible as a check of every drawn pose (the definition the prefix checks must equal)."""
    lim = cell.limits(model)
    lo, hi = lim[:, 0] + margin * (lim[:, 1] - lim[:, 0]), lim[:, 1] - margin * (lim[:, 1] - lim[:, 0])
    kept, draws = [], 0
    while sum(len(k) for k in kept) < n:
        q = rng.uniform(lo, hi, (batch, model.n_joints))
        draws += batch
        kept.append(q[feasible(cell, model, q)])
    return np.vstack(kept)[:n], draws


@pytest.mark.parametrize("robot, n, seed", [("ur10", 60, 0), ("ur10", 2500, 1), ("abb_irb140", 3, 2),
                                            ("kuka_kr150_r3100", 700, 3)])
def test_sample_feasible_keeps_the_poses_a_check_of_every_draw_keeps(robot, n, seed):
    """The batch is checked by prefixes until enough poses pass: the same poses, in the same order,
    and the same draws as checking the whole batch; also in a cell with a tracker, where few pass."""
    model = load_robot(robot)
    T = model.replace(T_world_base=np.eye(4)).fk(np.zeros(model.n_joints))
    tracker = Instrument(tuple(T[:3, 3] + [2500.0, 0.0, 500.0]), acceptance_deg=40.0)
    for cell in (default_cell((5.0, -10.0, 120.0)), default_cell(instrument=tracker)):
        got, got_draws = sample_feasible(cell, model, n, np.random.default_rng(seed))
        want, want_draws = _sample_whole_batches(cell, model, n, np.random.default_rng(seed))
        assert got_draws == want_draws
        np.testing.assert_array_equal(got, want)
