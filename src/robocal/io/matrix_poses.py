"""Flange poses as 4 x 4 matrices (issue 30 item 5): the layout most robot logs and hand-eye
datasets use, read without a conversion step.

Two layouts, told apart by the numbers per line (whitespace, comma or semicolon separated;
``#`` starts a comment):

* **one pose per line** (row-major): 16 numbers ``r11 r12 r13 tx r21 ... 0 0 0 1``, or 12 (the
  top three rows). This is the ``RobotPosesVec.txt`` layout of the robot-world-hand-eye datasets
  (one tab-separated row per image, MATLAB ``reshape(row, 4, [])'``);
* **one matrix per block**: 4 lines of 4 numbers per pose (or 3 lines of 4), blank lines between
  blocks optional.

The matrices carry no unit: the length unit of the translations must be declared, by a
``# length_unit: m`` (or ``mm``) line in the file or by the caller (``--length-unit``); translations
that look like the other unit are refused. Every matrix is checked: last row ``0 0 0 1``, rotation
orthonormal with determinant +1 (to 1e-3), naming the pose and its line.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from .header import FileFormatError, read_text

__all__ = ["MatrixPoseError", "is_matrix_pose_file", "read_matrix_poses"]

LENGTH_UNITS = {"mm": 1.0, "m": 1000.0}
_SPLIT = re.compile(r"[\s,;]+")
_UNIT_LINE = re.compile(r"^#\s*length_unit\s*:\s*(\S+)", re.IGNORECASE)


class MatrixPoseError(FileFormatError):
    """A 4 x 4 flange-pose file is malformed or its unit is not declared."""


def _numbers(text: str):
    """[(line number, [floats])] of the non-empty, non-comment lines, or None if one is not numeric;
    and the declared length unit (or None)."""
    rows, unit = [], None
    for k, raw in enumerate(text.splitlines(), 1):
        m = _UNIT_LINE.match(raw.strip())
        if m:
            unit = m.group(1).lower()
            continue
        line = raw.split("#", 1)[0].strip()
        if not line:
            continue
        try:
            rows.append((k, [float(v) for v in _SPLIT.split(line) if v]))
        except ValueError:
            return None, unit
    return rows, unit


def is_matrix_pose_file(path) -> bool:
    """True when every data line of ``path`` is numbers only (a matrix layout, not a CSV with a header)."""
    try:
        rows, _ = _numbers(read_text(path, MatrixPoseError))
    except (FileFormatError, OSError):
        return False
    return bool(rows)


def read_matrix_poses(path, length_unit: str | None = None) -> np.ndarray:
    """``T_base_flange`` (N, 4, 4) [mm] from a 4 x 4 matrix file (module docstring).

    length_unit: ``"m"`` or ``"mm"`` for the translations, unless the file declares it (both given
    and different: an error). Raises :class:`MatrixPoseError` naming the file and line.
    """
    path = Path(path)
    rows, file_unit = _numbers(read_text(path, MatrixPoseError))
    if rows is None:
        raise MatrixPoseError(path, "not a matrix pose file: a line holds something other than numbers")
    if not rows:
        raise MatrixPoseError(path, "no poses (empty file?)")
    unit = file_unit or length_unit
    if file_unit and length_unit and file_unit != length_unit:
        raise MatrixPoseError(path, f"the file declares length_unit {file_unit}, but {length_unit} was given")
    if unit not in LENGTH_UNITS:
        raise MatrixPoseError(path, "the matrices carry no unit: declare the translations' unit, '# length_unit: m' "
                                    "(or mm) in the file or --length-unit m|mm"
                              + ("" if unit is None else f" (got {unit!r})"))
    counts = {len(v) for _, v in rows}
    mats, first_lines = [], []
    if counts <= {16} or counts <= {12}:  # one pose per line, row-major
        n = counts.pop()
        for line, v in rows:
            mats.append(np.vstack([np.reshape(v, (n // 4, 4)), [[0.0, 0.0, 0.0, 1.0]]])[:4])
            first_lines.append(line)
    elif counts == {4}:  # one matrix per block of 4 (or 3) lines
        per = 4 if len(rows) % 4 == 0 and all(rows[i][1] == [0.0, 0.0, 0.0, 1.0] for i in range(3, len(rows), 4)) \
            else 3
        if len(rows) % per:
            raise MatrixPoseError(path, f"{len(rows)} lines of 4 numbers do not make whole {per} x 4 matrices",
                                  rows[-1][0])
        for i in range(0, len(rows), per):
            block = [v for _, v in rows[i:i + per]]
            mats.append(np.vstack([block, [[0.0, 0.0, 0.0, 1.0]]])[:4])
            first_lines.append(rows[i][0])
    else:
        line = next(ln for ln, v in rows if len(v) not in (4, 12, 16) or len(v) != len(rows[0][1]))
        raise MatrixPoseError(path, f"expected 16 (or 12) numbers per line, one row-major matrix each, or 4 per line "
                                    f"in blocks of 4; found lines with {sorted(counts)} numbers", line)
    T = np.array(mats, dtype=float)
    for k, (M, line) in enumerate(zip(T, first_lines)):
        if not np.allclose(M[3], [0.0, 0.0, 0.0, 1.0], atol=1e-6):
            raise MatrixPoseError(path, f"pose {k + 1}: last row {M[3].tolist()} is not 0 0 0 1 (a column-major "
                                        "or transposed matrix?)", line)
        R = M[:3, :3]
        err = float(np.max(np.abs(R.T @ R - np.eye(3))))
        if err > 1e-3 or np.linalg.det(R) < 0:
            raise MatrixPoseError(path, f"pose {k + 1}: the rotation part is not a rotation (orthonormality error "
                                        f"{err:.2g}, determinant {np.linalg.det(R):.3f}; transposed, or not a "
                                        "homogeneous transform?)", line)
    T[:, :3, 3] *= LENGTH_UNITS[unit]
    reach = float(np.max(np.linalg.norm(T[:, :3, 3], axis=1)))
    if unit == "mm" and reach < 5.0:
        raise MatrixPoseError(path, f"translations reach only {reach:.3g} mm: the values look like metres "
                                    "(declare length_unit m)")
    if unit == "m" and reach > 20000.0:
        raise MatrixPoseError(path, f"translations reach {reach / 1000:.4g} m: the values look like millimetres "
                                    "(declare length_unit mm)")
    return T
