"""Cell files (``robocal-cell/1``, docs/cells.md): how a robot is mounted, what stands around it,
where the instrument is, the tool, and the joint ranges the user allows.

::

    format = "robocal-cell/1"
    length_unit = "mm"                  # mm | m
    angle_unit = "deg"                  # deg | rad
    clearance = 10.0                    # distance kept from every obstacle

    [mounting]
    kind = "floor"                      # floor | ceiling | wall | tilted
    xyz = [0.0, 0.0, 0.0]               # robot base origin in the cell frame (z up)
    rpy = [0.0, 0.0, 0.0]               # tilted only: base orientation (roll, pitch, yaw)
    yaw = 0.0                           # floor/ceiling/wall: turn about the mounting normal
    plane = true                        # the mounting plane is an obstacle (default true)

    [[box]]                             # tables, fixtures, fences: axis-aligned in the cell frame
    name = "table"
    min = [600.0, -400.0, 0.0]
    max = [1400.0, 400.0, 750.0]

    [instrument]                        # optional: a laser tracker
    position = [2500.0, 0.0, 500.0]
    range = [1000.0, 15000.0]
    acceptance = 30.0                   # reflector acceptance half angle (1.5" SMR: about 30 deg)
    line_of_sight = true

    [tool]
    points = [[0.0, 0.0, 100.0]]        # in the flange frame; the last point is the reflector
    axis = [0.0, 0.0, 1.0]              # reflector axis in the flange frame
    radius = 25.0                       # tool capsule radius

    [joints]                            # optional: ranges narrower than the robot's limits
    J4 = [-180.0, 180.0]

    [links]
    radius = 60.0                       # optional: every link capsule; or a list per chain segment

Lengths in ``length_unit``, angles in ``angle_unit``; everything is converted to mm / rad.
"""

from __future__ import annotations

import math
import tomllib

import numpy as np

from ..calib.cell import Box, Cell, Instrument
from ..kinematics.links import frame_from_xyz_rpy
from .header import FileFormatError, read_text

__all__ = ["CELL_FORMAT", "CellFileError", "read_cell", "parse_cell", "MOUNTINGS"]

CELL_FORMAT = "robocal-cell/1"
#: Base orientation (roll, pitch, yaw) [deg] of each mounting kind before its ``yaw``.
MOUNTINGS = {"floor": (0.0, 0.0, 0.0), "ceiling": (180.0, 0.0, 0.0), "wall": (0.0, 90.0, 0.0), "tilted": None}
_TOP = {"format", "length_unit", "angle_unit", "clearance", "mounting", "box", "instrument", "tool", "joints",
        "links"}
_SECTIONS = {"mounting": {"kind", "xyz", "rpy", "yaw", "plane"}, "box": {"name", "min", "max"},
             "instrument": {"position", "range", "acceptance", "line_of_sight"},
             "tool": {"points", "axis", "radius"}, "links": {"radius"}}


class CellFileError(FileFormatError):
    """A cell file is malformed: the message names the file and the key."""


def read_cell(path, model) -> Cell:
    """Read the cell file ``path`` for the robot ``model`` (joint names, limits) into a
    :class:`~robocal.calib.cell.Cell` (mm, rad)."""
    text = read_text(path, CellFileError, what="cell")
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise CellFileError(path, f"not valid TOML: {exc}") from None
    return parse_cell(data, model, str(path))


def _vec(fail, key, v, n=3):
    if not isinstance(v, list) or len(v) != n or not all(isinstance(x, (int, float)) and not isinstance(x, bool)
                                                          and math.isfinite(x) for x in v):
        fail(f"{key}: expected {n} numbers, got {v!r}")
    return [float(x) for x in v]


def _num(fail, key, v, positive=False):
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or (positive and v <= 0):
        fail(f"{key}: expected a {'positive ' if positive else ''}number, got {v!r}")
    return float(v)


def _keys(fail, where, d, allowed):
    if not isinstance(d, dict):
        fail(f"{where}: expected a table")
    extra = sorted(set(d) - allowed)
    if extra:
        fail(f"{where}: unknown key(s) {extra}; allowed: {sorted(allowed)}")


def parse_cell(data: dict, model, origin: str = "<cell>") -> Cell:
    """The :class:`~robocal.calib.cell.Cell` of a parsed ``robocal-cell/1`` document."""
    def fail(msg):
        raise CellFileError(origin, msg)

    if data.get("format") != CELL_FORMAT:
        fail(f"'format' is {data.get('format')!r}, expected {CELL_FORMAT!r}")
    _keys(fail, "top level", data, _TOP)
    lu, au = data.get("length_unit", "mm"), data.get("angle_unit", "deg")
    if lu not in ("mm", "m"):
        fail(f"length_unit {lu!r}: expected 'mm' or 'm'")
    if au not in ("deg", "rad"):
        fail(f"angle_unit {au!r}: expected 'deg' or 'rad'")
    ls, as_ = (1000.0 if lu == "m" else 1.0), (math.pi / 180.0 if au == "deg" else 1.0)
    mount = data.get("mounting", {})
    _keys(fail, "[mounting]", mount, _SECTIONS["mounting"])
    kind = mount.get("kind", "floor")
    if kind not in MOUNTINGS:
        fail(f"[mounting] kind {kind!r}: expected one of {', '.join(MOUNTINGS)}")
    xyz = np.array(_vec(fail, "[mounting] xyz", mount.get("xyz", [0.0, 0.0, 0.0]))) * ls
    if kind == "tilted":
        if "rpy" not in mount:
            fail("[mounting] kind 'tilted' needs rpy = [roll, pitch, yaw]")
        rpy = np.array(_vec(fail, "[mounting] rpy", mount["rpy"])) * as_
    else:
        if "rpy" in mount:
            fail(f"[mounting] rpy is for kind 'tilted'; a {kind} mounting takes yaw only")
        rpy = np.radians(MOUNTINGS[kind])
    T = frame_from_xyz_rpy(xyz, rpy)
    if kind != "tilted":
        yaw = _num(fail, "[mounting] yaw", mount.get("yaw", 0.0)) * as_
        c, s = math.cos(yaw), math.sin(yaw)
        Rz = np.array([[c, -s, 0, 0], [s, c, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1.0]])
        T = T @ Rz
    plane_on = mount.get("plane", True)
    if not isinstance(plane_on, bool):
        fail(f"[mounting] plane: expected true or false, got {plane_on!r}")
    # without a plane obstacle, put it far below the robot (nothing ever reaches it)
    normal = T[:3, 2]
    point = xyz if plane_on else xyz - 1e9 * normal
    boxes = []
    raw_boxes = data.get("box", [])
    if not isinstance(raw_boxes, list):
        fail("[[box]]: expected an array of tables")
    for i, b in enumerate(raw_boxes):
        where = f"[[box]] {i + 1}"
        _keys(fail, where, b, _SECTIONS["box"])
        lo = np.array(_vec(fail, f"{where} min", b.get("min"))) * ls
        hi = np.array(_vec(fail, f"{where} max", b.get("max"))) * ls
        if np.any(hi <= lo):
            fail(f"{where}: max must exceed min on every axis")
        boxes.append(Box(str(b.get("name", f"box {i + 1}")), tuple(lo), tuple(hi)))
    instrument = None
    if "instrument" in data:
        ins = data["instrument"]
        _keys(fail, "[instrument]", ins, _SECTIONS["instrument"])
        if "position" not in ins:
            fail("[instrument] needs position = [x, y, z]")
        pos = np.array(_vec(fail, "[instrument] position", ins["position"])) * ls
        rng = np.array(_vec(fail, "[instrument] range", ins.get("range", [1000.0 / ls, 15000.0 / ls]), 2)) * ls
        if not 0 <= rng[0] < rng[1]:
            fail("[instrument] range: expected [nearest, farthest] with 0 <= nearest < farthest")
        acc = _num(fail, "[instrument] acceptance", ins.get("acceptance", 30.0 if au == "deg" else math.radians(30)),
                   positive=True) * as_
        if acc > math.pi:
            fail("[instrument] acceptance: at most 180 deg")
        los = ins.get("line_of_sight", True)
        if not isinstance(los, bool):
            fail(f"[instrument] line_of_sight: expected true or false, got {los!r}")
        instrument = Instrument(tuple(pos), tuple(rng), math.degrees(acc), los)
    tool = data.get("tool", {})
    _keys(fail, "[tool]", tool, _SECTIONS["tool"])
    pts = tool.get("points", [[0.0, 0.0, 100.0 / ls]])
    if not isinstance(pts, list) or not pts:
        fail("[tool] points: expected a list of [x, y, z]")
    pts = tuple(tuple(float(v) * ls for v in _vec(fail, "[tool] points", p)) for p in pts)
    axis = np.array(_vec(fail, "[tool] axis", tool.get("axis", [0.0, 0.0, 1.0])))
    if np.linalg.norm(axis) == 0:
        fail("[tool] axis has zero length")
    radius = _num(fail, "[tool] radius", tool.get("radius", 25.0 / ls), positive=True) * ls
    ranges = None
    if "joints" in data:
        j = data["joints"]
        _keys(fail, "[joints]", j, set(model.controller_joints))
        lim = np.array(model.limits, dtype=float)
        pris = model.prismatic_joints
        for name, v in j.items():
            k = model.controller_joints.index(name)
            lo, hi = _vec(fail, f"[joints] {name}", v, 2)
            if hi <= lo:
                fail(f"[joints] {name}: expected [min, max] with min < max")
            scale = ls if pris[k] else as_
            lim[k] = (lo * scale, hi * scale)
        ranges = lim
    link_r = None
    if "links" in data:
        lk = data["links"]
        _keys(fail, "[links]", lk, _SECTIONS["links"])
        r = lk.get("radius")
        if isinstance(r, list):
            link_r = tuple(_num(fail, "[links] radius", v, positive=True) * ls for v in r)
        elif r is not None:
            link_r = (_num(fail, "[links] radius", r, positive=True) * ls,)
    clearance = _num(fail, "clearance", data.get("clearance", 10.0 / ls)) * ls
    if clearance < 0:
        fail("clearance must be >= 0")
    return Cell(mounting=kind, T_cell_base=T, plane_point=tuple(point), plane_normal=tuple(normal),
                boxes=tuple(boxes), instrument=instrument, tool_mm=pts, tool_axis=tuple(axis / np.linalg.norm(axis)),
                tool_radius_mm=radius, joint_ranges=ranges, link_radii_mm=link_r, clearance_mm=clearance,
                source=str(origin))
