"""Files of the tool-frame calibration (docs/tcp.md): cross-laser sensor points, flange poses and
the parallel-barrier record.

* sensor points (:func:`read_sensor_points_csv`, :func:`write_sensor_points_csv`): CSV
  ``label,x,y,z`` [mm, base frame] with the 16 labels A1..D4, for
  :func:`robocal.tcp.calibrate_sensor`;
* flange poses (:func:`read_flange_poses_csv`): controller poses in a declared orientation
  convention and units, as ``T_base_flange`` (N, 4, 4) [mm] for :func:`robocal.tcp.four_point_tcp`
  and :func:`robocal.tcp.seven_point_tool_frame`;
* the parallel-barrier record (:func:`read_parallel_barriers_file`): TOML with the recorded
  values, as keyword arguments of :func:`robocal.tcp.parallel_barriers_tool` [mm].

Every problem raises :class:`TcpFileError` (a :class:`~robocal.io.header.FileFormatError`) naming
the file and, where known, the line and column or key.
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..tcp.sensor import SENSOR_POINT_LABELS
from .plausibility import angle_unit_problem, length_unit_problem
from ..transforms import ANGLE_UNITS, LENGTH_UNITS, POSE_CONVENTIONS, transform_from_pose
from .header import FileFormatError, declared_unit, read_header_block, read_text
from .table import check_field_counts, check_unique_labels, csv_cells, data_rows, number_columns

__all__ = [
    "TcpFileError",
    "FlangePoses",
    "read_sensor_points_csv",
    "write_sensor_points_csv",
    "read_flange_poses_csv",
    "write_flange_poses_csv",
    "read_parallel_barriers_file",
]


class TcpFileError(FileFormatError):
    """A tool-calibration input file is malformed (file, line and column in the message)."""


def _failer(path):
    def fail(message, line=None, column=None):
        raise TcpFileError(path, message, line, column)

    return fail


def _header(path, lines):
    """``(fail, values, key_line, index of the column row)``; unit values lower-cased."""
    fail = _failer(path)
    values, key_line, i = read_header_block(lines, fail)
    for key in ("length_unit", "angle_unit"):
        if key in values:
            values[key] = values[key].lower()
    return fail, values, key_line, i


# ---------------------------------------------------------------------------------------------
# cross-laser sensor points
# ---------------------------------------------------------------------------------------------


def read_sensor_points_csv(path) -> dict:
    """Read the sensor-calibration points file: CSV ``label,x,y,z`` (mm, base frame).

    A header block of ``#`` lines may declare ``# length_unit: mm|m`` (default mm); other ``#``
    lines are comments, blank lines are ignored. The first other line must be the column row
    ``label,x,y,z``; then one row per label, the 16 labels A1..A4, B1..B4, C1..C4, D1..D4
    (case-insensitive, any order). Returns ``{label: array(3) [mm]}``. Raises
    :class:`TcpFileError` naming the file, line and column of the first problem (missing file,
    bad header, wrong number of fields, non-numeric or non-finite values, unknown, duplicate or
    missing labels).
    """
    path = Path(path)
    lines = read_text(path, TcpFileError).splitlines()
    fail, values, key_line, i = _header(path, lines)
    scale = LENGTH_UNITS[declared_unit(values, key_line, "length_unit", LENGTH_UNITS, fail, "mm")]
    if i >= len(lines):
        fail("no header line 'label,x,y,z' (empty file?)")
    fields = csv_cells(lines[i])
    if [f.lower() for f in fields] != ["label", "x", "y", "z"]:
        fail(f"header must be 'label,x,y,z', got {','.join(fields)!r}", i + 1)
    rows = data_rows(lines, i + 1)
    check_field_counts(rows, 4, i + 1, fail)
    found: dict = {}
    for line, cells in rows:
        label = cells[0].upper()
        if label not in SENSOR_POINT_LABELS:
            fail(f"unknown label {cells[0]!r}; expected A1-A4, B1-B4, C1-C4, D1-D4", line, "label")
        if label in found:
            fail(f"duplicate label {label!r} (first on line {found[label][1]})", line, "label")
        xyz = number_columns([(line, cells)], [1, 2, 3], lambda problem, ln, j: fail(problem, ln, "xyz"[j - 1]))
        found[label] = (xyz[0] * scale, line)
    missing = [lab for lab in SENSOR_POINT_LABELS if lab not in found]
    if missing:
        fail(f"missing labels {', '.join(missing)}")
    problem = length_unit_problem([v for v, _ in found.values()], "m" if scale != 1.0 else "mm",
                                  what="sensor points")
    if problem:
        fail(problem, key_line.get("length_unit"))
    return {lab: found[lab][0] for lab in SENSOR_POINT_LABELS}


def write_sensor_points_csv(path, points: dict, note: str | None = None) -> Path:
    """Write ``points`` (label -> (3,) [mm], base frame) in the format
    :func:`read_sensor_points_csv` reads; ``note`` lines become ``# note:`` header lines."""
    path = Path(path)
    lines = ["# robocal cross-laser sensor calibration points (base frame)", "# length_unit: mm"]
    if note:
        lines += [f"# note: {ln}".rstrip() for ln in str(note).splitlines()]
    lines.append("label,x,y,z")
    for lab in SENSOR_POINT_LABELS:
        p = np.asarray(points[lab], dtype=float)
        if p.shape != (3,) or not np.all(np.isfinite(p)):
            raise ValueError(f"{lab}: expected 3 finite coordinates (x, y, z), got {points[lab]!r}")
        lines.append(f"{lab},{p[0]:.6f},{p[1]:.6f},{p[2]:.6f}")
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path


# ---------------------------------------------------------------------------------------------
# flange poses
# ---------------------------------------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class FlangePoses:
    """Flange poses read from a file: ``T_base_flange`` (N, 4, 4) [mm] and the N pose labels;
    the file's orientation convention and units, and its header values (``metadata``)."""

    labels: tuple
    T_base_flange: np.ndarray
    convention: str
    length_unit: str
    angle_unit: str | None
    metadata: dict = field(default_factory=dict)


def _pose_convention(values: dict, key_line: dict, fail) -> tuple:
    """``(convention, length_unit, angle_unit)`` declared by a flange-pose header; ``angle_unit``
    is ``None`` for quaternions without one. ``convention`` is accepted for ``orientation``."""
    if "convention" in values:
        if "orientation" in values:
            first, second = sorted((key_line["orientation"], key_line["convention"]))
            fail(f"header key 'orientation' given twice (first on line {first})", second)
        values["orientation"] = values.pop("convention")
        key_line["orientation"] = key_line.pop("convention")
    valid = ", ".join(sorted(POSE_CONVENTIONS))
    conv = values.get("orientation")
    if conv is None:
        fail(f"missing '# orientation: <convention>' line before the column row (one of {valid})")
    if conv.lower() not in POSE_CONVENTIONS:
        fail(f"unknown orientation convention {conv!r}; valid: {valid}")
    conv = conv.lower()
    lu, au = values.get("length_unit"), values.get("angle_unit")
    if lu not in LENGTH_UNITS:
        fail("missing or invalid '# length_unit: mm|m' line" + ("" if lu is None else f" (got {lu!r})"))
    if conv != "quaternion" and au not in ANGLE_UNITS:
        fail("missing or invalid '# angle_unit: deg|rad' line" + ("" if au is None else f" (got {au!r})"))
    return conv, lu, au


def _pose_columns(line: str, line_no: int, conv: str, fail) -> list:
    """The column row of a flange-pose file: ``pose,x,y,z`` + 3 (4 for quaternions) orientation columns."""
    fields = csv_cells(line)
    ncol = 8 if conv == "quaternion" else 7
    if len(fields) != ncol or [f.lower() for f in fields[:4]] != ["pose", "x", "y", "z"]:
        layout = "pose,x,y,z,qw,qx,qy,qz" if ncol == 8 else "pose,x,y,z + 3 orientation columns"
        fail(f"column row must have {ncol} columns ({layout}) for {conv}, got {','.join(fields)!r}", line_no)
    return fields


def _check_pose_units(values, conv: str, lu: str, au, key_line: dict, fail) -> None:
    """Flange positions and orientation angles (file units, (N, 6 | 7)) fit the declared units
    (:mod:`robocal.io.plausibility`); rotation vectors and quaternions are not judged by angle."""
    problem = length_unit_problem(np.linalg.norm(values[:, :3], axis=1) * LENGTH_UNITS[lu], lu,
                                  what="flange positions")
    if problem:
        fail(problem, key_line.get("length_unit"))
    if conv not in ("quaternion", "rotvec") and au:
        problem = angle_unit_problem(values[:, 3:] * ANGLE_UNITS[au], au, what="orientation angles", min_rows=4)
        if problem:
            fail(problem, key_line.get("angle_unit"))


def read_flange_poses_csv(path, min_rows: int = 1, convention: str | None = None) -> FlangePoses:
    """Read a flange-pose file (``docs/tcp.md``, "Flange-pose files").

    ```
    # orientation: kuka_abc        (a robocal.transforms.POSE_CONVENTIONS name; "convention" also accepted)
    # length_unit: mm              (mm or m)
    # angle_unit: deg              (deg or rad; not needed for quaternion)
    pose,x,y,z,A,B,C               (7 columns; 8 for quaternion: pose,x,y,z,qw,qx,qy,qz)
    P1,1200.5,-30.2,850.0,10.0,80.0,-170.0
    ```

    ``# key: value`` lines before the column row set keys; other ``#`` lines are comments. The
    orientation column names are free (their number must match the convention). Returns
    ``T_base_flange`` (N, 4, 4) [mm] with the labels. Raises :class:`TcpFileError` naming the
    file, line and column of the first problem. ``convention`` overrides the file's declared one.
    """
    path = Path(path)
    lines = read_text(path, TcpFileError).splitlines()
    fail, meta, key_line, i = _header(path, lines)
    if i >= len(lines):
        fail("no column row (empty file?)")
    conv, lu, au = _pose_convention(meta, key_line, fail)
    if convention is not None:  # another reading of the same numbers (the hand-eye gate's hypotheses)
        conv = convention
    header = _pose_columns(lines[i], i + 1, conv, fail)
    rows = data_rows(lines, i + 1)
    check_field_counts(rows, len(header), i + 1, fail)
    labels = check_unique_labels(rows, "pose", "pose", fail)
    poses, values = [], []
    for line, cells in rows:
        vals = number_columns([(line, cells)], range(1, len(header)), lambda p, ln, j: fail(p, ln, header[j]))
        values.append(vals[0])
        try:
            poses.append(transform_from_pose(vals[0], conv, lu, au or "deg"))
        except ValueError as exc:
            fail(str(exc), line)
    if len(poses) < min_rows:
        fail(f"need at least {min_rows} poses, got {len(poses)}")
    _check_pose_units(np.reshape(values, (len(poses), -1)), conv, lu, au, key_line, fail)
    meta.update(orientation=conv, length_unit=lu, angle_unit=au)
    return FlangePoses(labels=tuple(labels), T_base_flange=np.array(poses).reshape(-1, 4, 4), convention=conv,
                       length_unit=lu, angle_unit=au, metadata=meta)


_ORIENTATION_COLUMNS = {"quaternion": ("qw", "qx", "qy", "qz"), "rotvec": ("rx", "ry", "rz")}


def write_flange_poses_csv(path, labels, T_base_flange, *, convention: str = "kuka_abc", length_unit: str = "mm",
                           angle_unit: str = "deg", notes=(), overwrite: bool = False) -> Path:
    """Write flange poses ``T_base_flange`` (N, 4, 4) [mm] with their ``labels`` in the format
    :func:`read_flange_poses_csv` reads (atomic; an existing file needs ``overwrite``). Orientation
    columns are named ``qw,qx,qy,qz`` (quaternion), ``rx,ry,rz`` (rotvec) or ``a,b,c`` (Euler, in the
    convention's order); ``notes`` become ``# note:`` lines."""
    from ..transforms import pose_from_transform
    from .atomic import atomic_write_text

    T = np.asarray(T_base_flange, dtype=float).reshape(-1, 4, 4)
    labels = [str(v) for v in labels]
    if len(labels) != len(T) or len(set(labels)) != len(labels):
        raise ValueError(f"write_flange_poses_csv: need {len(T)} unique labels, got {len(labels)}")
    conv = convention.lower()
    values = pose_from_transform(T, conv, length_unit, angle_unit)
    lines = [f"# orientation: {conv}", f"# length_unit: {length_unit}"]
    if conv != "quaternion":
        lines.append(f"# angle_unit: {angle_unit}")
    lines += [f"# note: {n}" for n in notes]
    lines.append(",".join(("pose", "x", "y", "z") + _ORIENTATION_COLUMNS.get(conv, ("a", "b", "c"))))
    lines += [",".join([lab] + [f"{v:.12g}" for v in row]) for lab, row in zip(labels, values)]
    return atomic_write_text(path, "\n".join(lines) + "\n", overwrite=overwrite)


# ---------------------------------------------------------------------------------------------
# parallel light barriers
# ---------------------------------------------------------------------------------------------

_BARRIER_KEYS = {"length_unit", "h_up", "h_down", "delta_h", "x_up", "x_down", "x_up_vertical", "x_down_vertical",
                 "z7", "note"}


def _toml_numbers(path, data: dict, key: str, scale: float, n: int | None = None, required: bool = False):
    """``data[key]`` times ``scale``: one number (``n`` None) or a list of ``n``; None if absent."""
    if key not in data:
        if required:
            raise TcpFileError(path, f"missing key {key!r}")
        return None
    v = data[key]
    vals = v if n is not None else [v]
    if not isinstance(vals, list) or (n is not None and len(vals) != n):
        raise TcpFileError(path, f"expected a list of {n} numbers, got {v!r}", column=key)
    out = []
    for x in vals:
        if isinstance(x, bool) or not isinstance(x, (int, float)) or not math.isfinite(x):
            raise TcpFileError(path, f"{x!r} is not a finite number", column=key)
        out.append(float(x) * scale)
    return out if n is not None else out[0]


def read_parallel_barriers_file(path) -> dict:
    """Read the recorded values of the parallel-barrier method from a TOML file (``docs/tcp.md``).

    Keys: ``length_unit`` (mm | m, default mm), ``h_up``, ``h_down`` or ``delta_h``, ``x_up`` and
    ``x_down`` (4 numbers each), optional ``z7``, ``x_up_vertical``, ``x_down_vertical`` (2 each),
    ``note``. Returns keyword arguments of :func:`robocal.tcp.parallel_barriers_tool` [mm].
    Raises :class:`TcpFileError` naming the file and key.
    """
    path = Path(path)
    try:
        data = tomllib.loads(read_text(path, TcpFileError))
    except tomllib.TOMLDecodeError as exc:
        raise TcpFileError(path, f"not valid TOML: {exc}") from None
    unknown = sorted(set(data) - _BARRIER_KEYS)
    if unknown:
        raise TcpFileError(path, f"unknown key(s) {', '.join(unknown)}; valid: {', '.join(sorted(_BARRIER_KEYS))}")
    unit = data.get("length_unit", "mm")
    if not isinstance(unit, str) or unit not in LENGTH_UNITS:
        raise TcpFileError(path, f"length_unit {unit!r} not supported; use mm or m", column="length_unit")
    scale = LENGTH_UNITS[unit]

    def num(key, n=None, required=False):
        return _toml_numbers(path, data, key, scale, n, required)

    kw = dict(x_up=num("x_up", 4, True), x_down=num("x_down", 4, True), delta_h_mm=num("delta_h"),
              h_up_mm=num("h_up"), h_down_mm=num("h_down"), z7_mm=num("z7"),
              x_up_vertical=num("x_up_vertical", 2), x_down_vertical=num("x_down_vertical", 2))
    if kw["delta_h_mm"] is None and (kw["h_up_mm"] is None or kw["h_down_mm"] is None):
        raise TcpFileError(path, "give delta_h, or h_up and h_down")
    return kw
