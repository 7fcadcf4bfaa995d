"""Held-spot files of the virtual closed kinematic chain (format ``robocal-spots/1``).

A laser pointer on the flange is steered, configuration after configuration, until its spot
sits on a marked target of a plate; the controller's joints are then logged. One row per held
spot::

    # format: robocal-spots/1
    # robot: abb_irb140
    # angle_unit: deg
    # spot_tolerance_mm: 0.1
    # note: plate p1 parallel to the base XZ plane, 5 targets 50 mm apart
    id,plate,target,J1,J2,J3,J4,J5,J6
    1,p1,t1,82.113,12.930,-20.551,4.208,37.912,-101.700

``plate`` names the plate position (moving the plate starts a new one) and ``target`` the mark
on the plate: a spot is the pair (plate, target), and every spot must be held in two or more
configurations for a chain to close. Joint columns are the robot's controller joints, in
``angle_unit`` (``deg`` or ``rad``; prismatic joints in ``length_unit``, default ``mm``).
``spot_tolerance_mm`` (optional) is the detection tolerance: how far from the mark the spot may
sit when the joints are read (a camera watching the plate, or the eye: 0.05-0.3 mm).

Inside robocal joints are radians (mm for prismatic). Every problem raises
:class:`SpotFileError` naming the file, line and column.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..transforms import ANGLE_UNITS, LENGTH_UNITS
from .atomic import atomic_write_text
from .header import FileFormatError, declared_unit, read_header_block, read_text
from .plausibility import angle_unit_problem
from .rows_check import joint_ranges
from .table import check_field_counts, csv_cells, data_rows, number_columns

__all__ = ["SPOTS_FORMAT", "HeldSpots", "SpotFileError", "canonical_order", "read_spots", "write_spots"]

SPOTS_FORMAT = "robocal-spots/1"
_ID_COLUMNS = ("id", "plate", "target")


class SpotFileError(FileFormatError):
    """A held-spot file is malformed (file, line and column in the message)."""


@dataclass
class HeldSpots:
    """Held spots: ids (H,), plate (H,) and target (H,) labels, joints (H, n_ctrl) [rad | mm];
    joint_names (n_ctrl,); tolerance_mm: the declared detection tolerance (or ``None``);
    metadata: the header's other keys; lines (H,) the file line of every row (0 when built in code)."""

    ids: tuple
    plate: tuple
    target: tuple
    joints: np.ndarray
    joint_names: tuple
    tolerance_mm: float | None = None
    metadata: dict = field(default_factory=dict)
    lines: tuple = ()

    @property
    def n_rows(self) -> int:
        return len(self.ids)

    def subset(self, rows) -> "HeldSpots":
        rows = np.asarray(rows, dtype=int)

        def pick(seq):
            return tuple(seq[i] for i in rows)

        return HeldSpots(pick(self.ids), pick(self.plate), pick(self.target), self.joints[rows], self.joint_names,
                         self.tolerance_mm, dict(self.metadata), pick(self.lines) if self.lines else ())


def canonical_order(spots: HeldSpots) -> np.ndarray:
    """(H,) row indices sorting held spots by plate, target, id and joint values: a calibration on
    ``spots.subset(canonical_order(spots))`` does not depend on the file's row order (issue 29)."""
    keys = [spots.joints[:, j] for j in range(spots.joints.shape[1] - 1, -1, -1)]
    codes = [np.unique(np.asarray(seq, dtype=str), return_inverse=True)[1] for seq in (spots.ids, spots.target,
                                                                                       spots.plate)]
    return np.lexsort(keys + codes)


def read_spots(path, robot=None) -> HeldSpots:
    """Read a ``robocal-spots/1`` file; ``robot``: the :class:`~robocal.kinematics.RobotModel`
    whose controller joints the columns must name (and whose limits the joints must respect)."""
    path = Path(path)

    def fail(message, line=None, column=None):
        raise SpotFileError(path, message, line, column)

    lines = read_text(path, SpotFileError, what="spots").splitlines()
    values, key_line, i = read_header_block(lines, fail)
    fmt = values.get("format")
    if fmt is not None and fmt != SPOTS_FORMAT:
        fail(f"format {fmt!r}, expected {SPOTS_FORMAT!r}", key_line["format"])
    au = declared_unit(values, key_line, "angle_unit", ANGLE_UNITS, fail)
    if au is None:
        fail("no '# angle_unit: deg|rad' header line: the joint unit must be declared")
    lu = declared_unit(values, key_line, "length_unit", LENGTH_UNITS, fail, "mm")
    af, lf = ANGLE_UNITS[au], LENGTH_UNITS[lu]
    if robot is not None and values.get("robot") and values["robot"] != robot.name:
        fail(f"the file is for robot {values['robot']!r}, not {robot.name!r}", key_line["robot"])
    tol = None
    if "spot_tolerance_mm" in values:
        try:
            tol = float(values["spot_tolerance_mm"])
        except ValueError:
            tol = float("nan")
        if not (math.isfinite(tol) and 0.0 < tol < 50.0):
            fail(f"spot_tolerance_mm {values['spot_tolerance_mm']!r}: expected a detection tolerance in mm "
                 "(0 < value < 50)", key_line["spot_tolerance_mm"])
    if i >= len(lines):
        fail("no column row 'id,plate,target,<joints>' (empty file?)")
    cols = csv_cells(lines[i])
    if [c.lower() for c in cols[:3]] != list(_ID_COLUMNS):
        fail(f"the columns must start with 'id,plate,target', got {','.join(cols[:3])!r}", i + 1)
    joint_names = tuple(cols[3:])
    if robot is not None and joint_names != tuple(robot.controller_joints):
        fail(f"joint columns {list(joint_names)} do not match {robot.name}'s controller joints "
             f"{list(robot.controller_joints)}", i + 1)
    if not joint_names:
        fail("no joint columns after 'id,plate,target'", i + 1)
    rows = data_rows(lines, i + 1)
    if not rows:
        fail("no held spots (no data rows)")
    check_field_counts(rows, len(cols), i + 1, fail)
    seen = {}
    for line, cells in rows:
        for c, name in enumerate(_ID_COLUMNS):
            if not cells[c]:
                fail(f"empty {name}", line, name)
        if cells[0] in seen:
            fail(f"id {cells[0]!r} given twice (first on line {seen[cells[0]]})", line, "id")
        seen[cells[0]] = line
    q = number_columns(rows, range(3, len(cols)), lambda problem, ln, j: fail(problem, ln, cols[j]))
    prismatic = np.zeros(len(joint_names), bool) if robot is None else np.asarray(robot.prismatic_joints, bool)
    q = q * np.where(prismatic, lf, af)
    line_nos = [ln for ln, _ in rows]
    problem = angle_unit_problem(q[:, ~prismatic], au, what="joint angles")
    if problem:
        fail(problem, key_line.get("angle_unit"))
    joint_ranges(q, lf, af, line_nos, joint_names, prismatic, robot, au, fail)
    meta = {k: v for k, v in values.items() if k not in ("format", "angle_unit", "length_unit", "spot_tolerance_mm")}
    return HeldSpots(tuple(c[0] for _, c in rows), tuple(c[1] for _, c in rows), tuple(c[2] for _, c in rows), q,
                     joint_names, tol, meta, tuple(line_nos))


def write_spots(path, spots: HeldSpots, *, robot: str | None = None, angle_unit: str = "deg", prismatic=None,
                notes=(), overwrite: bool = False) -> Path:
    """Write ``spots`` as a ``robocal-spots/1`` file (atomically; an existing file needs
    ``overwrite``). angle_unit: ``deg`` or ``rad``; prismatic (n_ctrl,) bool: joints in mm."""
    if angle_unit not in ANGLE_UNITS:
        raise ValueError(f"angle_unit must be one of {list(ANGLE_UNITS)}, got {angle_unit!r}")
    n = len(spots.joint_names)
    prismatic = np.zeros(n, bool) if prismatic is None else np.asarray(prismatic, bool)
    q = spots.joints / np.where(prismatic, 1.0, ANGLE_UNITS[angle_unit])
    head = [f"# format: {SPOTS_FORMAT}"]
    if robot:
        head.append(f"# robot: {robot}")
    head += [f"# angle_unit: {angle_unit}", "# length_unit: mm"]
    if spots.tolerance_mm is not None:
        head.append(f"# spot_tolerance_mm: {spots.tolerance_mm:g}")
    head += [f"# note: {ln}" for note in notes for ln in str(note).splitlines()]
    head.append(",".join(_ID_COLUMNS + tuple(spots.joint_names)))
    body = [",".join([str(a), str(b), str(c)] + [f"{v:.6f}" for v in row])
            for a, b, c, row in zip(spots.ids, spots.plate, spots.target, q)]
    return atomic_write_text(path, "\n".join(head + body) + "\n", overwrite=overwrite)
