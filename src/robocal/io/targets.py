"""Cartesian target files (``robocal-targets/1``, read by ``robocal correct``) and the corrected
joint targets it writes (``robocal-corrected-targets/1``); see docs/calibration.md.

Target file: a CSV file like the measurement files, a ``#`` header declaring the units, then one
row per target::

    # format: robocal-targets/1
    # length_unit: mm                 (mm | m)
    # angle_unit: deg                 (deg | rad: Euler / rotation-vector angles, seed joints)
    # orientation: kuka_abc           (optional: a name of robocal.transforms.POSE_CONVENTIONS)
    # frame: world                    (world | base; required unless --frame is given)
    name,x,y,z,rx,ry,rz,J1,J2,J3,J4,J5,J6
    P1,1510.2,-220.0,980.5,180.0,0.0,90.0,10.0,-80.0,95.0,0.0,30.0,0.0

``name`` (optional) names the target; ``x, y, z`` the position; orientation columns (optional,
need ``orientation``) as in measurement files: ``qw, qx, qy, qz`` for ``quaternion``, otherwise
``rx, ry, rz`` holding the convention's three numbers in its order (KUKA A, B, C) in
``angle_unit``. Optional joint columns named as the robot's controller joints (all of them) give
the taught joints, used to seed the solver (branch choice). ``frame: world`` means the calibrated
robot's world frame (for ``robocal calibrate`` output: the instrument frame); ``base`` the robot
base frame. Without orientation the targets are position-only.

Every problem raises :class:`TargetFileError` naming file, line and column; a missing file raises
``FileNotFoundError``.
"""

from __future__ import annotations

import csv
import io
import math
from pathlib import Path

import numpy as np

from ..transforms import ANGLE_UNITS, LENGTH_UNITS, POSE_CONVENTIONS, pose_from_transform, transform_from_pose
from .atomic import atomic_write_text
from .header import FileFormatError, declared_unit, read_header_block, read_text
from .plausibility import angle_unit_problem, length_unit_problem
from .table import check_field_counts, csv_cells, data_rows, number_columns

__all__ = ["TARGETS_FORMAT", "CORRECTED_FORMAT", "TargetFileError", "read_targets", "write_corrected_targets"]

TARGETS_FORMAT = "robocal-targets/1"
CORRECTED_FORMAT = "robocal-corrected-targets/1"

_EULER_COLUMNS = ["rx", "ry", "rz"]
_QUAT_COLUMNS = ["qw", "qx", "qy", "qz"]


class TargetFileError(FileFormatError):
    """A targets file is malformed; the message names file, line and column."""


# ---------------------------------------------------------------------------------------------- reading
def _check_header(md: dict, where: dict, fail) -> tuple:
    """``(length_unit, angle_unit, frame, orientation convention or None)`` of a targets header."""
    if md.get("format", "") != TARGETS_FORMAT:
        fail(f"header must start with '# format: {TARGETS_FORMAT}' (got {md.get('format', 'nothing')!r})")
    for key in ("length_unit", "angle_unit"):
        if key not in md:
            fail(f"header is missing '# {key}: ...'")
    lu = declared_unit(md, where, "length_unit", LENGTH_UNITS, fail)
    au = declared_unit(md, where, "angle_unit", ANGLE_UNITS, fail)
    frame = md.get("frame")  # None: not stated (the command asks for it)
    if frame is not None and frame not in ("world", "base"):
        fail(f"frame {frame!r}: expected world or base", where["frame"])
    conv = md.get("orientation")
    if conv is not None:
        conv = conv.lower()
        if conv not in POSE_CONVENTIONS:
            fail(f"unknown orientation convention {conv!r}; valid: {', '.join(sorted(POSE_CONVENTIONS))}",
                 where["orientation"])
    return lu, au, frame, conv


def _check_columns(cols: list, line: int, conv, robot, fail) -> tuple:
    """``(orientation columns, seed joint columns)`` of the column row ``cols``."""
    for c in ("x", "y", "z"):
        if c not in cols:
            fail(f"missing column {c!r} (columns: {', '.join(cols)})", line)
    ori_cols = [] if conv is None else (_QUAT_COLUMNS if conv == "quaternion" else _EULER_COLUMNS)
    for c in ori_cols:
        if c not in cols:
            fail(f"orientation {conv!r} needs column {c!r}", line)
    if conv is None and any(c in cols for c in _EULER_COLUMNS + _QUAT_COLUMNS):
        fail("orientation columns without '# orientation: <convention>' in the header", line)
    joint_cols = [c for c in robot.controller_joints if c in cols]
    if joint_cols and len(joint_cols) != robot.n_joints:
        missing = [c for c in robot.controller_joints if c not in cols]
        fail(f"seed joint columns must name all joints of {robot.name}; missing {missing}", line)
    known = {"name", "x", "y", "z", *ori_cols, *joint_cols}
    unknown = [c for c in cols if c not in known]
    if unknown:
        fail(f"unknown column(s) {unknown}; expected name, x, y, z, orientation columns, joints "
             f"{list(robot.controller_joints)}", line)
    return ori_cols, joint_cols


def read_targets(path, robot) -> dict:
    """Read a ``robocal-targets/1`` file (module docstring) for ``robot`` (a
    :class:`~robocal.kinematics.RobotModel`, for the seed joint columns).

    Returns {``names`` (N,), ``positions`` (N, 3) [mm], ``rotations`` (N, 3, 3) or None,
    ``q_seed`` (N, n) [rad | mm] or None, ``frame``, ``orientation``, ``length_unit``, ``angle_unit``}.
    """
    path = Path(path)
    text = read_text(path, TargetFileError, what="targets")

    def fail(msg, line=None, column=None):
        raise TargetFileError(path, msg, line or None, column)

    lines = text.splitlines()
    md, where, i = read_header_block(lines, fail)
    lu, au, frame, conv = _check_header(md, where, fail)
    if i >= len(lines):
        fail("no column row")
    cols = csv_cells(lines[i])
    rows = data_rows(lines, i + 1)
    if not rows:
        fail("0 target rows; at least 1 required")
    ori_cols, joint_cols = _check_columns(cols, i + 1, conv, robot, fail)
    check_field_counts(rows, len(cols), i + 1, fail)

    def numbers(names):
        return number_columns(rows, [cols.index(n) for n in names], lambda p, ln, j: fail(p, ln, cols[j]))

    lf, af = LENGTH_UNITS[lu], ANGLE_UNITS[au]
    xyz = numbers(["x", "y", "z"])
    problem = length_unit_problem(np.linalg.norm(xyz, axis=1) * lf, lu, what="target distances from the origin")
    if problem:
        fail(problem, where.get("length_unit"))
    rotations = values = None
    if conv is not None:
        values = np.concatenate([xyz, numbers(ori_cols)], axis=1)
        try:
            T = transform_from_pose(values, conv, length_unit=lu, angle_unit=au)
        except ValueError as exc:
            fail(str(exc))
        rotations = T[:, :3, :3]
    q_seed = None
    if joint_cols:
        q = numbers(list(robot.controller_joints))
        q_seed = np.where(robot.prismatic_joints, q * lf, q * af)
        problem = angle_unit_problem(q_seed[:, ~robot.prismatic_joints], au, what="seed joint values")
        if problem:
            fail(problem, where.get("angle_unit"))
    names = [cells[cols.index("name")] if "name" in cols else str(r + 1) for r, (_, cells) in enumerate(rows)]
    return {"names": names, "positions": xyz * lf, "rotations": rotations, "q_seed": q_seed, "frame": frame,
            "orientation": conv, "length_unit": lu, "angle_unit": au,
            "orientation_values": None if values is None else values[:, 3:]}


# ---------------------------------------------------------------------------------------------- writing
def write_corrected_targets(path, corrected, model, names, *, robot: str, nominal: str, targets: str,
                            length_unit: str, angle_unit: str, orientation: str | None,
                            overwrite: bool = False) -> Path:
    """Write corrected joint targets as ``robocal-corrected-targets/1`` (atomically).

    corrected: a :class:`robocal.calib.outputs.CorrectedTargets` of ``model`` (the calibrated
    robot) for the N targets ``names``. robot, nominal, targets: header texts (calibrated robot
    file, the nominal robot's name, the targets file and frame). Columns: ``name``, the corrected
    joints (``model.controller_joints``, in ``angle_unit``; prismatic in ``length_unit``), the
    filtered Cartesian target for a nominal-model controller in the robot base frame (``x, y, z``
    and orientation columns in ``orientation``, ``quaternion`` if None), ``converged``,
    ``status``, ``position_error_mm``, ``rotation_error_deg``.
    """
    lf, af = LENGTH_UNITS[length_unit], ANGLE_UNITS[angle_unit]
    conv = orientation or "quaternion"
    qf = np.where(model.prismatic_joints, corrected.q / lf, corrected.q / af)
    pose = pose_from_transform(corrected.T_filtered, conv, length_unit=length_unit, angle_unit=angle_unit)
    ori_cols = _QUAT_COLUMNS if conv == "quaternion" else _EULER_COLUMNS
    buf = io.StringIO()
    for key, val in (("format", CORRECTED_FORMAT), ("robot", robot), ("nominal", nominal),
                     ("length_unit", length_unit), ("angle_unit", angle_unit), ("orientation", conv),
                     ("frame", "base (filtered targets: what a controller running the nominal model needs)"),
                     ("targets", targets)):
        buf.write(f"# {key}: {val}\n")
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(["name", *model.controller_joints, "x", "y", "z", *ori_cols, "converged", "status",
                "position_error_mm", "rotation_error_deg"])
    for i, name in enumerate(names):
        w.writerow([name, *(repr(float(v)) for v in qf[i]), *(repr(float(v)) for v in pose[i]),
                    "yes" if corrected.converged[i] else "no", corrected.report[i]["status"],
                    f"{corrected.position_error_mm[i]:.3e}", f"{math.degrees(corrected.rotation_error_rad[i]):.3e}"])
    return atomic_write_text(path, buf.getvalue(), overwrite=overwrite)
