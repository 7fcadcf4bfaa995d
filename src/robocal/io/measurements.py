"""Measurement files (format ``robocal-measurements/1``, see docs/measurement-files.md).

A measurement file is a CSV file: a header block of ``# key: value`` lines declaring the format,
robot and units, then one CSV header row naming the columns, then one row per robot pose::

    # format: robocal-measurements/1
    # robot: kuka_kr150_r3100
    # length_unit: mm
    # angle_unit: deg
    # instrument: laser tracker
    # frame: tracker
    pose,A1,A2,A3,A4,A5,A6,x,y,z
    1,12.5,-90.0,95.0,0.0,30.0,0.0,2512.113,-803.377,1422.901

Inside robocal (the :class:`Measurements` arrays) lengths are millimetres and angles radians;
the file's declared units are converted on reading and writing. Every problem in a file raises
:class:`MeasurementFileError` naming the file, the line (1-based, counted in the file) and the
column. Writing never replaces an existing file unless ``overwrite=True`` and never leaves a
half-written file: the text goes to a temporary file in the same directory, then is renamed.
"""

from __future__ import annotations

import csv
import difflib
import io
import math
import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .atomic import atomic_write_text
from .plausibility import angle_unit_problem, length_unit_problem
from .header import KEY_RE, FileFormatError, declared_unit, open_text, read_header_block
from .rows_check import duplicate_rows, joint_ranges
from .stream import MAX_ROWS, read_numeric_table
from .table import csv_cells
from ..transforms import (
    ANGLE_UNITS,
    LENGTH_UNITS,
    POSE_CONVENTIONS,
    euler_from_matrix,
    matrix_from_euler,
    matrix_from_quaternion,
    matrix_from_rotvec,
    quaternion_from_matrix,
    rotvec_from_matrix,
)

__all__ = [
    "FORMAT",
    "DEFAULT_TARGET",
    "Measurements",
    "MeasurementFileError",
    "read_measurements",
    "write_measurements",
    "atomic_write_text",
]

FORMAT = "robocal-measurements/1"
#: Name of the single target whose columns are plain ``x, y, z``.
DEFAULT_TARGET = "point"

_REQUIRED_KEYS = ("format", "robot", "length_unit", "angle_unit")
# Keys written first, in this order; any other key follows, then the notes.
_KEY_ORDER = ("format", "robot", "length_unit", "angle_unit", "prismatic", "orientation", "instrument", "frame")
_TARGET_RE = re.compile(r"^[A-Za-z][A-Za-z0-9]*$")
_EULER_COLUMNS = ("rx", "ry", "rz")
_QUAT_COLUMNS = ("qw", "qx", "qy", "qz")
_AXES = ("x", "y", "z")



class MeasurementFileError(FileFormatError):
    """A measurement file is malformed or implausible (file, line and column in the message)."""


# ---------------------------------------------------------------------------------------------
# the in-memory form
# ---------------------------------------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class Measurements:
    """Measured points (and optionally orientations) for a sequence of robot poses.

    joints: (N, n) controller joint values [rad | mm (prismatic)], columns ``joint_names``.
    points: (N, k, 3) measured target positions [mm] in the instrument frame, one per target.
    targets: k target names (``DEFAULT_TARGET`` for a single plain ``x, y, z`` target).
    joint_names: n controller joint names, in column order of ``joints``.
    pose_ids: N pose identifiers (strings; default ``"1" .. "N"``).
    rotations: optional (N, 3, 3) measured orientations in the instrument frame.
    prismatic: (n,) bool, which joints are prismatic (values in mm, not rad).
    metadata: header values as strings (``robot``, ``instrument``, ``frame``, ``note``,
        ``orientation``, ...). ``length_unit`` / ``angle_unit`` here only record the units of
        the file this came from; the arrays are always mm / rad.
    """

    joints: np.ndarray
    points: np.ndarray
    targets: tuple = (DEFAULT_TARGET,)
    joint_names: tuple = ()
    pose_ids: tuple = ()
    rotations: np.ndarray | None = None
    prismatic: np.ndarray | None = None
    metadata: dict = field(default_factory=dict)

    def __post_init__(self):
        set_ = object.__setattr__
        q = np.array(self.joints, dtype=float)
        if q.ndim != 2:
            raise ValueError(f"Measurements.joints: expected shape (N, n_joints), got {q.shape}")
        N, n = q.shape
        p = np.array(self.points, dtype=float)
        if p.ndim == 2 and p.shape[-1] == 3:
            p = p[:, None, :]
        if p.ndim != 3 or p.shape[0] != N or p.shape[2] != 3:
            raise ValueError(f"Measurements.points: expected shape ({N}, k, 3), got {p.shape}")
        for name, arr in (("joints", q), ("points", p)):
            if not np.all(np.isfinite(arr)):
                raise ValueError(f"Measurements.{name}: contains NaN or infinite values")
        targets = _checked_targets(self.targets, p.shape[1])
        names = tuple(str(j) for j in self.joint_names) or tuple(f"J{i + 1}" for i in range(n))
        if len(names) != n:
            raise ValueError(f"Measurements.joint_names: {len(names)} names for {n} joint columns")
        if len(set(names)) != n:
            raise ValueError(f"Measurements.joint_names: duplicate names in {names}")
        ids = tuple(str(i) for i in self.pose_ids) or tuple(str(i + 1) for i in range(N))
        if len(ids) != N:
            raise ValueError(f"Measurements.pose_ids: {len(ids)} ids for {N} poses")
        for i in ids:
            if not i.strip() or "\n" in i or "\r" in i:
                raise ValueError(f"Measurements.pose_ids: {i!r} is not a valid pose id (empty or multi-line)")
        R = None
        if self.rotations is not None:
            R = np.array(self.rotations, dtype=float)
            if R.shape != (N, 3, 3):
                raise ValueError(f"Measurements.rotations: expected shape ({N}, 3, 3), got {R.shape}")
            if not np.all(np.isfinite(R)):
                raise ValueError("Measurements.rotations: contains NaN or infinite values")
            R.setflags(write=False)
        pr = np.zeros(n, dtype=bool) if self.prismatic is None else np.array(self.prismatic, dtype=bool)
        if pr.shape != (n,):
            raise ValueError(f"Measurements.prismatic: expected shape ({n},), got {pr.shape}")
        for arr in (q, p, pr):
            arr.setflags(write=False)
        set_(self, "joints", q)
        set_(self, "points", p)
        set_(self, "targets", targets)
        set_(self, "joint_names", names)
        set_(self, "pose_ids", ids)
        set_(self, "rotations", R)
        set_(self, "prismatic", pr)
        set_(self, "metadata", {str(k): str(v) for k, v in dict(self.metadata).items()})

    @property
    def n_poses(self) -> int:
        return self.joints.shape[0]

    @property
    def n_targets(self) -> int:
        return self.points.shape[1]

    @property
    def robot(self) -> str | None:
        return self.metadata.get("robot")

    def __len__(self) -> int:
        return self.n_poses

    def subset(self, index) -> "Measurements":
        """The poses selected by ``index`` (indices, slice or boolean mask), same metadata."""
        idx = np.arange(self.n_poses)[index]
        return Measurements(
            joints=self.joints[idx], points=self.points[idx], targets=self.targets,
            joint_names=self.joint_names, pose_ids=[self.pose_ids[i] for i in np.atleast_1d(idx)],
            rotations=None if self.rotations is None else self.rotations[idx],
            prismatic=self.prismatic, metadata=self.metadata,
        )


def _checked_targets(targets, k: int) -> tuple:
    """The ``k`` target names as strings: unique, letters and digits starting with a letter."""
    targets = tuple(str(t) for t in targets)
    if len(targets) != k:
        raise ValueError(f"Measurements.targets: {len(targets)} names for {k} targets")
    if len(set(targets)) != len(targets):
        raise ValueError(f"Measurements.targets: duplicate names in {targets}")
    for t in targets:
        if not _TARGET_RE.match(t):
            raise ValueError(f"Measurements.targets: {t!r} is not a valid target name (letters and digits, "
                             "starting with a letter)")
    return targets


# ---------------------------------------------------------------------------------------------
# writing
# ---------------------------------------------------------------------------------------------


def _orientation_columns(convention: str) -> tuple:
    return _QUAT_COLUMNS if convention == "quaternion" else _EULER_COLUMNS


def _check_convention(convention) -> str:
    key = str(convention).strip().lower()
    if key not in POSE_CONVENTIONS:
        raise ValueError(f"unknown orientation convention {convention!r}; valid names: "
                         f"{', '.join(sorted(POSE_CONVENTIONS))}")
    return key


def _point_columns(targets) -> list:
    if len(targets) == 1 and targets[0] == DEFAULT_TARGET:
        return list(_AXES)
    return [f"{t}_{a}" for t in targets for a in _AXES]


def write_measurements(path, meas: Measurements, *, length_unit: str | None = None,
                       angle_unit: str | None = None, orientation: str | None = None,
                       overwrite: bool = False, float_format: str | None = None,
                       metadata: dict | None = None) -> Path:
    """Write ``meas`` to the CSV measurement file ``path`` (atomically).

    length_unit: "mm" or "m" for points and prismatic joints (default: ``meas.metadata`` or mm).
    angle_unit: "deg" or "rad" for revolute joints and Euler / rotation-vector angles
        (default: ``meas.metadata`` or deg).
    orientation: convention of the orientation columns when ``meas.rotations`` is set (a name of
        ``robocal.transforms.POSE_CONVENTIONS``; default: ``meas.metadata`` or "quaternion").
    overwrite: replace an existing file; otherwise ``FileExistsError``.
    float_format: a ``format()`` spec for numbers such as ``".6f"``; default ``None`` writes the
        shortest text that reads back to the identical float (exact round trip); ``"short"`` the
        shortest text within 1e-12 (relative) of the value: no unit-conversion noise
        (``255.371``, not ``255.37100000000004``), far below any instrument's resolution.
    metadata: extra or replacing header entries (``instrument``, ``frame``, ``note``, ...).
    """
    md, lu, au, conv = _header_values(meas, metadata, length_unit, angle_unit, orientation)
    columns, data = _data_block(meas, conv, LENGTH_UNITS[lu], ANGLE_UNITS[au])
    fmt = (repr if float_format is None else short_number if float_format == "short"
           else (lambda v: format(v, float_format)))
    buf = io.StringIO()
    buf.write("\n".join(_header_lines(md)) + "\n")
    writer = csv.writer(buf, lineterminator="\n")
    writer.writerow(columns)
    for pid, row in zip(meas.pose_ids, data.tolist()):
        writer.writerow([pid, *(fmt(v) for v in row)])
    return atomic_write_text(path, buf.getvalue(), overwrite=overwrite)


def short_number(v: float, rel: float = 1e-12) -> str:
    """The shortest decimal text of ``v`` within ``rel`` (relative; absolute below 1) of it."""
    v = float(v)
    tol = rel * max(1.0, abs(v))
    if not math.isfinite(v) or abs(v) >= 1e15:
        return repr(v)
    for places in range(0, 16):
        text = f"{v:.{places}f}"
        if abs(float(text) - v) <= tol:
            return "0" if float(text) == 0.0 else text
    return repr(v)


def _header_values(meas: Measurements, metadata, length_unit, angle_unit, orientation) -> tuple:
    """``(header values, length_unit, angle_unit, orientation convention or None)`` of the file
    :func:`write_measurements` writes: ``meas.metadata`` updated by ``metadata`` and the units."""
    md = dict(meas.metadata)
    md.update({str(k): str(v) for k, v in (metadata or {}).items()})
    lu = length_unit or md.get("length_unit", "mm")
    au = angle_unit or md.get("angle_unit", "deg")
    if lu not in LENGTH_UNITS:
        raise ValueError(f"unknown length_unit {lu!r}; valid: {', '.join(LENGTH_UNITS)}")
    if au not in ANGLE_UNITS:
        raise ValueError(f"unknown angle_unit {au!r}; valid: {', '.join(ANGLE_UNITS)}")
    if "robot" not in md or not md["robot"].strip():
        raise ValueError("write_measurements: metadata must name the robot (metadata={'robot': ...})")
    md["format"] = FORMAT
    md["length_unit"], md["angle_unit"] = lu, au
    md.pop("prismatic", None)
    if meas.prismatic.any():
        md["prismatic"] = ", ".join(n for n, p in zip(meas.joint_names, meas.prismatic) if p)
    conv = None
    if meas.rotations is not None:
        conv = _check_convention(orientation or md.get("orientation", "quaternion"))
        md["orientation"] = conv
    else:
        md.pop("orientation", None)
    clash = {"pose"} & set(meas.joint_names) | set(_point_columns(meas.targets)) & set(meas.joint_names)
    if clash:
        raise ValueError(f"write_measurements: joint names {sorted(clash)} clash with other column names")
    return md, lu, au, conv


def _header_lines(md: dict) -> list:
    """The ``# key: value`` lines of ``md``: :data:`_KEY_ORDER` first, then the other keys sorted,
    then the ``note`` lines."""
    md = dict(md)
    lines = []
    notes = md.pop("note", None)
    for key in list(_KEY_ORDER) + sorted(k for k in md if k not in _KEY_ORDER):
        if key not in md:
            continue
        value = md[key]
        if "\n" in value or "\r" in value:
            raise ValueError(f"write_measurements: metadata {key!r} must be a single line (use 'note' for text)")
        if not KEY_RE.match(f"# {key}: x"):
            raise ValueError(f"write_measurements: metadata key {key!r} is not a valid header key")
        lines.append(f"# {key}: {value}")
    if notes:
        lines.extend(f"# note: {line}".rstrip() for line in notes.splitlines())
    return lines


def _data_block(meas: Measurements, conv, lf: float, af: float) -> tuple:
    """``(column names, values (N, n_columns - 1) in file units)`` of the data rows (pose ids aside)."""
    q = np.where(meas.prismatic, meas.joints / lf, meas.joints / af)
    blocks = [q, meas.points.reshape(meas.n_poses, -1) / lf]
    columns = ["pose", *meas.joint_names, *_point_columns(meas.targets)]
    if conv is not None:
        columns += list(_orientation_columns(conv))
        if conv == "quaternion":
            blocks.append(quaternion_from_matrix(meas.rotations))
        elif conv == "rotvec":
            blocks.append(rotvec_from_matrix(meas.rotations) / af)
        else:
            blocks.append(euler_from_matrix(meas.rotations, conv) / af)
    return columns, np.concatenate(blocks, axis=1)


# ---------------------------------------------------------------------------------------------
# reading
# ---------------------------------------------------------------------------------------------


def read_measurements(path, robot=None, *, min_rows: int = 1, drop_duplicates: bool = False,
                      max_rows: int = MAX_ROWS, check_limits: bool = False) -> Measurements:
    """Read a measurement file; arrays come back in mm / rad.

    robot: optional :class:`~robocal.kinematics.RobotModel`. When given, the joint columns must be
        exactly its controller joints (any order; returned in the model's order), prismatic
        joints are taken from the model, the file's ``robot:`` must match ``robot.name``
        unless the file names a path; with ``check_limits`` joint values must lie within its limits.
    min_rows: fewer data rows than this is an error; max_rows: more is an error (the file is
        streamed: memory grows with the rows kept, not with the text).
    drop_duplicates: duplicate pose ids and duplicate rows are an error unless this is true; then
        every repeat after the first is dropped and reported in ``metadata["dropped_duplicates"]``
        (:mod:`robocal.io.rows_check`).

    Steps: header block (:func:`_check_header`; none at all: :func:`_fail_plain_export`), column
    row (:func:`_read_columns`), data rows (:func:`robocal.io.stream.read_numeric_table`),
    duplicates, numbers in file units converted to mm / rad (:func:`_joints_and_points`),
    plausibility of the declared units (:func:`_check_units_plausible`), joint ranges,
    orientations (:func:`_rotations`).
    Raises :class:`MeasurementFileError` (a ``ValueError``) naming file, line and column; a
    missing file raises ``FileNotFoundError``.
    """
    path = Path(path)

    def fail(message, line=None, column=None):
        raise MeasurementFileError(path, message, line, column)

    with open_text(path, MeasurementFileError, what="measurement") as fh:
        try:
            head = _head_lines(fh)
            md, key_line, i = read_header_block(head, fail)
            if not md:
                _fail_plain_export(head, i, fail)
            lu, au, conv = _check_header(md, key_line, robot, fail)
            if i >= len(head):
                fail("no column header row after the '#' header block")
            layout = _read_columns(head[i], i + 1, md, key_line, conv, robot, fail)
            table = read_numeric_table(fh, i + 2, len(layout.columns), lambda m, ln, j: fail(
                m, ln, None if j is None else layout.columns[j]), max_rows=max_rows, header_line=i + 1)
        except UnicodeDecodeError as exc:
            fail(f"not a UTF-8 text file ({exc.reason})")
    table = duplicate_rows(table, drop_duplicates, md, fail)
    if len(table) < max(min_rows, 1):
        fail(f"{len(table)} data row(s); at least {max(min_rows, 1)} required")
    if "" in table.ids:
        fail("empty pose id", int(table.lines[table.ids.index("")]), "pose")
    q, points = _joints_and_points(table, layout, LENGTH_UNITS[lu], ANGLE_UNITS[au], fail)
    _check_units_plausible(q, points, table, layout, lu, au, key_line, fail)
    joint_ranges(q, LENGTH_UNITS[lu], ANGLE_UNITS[au], table.lines, layout.joint_names, layout.prismatic, robot if check_limits else None, au,
                 fail)
    rotations = None if conv is None else _rotations(table, layout, conv, ANGLE_UNITS[au], fail)
    ids = table.ids
    del table  # memory: the file's table goes before the Measurements copies its arrays
    return Measurements(joints=q, points=points, targets=layout.targets, joint_names=layout.joint_names,
                        pose_ids=ids, rotations=rotations, prismatic=layout.prismatic, metadata=md)


def _head_lines(fh) -> list:
    """The lines of ``fh`` up to and including the first that is neither blank nor ``#`` (the
    column row); the rest of ``fh`` is the data."""
    head = []
    for raw in fh:
        head.append(raw.rstrip("\r\n"))
        s = raw.strip()
        if s and not s.startswith("#"):
            break
    return head


def _fail_plain_export(lines, i: int, fail):
    """A file without any header block: a plain export given as a measurement file."""
    start = lines[i].strip()[:60] if i < len(lines) else ""
    fail(f"no '# format: {FORMAT}' header line" + (f" (the file starts with {start!r})" if start else "")
         + "; this looks like a plain export: declare the format with the header lines '# format: "
         f"{FORMAT}', '# robot: ...', '# length_unit: mm', '# angle_unit: deg' above the column row "
         "(docs/measurement-files.md), or convert the export with 'robocal import' (docs/importers.md)", 1)


def _check_header(md: dict, key_line: dict, robot, fail) -> tuple:
    """``(length_unit, angle_unit, orientation convention or None)`` of a measurement header;
    ``md["orientation"]`` is normalised to the convention's name."""
    for key in _REQUIRED_KEYS:
        if key not in md or not md[key]:
            fail(f"header is missing '# {key}: ...' (required: {', '.join(_REQUIRED_KEYS)})")
    if md["format"] != FORMAT:
        fail(f"format {md['format']!r} is not supported; expected {FORMAT!r}", key_line["format"])
    lu = declared_unit(md, key_line, "length_unit", LENGTH_UNITS, fail)
    au = declared_unit(md, key_line, "angle_unit", ANGLE_UNITS, fail)
    conv = None
    if "orientation" in md:
        conv = md["orientation"].strip().lower()
        if conv not in POSE_CONVENTIONS:
            fail(f"unknown orientation convention {md['orientation']!r}; valid: {', '.join(sorted(POSE_CONVENTIONS))}",
                 key_line["orientation"])
        md["orientation"] = conv
    if robot is not None:
        file_robot = md["robot"]
        if file_robot != robot.name and not (file_robot.endswith(".toml") or "/" in file_robot):
            fail(f"file is for robot {file_robot!r} but robot model {robot.name!r} was given", key_line["robot"])
    return lu, au, conv


@dataclass(frozen=True)
class _Layout:
    """What the column row says: ``columns`` (names in file order), ``index`` (name -> position),
    the joint columns (file order) and names (returned order), the targets with their
    ``(x, y, z)`` columns, the orientation columns and which joints are prismatic."""

    columns: list
    index: dict
    joint_cols: list
    joint_names: list
    targets: list
    point_cols: list
    ori_cols: list
    prismatic: np.ndarray


def _read_columns(line: str, line_no: int, md: dict, key_line: dict, conv, robot, fail) -> _Layout:
    """The column row: pose, joint, point and orientation columns, checked (robot: its joints)."""
    columns = csv_cells(line)
    seen: dict[str, int] = {}
    for j, c in enumerate(columns):
        if not c:
            fail(f"column {j + 1} has an empty name", line_no)
        if c in seen:
            fail(f"column name given twice (columns {seen[c] + 1} and {j + 1})", line_no, c)
        seen[c] = j
    if "pose" not in seen:
        fail("missing column 'pose' (pose identifiers)", line_no)
    if seen["pose"] != 0:
        fail("'pose' must be the first column", line_no, "pose")
    ori_cols = _check_orientation_columns(seen, conv, line_no, fail)
    rest = [c for c in columns[1:] if c not in ori_cols]
    joint_cols, targets, point_cols = _joint_and_point_columns(rest, seen, robot, line_no, fail)
    joint_names = joint_cols if robot is None else list(robot.controller_joints)
    prismatic = _prismatic_joints(md, key_line, joint_names, robot, fail)
    return _Layout(columns, seen, joint_cols, joint_names, targets, point_cols, ori_cols, prismatic)


def _check_orientation_columns(seen: dict, conv, line_no: int, fail) -> list:
    """The orientation columns the convention ``conv`` needs (none without one), all present."""
    if conv is None:
        found = [c for c in (*_EULER_COLUMNS, *_QUAT_COLUMNS) if c in seen]
        if found:
            fail(f"orientation columns {found} but no '# orientation: <convention>' in the header", line_no, found[0])
        return []
    ori_cols = list(_orientation_columns(conv))
    missing = [c for c in ori_cols if c not in seen]
    if missing:
        fail(f"orientation {conv!r} needs columns {ori_cols}; missing {missing}", line_no, missing[0])
    wrong = [c for c in (_QUAT_COLUMNS if conv != "quaternion" else _EULER_COLUMNS) if c in seen]
    if wrong:
        fail(f"column does not belong to orientation {conv!r} (expected {ori_cols})", line_no, wrong[0])
    return ori_cols


def _joint_and_point_columns(rest: list, seen: dict, robot, line_no: int, fail) -> tuple:
    """``(joint columns, targets, point columns per target)`` of the columns ``rest`` (neither
    pose nor orientation). With ``robot`` the joint columns are its controller joints and any
    other non-point column is an error; without, every non-point column is a joint."""
    joint_cols: list[str] = []
    if robot is not None:
        expected = list(robot.controller_joints)
        joint_cols = [c for c in rest if c in expected]
        missing = [c for c in expected if c not in seen]
        if missing:
            unknown = [c for c in rest if c not in expected and not _is_point_column(c)]
            hint = f"; the file has {unknown}" if unknown else ""
            fail(f"missing joint column(s) {missing} of robot {robot.name!r} "
                 f"(its controller joints are {expected}){hint}", line_no, missing[0])
    try:
        targets, point_cols, leftovers = _classify_point_columns([c for c in rest if c not in joint_cols])
    except _ColumnProblem as exc:
        fail(exc.message, line_no, exc.column)
    if robot is None:
        joint_cols, leftovers = leftovers, []
    if leftovers:
        c = leftovers[0]
        close = difflib.get_close_matches(c, list(robot.controller_joints), n=2)
        hint = f"; did you mean {', '.join(close)}?" if close else ""
        fail(f"unknown column: not a joint of robot {robot.name!r} ({', '.join(robot.controller_joints)}), "
             f"a point column (x, y, z or <target>_x ...) or an orientation column{hint}", line_no, c)
    if not targets:
        fail("no point columns: expected x, y, z or <target>_x, <target>_y, <target>_z", line_no)
    if not joint_cols:
        fail("no joint columns", line_no)
    return joint_cols, targets, point_cols


def _prismatic_joints(md: dict, key_line: dict, joint_names: list, robot, fail) -> np.ndarray:
    """(n,) bool: the joints the header's ``prismatic`` key names, or the robot's (which the key,
    if given, must agree with)."""
    declared = [s.strip() for s in md.get("prismatic", "").split(",") if s.strip()]
    for name in declared:
        if name not in joint_names:
            fail(f"'prismatic' names {name!r}, which is not a joint column ({', '.join(joint_names)})",
                 key_line["prismatic"])
    if robot is None:
        return np.array([n in declared for n in joint_names], dtype=bool)
    prismatic = robot.prismatic_joints
    model_set = {n for n, p in zip(joint_names, prismatic) if p}
    if "prismatic" in md and set(declared) != model_set:
        fail(f"'prismatic: {md['prismatic']}' disagrees with robot {robot.name!r}, whose prismatic "
             f"joints are {sorted(model_set) or 'none'}", key_line["prismatic"])
    return prismatic


def _numbers(table, layout: _Layout, names, fail) -> np.ndarray:
    """The columns ``names`` of the data rows as floats (file units), shape (N, len(names))."""
    return table.values[:, [layout.index[c] for c in names]]


def _joints_and_points(table, layout: _Layout, lf: float, af: float, fail) -> tuple:
    """``(joints in file units (N, n), joints [rad | mm] (N, n), points [mm] (N, K, 3))``, joints
    in the returned (model's) order."""
    order = [layout.joint_cols.index(n) for n in layout.joint_names]
    q = _numbers(table, layout, [layout.joint_cols[k] for k in order], fail)  # a copy, scaled in place
    pts_file = _numbers(table, layout, [c for cols in layout.point_cols for c in cols], fail)
    q[:, ~layout.prismatic] *= af
    q[:, layout.prismatic] *= lf
    pts_file *= lf
    return q, pts_file.reshape(len(table), len(layout.targets), 3)


def _check_units_plausible(q, points, table, layout: _Layout, lu: str, au: str, key_line: dict, fail):
    """Numbers that look like another unit than the declared one are an error
    (:mod:`robocal.io.plausibility`), located at the largest value (or the unit's header line)."""
    dist = np.linalg.norm(points, axis=-1)
    problem = length_unit_problem(dist, lu, what="point distances from the origin")
    if problem:
        r, t = np.unravel_index(np.argmax(dist), dist.shape)
        if lu == "mm":
            fail(problem, key_line["length_unit"])
        fail(problem, int(table.lines[r]), layout.point_cols[t][0])
    revolute = q[:, ~layout.prismatic] if layout.prismatic.any() else q
    problem = angle_unit_problem(revolute, au, what="revolute joint values")
    if problem:
        r, j = np.unravel_index(np.argmax(np.abs(revolute)), revolute.shape)
        if au == "deg":
            fail(problem, key_line["angle_unit"])
        fail(problem, int(table.lines[r]), [n for n, p in zip(layout.joint_names, layout.prismatic) if not p][j])


def _rotations(table, layout: _Layout, conv: str, af: float, fail) -> np.ndarray:
    """The measured orientations (N, 3, 3) from the orientation columns of convention ``conv``."""
    o = _numbers(table, layout, layout.ori_cols, fail)
    if conv == "quaternion":
        norm = np.linalg.norm(o, axis=1)
        bad = np.flatnonzero(np.abs(norm - 1.0) > 1e-3)
        if bad.size:
            r = bad[0]
            fail(f"quaternion (qw, qx, qy, qz) has norm {norm[r]:.6g}, expected 1 (check the component "
                 "order: w first)", int(table.lines[r]), "qw")
        return matrix_from_quaternion(o)
    if conv == "rotvec":
        return matrix_from_rotvec(o * af)
    return matrix_from_euler(o * af, conv)


def _is_point_column(c: str) -> bool:
    return c in _AXES or (len(c) > 2 and c[-2] == "_" and c[-1] in _AXES)


def _classify_point_columns(cols):
    """Split column names into targets with their (x, y, z) columns, and leftovers (non-point).

    Raises ``ValueError`` (message only) for an incomplete triple or a target given twice.
    """
    targets: list[str] = []
    point_idx: list[tuple] = []
    used = set()
    present = set(cols)
    for c in cols:
        if c in used or not _is_point_column(c):
            continue
        prefix = "" if c in _AXES else c[:-2]
        if prefix and not _TARGET_RE.match(prefix):
            continue
        triple = tuple(f"{prefix}_{a}" if prefix else a for a in _AXES)
        missing = [t for t in triple if t not in present]
        if missing:
            raise _ColumnProblem(c, f"point column without {', '.join(repr(m) for m in missing)} "
                                    f"(a target needs all of {', '.join(triple)})")
        name = prefix or DEFAULT_TARGET
        if name in targets:
            raise _ColumnProblem(c, f"target {name!r} given twice (plain x, y, z is the target {DEFAULT_TARGET!r})")
        targets.append(name)
        point_idx.append(triple)
        used.update(triple)
    leftovers = [c for c in cols if c not in used]
    return targets, point_idx, leftovers


class _ColumnProblem(Exception):
    def __init__(self, column, message):
        super().__init__(message)
        self.column = column
        self.message = message
