"""Orientation columns of tracker exports (6-DoF probes: Leica T-Mac / T-Probe, SpatialAnalyzer
frames, any CSV whose convention the user declares).

Column sets recognised by name (any case, unit in brackets allowed):

* quaternions ``qw, qx, qy, qz`` or ``q0, q1, q2, q3`` (scalar first): no convention needed;
* three angles ``rx, ry, rz`` (also ``rot x``, ``a, b, c``, ``roll, pitch, yaw``, ``w, p, r``):
  their meaning differs between vendors and export settings, so the convention must be declared
  (``orientation=`` / ``--orientation``, a name of
  :data:`~robocal.transforms.POSE_CONVENTIONS`, e.g. ``rpy`` for fixed-axis X-Y-Z angles). Without
  it the angles are NOT imported and the notes say so and why.

Angles are in the unit the header names (``Rx [deg]``), else the one the caller declares, else
degrees when a value exceeds 2 pi (radians cannot), else the import stops and asks.
"""

from __future__ import annotations

import math

import numpy as np

from ...transforms import ANGLE_UNITS, POSE_CONVENTIONS, matrix_from_euler, matrix_from_quaternion, matrix_from_rotvec
from ..header import FileFormatError

__all__ = ["EULER_COLUMN_SETS", "QUATERNION_COLUMN_SETS", "find_orientation_columns", "rotations_from_values",
           "check_orientation_convention"]

QUATERNION_COLUMN_SETS = (("qw", "qx", "qy", "qz"), ("q0", "q1", "q2", "q3"), ("quat w", "quat x", "quat y", "quat z"))
EULER_COLUMN_SETS = (("rx", "ry", "rz"), ("rot x", "rot y", "rot z"), ("rotx", "roty", "rotz"), ("a", "b", "c"),
                     ("roll", "pitch", "yaw"), ("w", "p", "r"))


def check_orientation_convention(name: str | None) -> str | None:
    """The lower-cased convention name, or ``None``; ``ValueError`` listing the valid ones."""
    if name is None:
        return None
    key = str(name).strip().lower()
    if key not in POSE_CONVENTIONS:
        raise ValueError(f"unknown orientation convention {name!r}; valid: {', '.join(sorted(POSE_CONVENTIONS))}")
    return key


def find_orientation_columns(names) -> tuple[list[int] | None, str | None]:
    """``(column indices, "quaternion" | "euler")`` of the first complete orientation column set
    among the lower-cased header ``names``, or ``(None, None)``."""
    index = {n: i for i, n in reversed(list(enumerate(names)))}
    for cols in QUATERNION_COLUMN_SETS:
        if all(c in index for c in cols):
            return [index[c] for c in cols], "quaternion"
    for cols in EULER_COLUMN_SETS:
        if all(c in index for c in cols):
            return [index[c] for c in cols], "euler"
    return None, None


def _angle_unit(path, values, header_unit, declared, where) -> tuple[str, list[str]]:
    words = {"deg": "deg", "°": "deg", "degree": "deg", "degrees": "deg", "rad": "rad", "radian": "rad",
             "radians": "rad"}
    if header_unit is not None:
        unit = words.get(header_unit.strip().lower())
        if unit is None:
            raise FileFormatError(path, f"unknown angle unit {header_unit!r} of the orientation columns {where}; "
                                        "valid: deg, rad")
        if declared is not None and declared != unit:
            raise FileFormatError(path, f"orientation angle unit {declared!r} given, but the header says {unit!r}")
        return unit, []
    if declared is not None:
        if declared not in ANGLE_UNITS:
            raise ValueError(f"orientation angle unit: expected deg or rad, got {declared!r}")
        return declared, []
    big = float(np.max(np.abs(values))) if np.size(values) else 0.0
    if big > 2.0 * math.pi:
        return "deg", [f"orientation angles {where} taken as degrees (a value of {big:.4g} is beyond 2 pi rad)"]
    raise FileFormatError(path, f"the unit of the orientation angles {where} is not declared and all values lie "
                                "within +-2 pi (degrees and radians both possible): name it in the header "
                                "('Rx [deg]') or pass --orientation-unit deg|rad")


def rotations_from_values(path, values, kind: str, convention: str | None, *, header_unit=None,
                          angle_unit: str | None = None, where: str = "", lines=None) -> tuple:
    """``(rotations (N, 3, 3) or None, convention or None, notes)`` of orientation cells.

    values: (N, 3) angles or (N, 4) quaternions (scalar first) as read. kind: ``"euler"`` or
    ``"quaternion"`` (:func:`find_orientation_columns`). convention: the declared convention
    (required for angles; ``None`` drops them with a note saying why). header_unit / angle_unit:
    the unit in the header / the unit the caller declares (angles only).
    """
    values = np.asarray(values, dtype=float)
    conv = check_orientation_convention(convention)
    if kind == "quaternion":
        if conv not in (None, "quaternion"):
            raise ValueError(f"--orientation {conv}: the file has quaternion columns {where}; pass --orientation "
                             "quaternion or leave it out")
        norms = np.linalg.norm(values, axis=1)
        bad = np.flatnonzero(np.abs(norms - 1.0) > 1e-3)
        if len(bad):
            k = int(bad[0])
            raise FileFormatError(path, f"quaternion {where} has norm {norms[k]:.6g}, not 1",
                                  None if lines is None else lines[k])
        return matrix_from_quaternion(values / norms[:, None]), "quaternion", []
    if conv is None:
        return None, None, [f"orientation columns {where} NOT imported: three angles whose convention the file "
                            "does not say (vendors and export settings differ); pass --orientation CONVENTION "
                            "(e.g. rpy for fixed-axis X, Y, Z angles) to import them"]
    if conv == "quaternion":
        raise ValueError(f"--orientation quaternion, but the file has three angle columns {where}")
    unit, notes = _angle_unit(path, values, header_unit, angle_unit, where)
    angles = values * ANGLE_UNITS[unit]
    R = matrix_from_rotvec(angles) if conv == "rotvec" else matrix_from_euler(angles, conv)
    return R, conv, notes + [f"orientations {where} imported as {conv} angles in {unit}"]
