"""``robocal iso9283 plan``: the ISO 9283 test for one robot — cube, poses, sequences, protocol.

The protocol (``protocol.json``, format ``robocal-iso9283-plan/1``) is what the evaluation reads:
the commanded poses in the robot's base frame (mm, rotation matrix), the nominal joints of each on
one arm configuration, and every measurement the test asks for with its identifier. The joint
program (``program.csv``, ``robocal-program/1``) lists the poses in the order the robot drives them.

Test conditions stated in the protocol (ISO 9283 6.2–6.4): the load (100 % of the rated load at
its rated offset unless declared otherwise), the speed (100 % of the rated speed unless declared;
the standard also asks for 50 % and 10 %), warm-up before the test.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from ...io.atomic import atomic_write_text
from ...io.programs.joint_table import JointProgram, write_joint_program
from ...performance.iso_cube import largest_iso_cube, reachable_on_one_branch

__all__ = ["PLAN_FORMAT", "build_iso_plan", "write_iso_plan", "read_iso_plan"]

PLAN_FORMAT = "robocal-iso9283-plan/1"
POSE_NAMES = ("P1", "P2", "P3", "P4", "P5")
#: the cycle order of the pose test (ISO 9283 7.2.1): P1 -> P5 -> P4 -> P3 -> P2
CYCLE_ORDER = ("P1", "P5", "P4", "P3", "P2")
#: approach directions of the multi-directional test (ISO 9283 7.2.3): from +x, +y, +z
DIRECTIONS = {"+x": (1.0, 0.0, 0.0), "+y": (0.0, 1.0, 0.0), "+z": (0.0, 0.0, 1.0)}


def _pose(p, R) -> dict:
    return {"position_mm": [float(v) for v in p], "R": [[float(v) for v in row] for row in R]}


def build_iso_plan(model, *, T_flange_tool=None, cycles: int = 30, path_cycles: int = 10,
                   drift_hours: float = 0.0, drift_interval_min: float = 10.0, load: str | None = None,
                   speed_percent: float = 100.0, min_height_mm: float = 100.0, cell=None) -> dict:
    """The ISO 9283 test plan for ``model`` (in memory).

    Parameters
    ----------
    model : RobotModel
        The nominal model the controller runs.
    T_flange_tool : array_like, shape (4, 4), optional
        The tool whose centre point is measured (the reflector) [mm].
    cycles : int
        Cycles of the pose and distance tests (the standard: 30).
    path_cycles : int
        Cycles of the path tests (the standard: 10).
    drift_hours : float
        Length of the optional drift run (the standard: 8 h); 0 leaves it out.
    load : str, optional
        The load the test assumes, as text (default: the rated load at its rated offset).
    speed_percent : float
        Speed as a share of the rated speed [%].
    cell : robocal.calib.cell.Cell, optional
        The cell (mounting, obstacles, user joint ranges; docs/cells.md). Default: a floor-mounted
        robot whose floor is an obstacle. Every commanded pose and the motion between consecutive
        poses must be feasible in it.

    Returns
    -------
    dict
        The protocol (JSON-ready).
    """
    from ...errors import InputError

    for name, v, lo in (("cycles", cycles, 2), ("path_cycles", path_cycles, 2)):
        if int(v) != v or v < lo or v > 1000:
            raise InputError(f"{name} must be an integer in [{lo}, 1000], got {v}")
    if not 0 < speed_percent <= 100:
        raise InputError(f"speed must be in (0, 100] %, got {speed_percent}")
    if drift_hours < 0 or drift_hours > 48:
        raise InputError(f"drift run must be 0-48 h, got {drift_hours}")
    from ...calib.cell import default_cell, feasible as cell_feasible

    tool_pt = (0.0, 0.0, 0.0) if T_flange_tool is None else tuple(np.asarray(T_flange_tool, float)[:3, 3])
    the_cell = cell if cell is not None else default_cell(tool_pt)

    def feasible(q):
        q = np.atleast_2d(q)
        lim = the_cell.limits(model)
        inside = np.all((q >= lim[:, 0] - 1e-9) & (q <= lim[:, 1] + 1e-9), axis=1)
        return inside & cell_feasible(the_cell, model, q)

    cube = largest_iso_cube(model, T_flange_tool=T_flange_tool, min_height_mm=min_height_mm, feasible=feasible)
    c, L, R = cube.centre_mm, cube.edge_mm, cube.R_base_tool
    from ...performance.iso_cube import iso_test_poses

    P = iso_test_poses(c, L)
    d_approach = max(0.1 * L, 20.0)
    # every position the robot is commanded to (poses, approach points, path points): one branch
    path_line = np.linspace(P[1], P[3], 41)
    u = (P[3] - P[1]) / np.linalg.norm(P[3] - P[1])                  # in the test plane, along a diagonal
    n_plane = np.cross(P[2] - P[1], P[4] - P[1])
    n_plane /= np.linalg.norm(n_plane)
    v = np.cross(n_plane, u)
    radius = 0.4 * L
    ang = np.linspace(0.0, 2 * np.pi, 73)
    path_circle = c + radius * (np.cos(ang)[:, None] * u + np.sin(ang)[:, None] * v)
    approach = {f"{name}{d}": P[i] + d_approach * np.array(vec) for i, name in ((0, "P1"), (1, "P2"), (3, "P4"))
                for d, vec in DIRECTIONS.items()}
    all_pts = np.vstack([P, np.array(list(approach.values())), path_line, path_circle])
    found = reachable_on_one_branch(model, all_pts, R, T_flange_tool, feasible=feasible)
    if found is None:
        raise InputError(f"{model.name}: the ISO test's poses are not reachable on one arm configuration "
                         f"(cube {L:.0f} mm at {np.round(c, 1).tolist()} mm)")
    q_all = _continuous(found[0], model, the_cell.limits(model), first_path=5 + len(approach),
                        path_lengths=(len(path_line), len(path_circle)))
    q_pose = {name: q_all[i] for i, name in enumerate(POSE_NAMES)}
    q_app = {k: q_all[5 + i] for i, k in enumerate(approach)}
    k0 = 5 + len(approach)
    q_line = q_all[k0:k0 + len(path_line)]
    q_circle = q_all[k0 + len(path_line):]
    measurements = []
    for k in range(1, cycles + 1):
        for name in CYCLE_ORDER:
            measurements.append({"id": f"pose.c{k:02d}.{name}", "test": "pose", "pose": name, "cycle": k})
    for name in ("P1", "P2", "P4"):
        for d in DIRECTIONS:
            for k in range(1, cycles + 1):
                measurements.append({"id": f"vap.{name}.{d}.c{k:02d}", "test": "vap", "pose": name, "direction": d,
                                     "cycle": k, "approach_from": f"{name}{d}"})
    n_blocks = int(np.floor(drift_hours * 60.0 / drift_interval_min)) + 1 if drift_hours > 0 else 0
    for b in range(n_blocks):
        for k in range(1, 11):
            measurements.append({"id": f"drift.b{b:03d}.c{k:02d}", "test": "drift", "pose": "P1", "block": b,
                                 "cycle": k, "time_min": b * drift_interval_min})
    for kind in ("line", "circle"):
        for k in range(1, path_cycles + 1):
            measurements.append({"id": f"{kind}.c{k:02d}", "test": kind, "cycle": k, "continuous": True})
    return {
        "format": PLAN_FORMAT, "robot": model.name, "frame": "base", "length_unit": "mm",
        "conditions": {
            "load": load or "100 % of the rated load at its rated centre-of-gravity offset (ISO 9283 6.2)",
            "speed_percent_of_rated": float(speed_percent),
            "warm_up": "run the robot until its temperature is stable before the test (ISO 9283 6.3)",
            "measurement_frame": "the robot's base frame (register the instrument to it before the test)"},
        "cube": {"centre_mm": [float(v) for v in c], "edge_mm": float(L), "branch": int(cube.branch)},
        "tool": None if T_flange_tool is None else np.asarray(T_flange_tool, float).tolist(),
        "poses": {name: dict(_pose(P[i], R), joints_rad=[float(x) for x in q_pose[name]])
                  for i, name in enumerate(POSE_NAMES)},
        "approach_points": {k: dict(_pose(approach[k], R), joints_rad=[float(x) for x in q_app[k]]) for k in approach},
        "paths": {
            "line": {"from": "P2", "to": "P4", "points_mm": path_line.tolist(), "joints_rad": q_line.tolist(),
                     "evaluation_points": 10},
            "circle": {"centre_mm": [float(x) for x in c], "radius_mm": float(radius), "normal": n_plane.tolist(),
                       "points_mm": path_circle.tolist(), "joints_rad": q_circle.tolist(), "evaluation_points": 12}},
        "cycles": int(cycles), "path_cycles": int(path_cycles), "drift_hours": float(drift_hours),
        "drift_interval_min": float(drift_interval_min),
        "measurements": measurements,
    }


def _continuous(q, model, limits, *, first_path: int, path_lengths) -> np.ndarray:
    """Joint targets without whole-turn jumps: every pose and approach point the 2 pi equivalent
    nearest P1's joints, every path point the one nearest the previous path point (a closed-form
    solution wraps a wrist joint at +-180 deg; interpolated, that jump would swing the tool round).

    Raises
    ------
    robocal.errors.InputError
        When a path cannot be driven without a jump of more than 20 deg between neighbouring points
        (a joint limit in the way).
    """
    from ...calib.cell import nearest_equivalent
    from ...errors import InputError

    revolute = ~np.asarray(model.prismatic_joints, dtype=bool)
    q = nearest_equivalent(q, q[0], limits, revolute)
    start = first_path
    for n in path_lengths:
        for i in range(start + 1, start + n):
            q[i] = nearest_equivalent(q[i:i + 1], q[i - 1], limits, revolute)[0]
        jump = np.degrees(np.abs(np.diff(q[start:start + n][:, revolute], axis=0))).max()
        if jump > 20.0:
            raise InputError(f"{model.name}: an ISO test path needs a joint to jump {jump:.0f} deg between neighbouring "
                             "points (a joint limit in the way); give a smaller --min-height or a cell with other "
                             "joint ranges")
        start += n
    return q


def _program_rows(protocol: dict) -> tuple[list, list]:
    """The joint targets in driving order, with the point names (approach, pose, pose ...)."""
    names, q = [], []
    for m in protocol["measurements"]:
        if m["test"] == "pose":
            names.append(m["id"])
            q.append(protocol["poses"][m["pose"]]["joints_rad"])
        elif m["test"] == "vap":
            names.append(m["id"] + ".approach")
            q.append(protocol["approach_points"][m["approach_from"]]["joints_rad"])
            names.append(m["id"])
            q.append(protocol["poses"][m["pose"]]["joints_rad"])
    return names, q


def write_iso_plan(out_dir, protocol: dict, model, *, overwrite: bool = False, language: str | None = None,
                   inputs=None) -> dict:
    """Write ``protocol.json`` and the joint program ``program.csv`` into ``out_dir`` (atomically);
    with ``language`` (krl, rapid, tp, urscript) also the test as a robot program (``iso9283.<suffix>``:
    joint targets in driving order, a wait/trigger comment at each point). ``inputs``: the command's
    input paths (``{option: path}``); an output that is one of them is refused even with ``overwrite``."""
    from ...io.programs.campaign import CAMPAIGN_LANGUAGES, write_campaign_program
    from ..outputs import check_output_folder, ensure_writable_dir

    out = Path(out_dir)
    program_names = []
    if language is not None:
        suffix = CAMPAIGN_LANGUAGES[language][1]
        program_names = [f"iso9283{suffix}"] + (["iso9283.src"] if language == "krl" else [])
    check_output_folder(out, ["protocol.json", "program.csv"] + program_names, inputs or {}, overwrite)
    ensure_writable_dir(out)
    names, q = _program_rows(protocol)
    files = {}
    if language is not None:
        # identifiers every controller accepts: letters, digits, underscores
        ids = [n.replace(".", "_").replace("+", "p") for n in names]
        files["robot_program"] = [str(p) for p in write_campaign_program(
            out / "iso9283.csv", language, np.array(q), ids, overwrite=overwrite, prismatic=model.prismatic_joints)]
    prog = JointProgram(np.array(q), tuple(names), tuple(model.controller_joints),
                        {"robot": model.name, "angle_unit": "deg",
                         "note": "ISO 9283 test: measure at every point not ending in '.approach' "
                                 "(wait for the robot to settle, then trigger the instrument)"})
    write_joint_program(out / "program.csv", prog, model, overwrite=overwrite)
    atomic_write_text(out / "protocol.json", json.dumps(protocol, indent=1) + "\n", overwrite=overwrite)
    return {"protocol": str(out / "protocol.json"), "program": str(out / "program.csv"), **files}


def read_iso_plan(path) -> dict:
    """Read a ``protocol.json`` (a folder holding one is accepted)."""
    from ...errors import InputFileError

    p = Path(path)
    if p.is_dir():
        p = p / "protocol.json"
    try:
        d = json.loads(p.read_text(encoding="utf-8"))
    except json.JSONDecodeError as exc:
        raise InputFileError(f"{p}: not a JSON ISO 9283 plan ({exc})") from None
    if not isinstance(d, dict) or d.get("format") != PLAN_FORMAT:
        raise InputFileError(f"{p}: not an ISO 9283 plan (expected format {PLAN_FORMAT!r}; "
                             "write one with `robocal iso9283 plan`)")
    return d
