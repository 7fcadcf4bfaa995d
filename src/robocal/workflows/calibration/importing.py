"""``robocal import``: other software's files (tracker exports + controller joint logs) into
robocal's measurement file (docs/importers.md, docs/measurement-files.md)."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np

from ...io.importers import pair_by_id, pair_by_index, pair_by_time, read_joint_log, read_spatialanalyzer, read_tracker_csv
from ...io.measurements import write_measurements
from ...robots import load_robot

__all__ = ["POINT_FORMATS", "PAIRINGS", "read_campaign", "import_campaign"]

#: Point-file formats that ``robocal import --format`` reads.
POINT_FORMATS = {"tracker-csv": read_tracker_csv, "sa-text": read_spatialanalyzer}
#: How points and joint rows are paired.
PAIRINGS = ("index", "id", "time")


def _joints_named_as_robot(meas, model, notes):
    """The log's joint columns renamed to the robot's controller joints (by position) when the
    counts agree and the names differ; a clear error when the counts differ."""
    names = tuple(meas.joint_names)
    expected = tuple(model.controller_joints)
    if len(names) != len(expected):
        raise ValueError(f"the joint log has {len(names)} joint columns ({', '.join(names)}) but {model.name} has "
                         f"{len(expected)} joints ({', '.join(expected)})")
    log_prismatic = np.zeros(len(names), bool) if meas.prismatic is None else np.asarray(meas.prismatic, bool)
    model_prismatic = np.asarray(model.prismatic_joints, bool)
    if np.any(log_prismatic != model_prismatic):
        j = int(np.flatnonzero(log_prismatic != model_prismatic)[0])
        kind = "linear (mm)" if model_prismatic[j] else "revolute"
        raise ValueError(f"joint column {names[j]!r} of the joint log was read as "
                         f"{'linear (mm)' if log_prismatic[j] else 'an angle'} but {model.name}'s joint "
                         f"{expected[j]} is {kind}; declare it in the log's header (e.g. '{names[j]} [mm]')")
    if names == expected:
        return meas
    notes.append(f"joint columns {', '.join(names)} taken as {', '.join(expected)} (same order)")
    return dataclasses.replace(meas, joint_names=expected, prismatic=model_prismatic)


def read_campaign(points_file, joints_file, *, robot: str, point_format: str = "tracker-csv", pair: str = "index",
                  tolerance_s: float | None = None, offset_s: float = 0.0, id_match: str = "exact",
                  length_unit: str | None = None, angle_unit: str | None = None, name_fields: int | None = None,
                  joint_columns=None, orientation: str | None = None, orientation_unit: str | None = None) -> dict:
    """Read a tracker export and a joint log and pair them (the arguments of :func:`import_campaign`).

    Returns ``{measurements, pairing, notes}`` without writing anything (``robocal calibrate
    --format`` calibrates from it directly).
    """
    if point_format not in POINT_FORMATS:
        raise ValueError(f"unknown point format {point_format!r}; expected one of {', '.join(POINT_FORMATS)}")
    if pair not in PAIRINGS:
        raise ValueError(f"unknown pairing {pair!r}; expected one of {', '.join(PAIRINGS)}")
    model = load_robot(robot)
    kw = {"orientation": orientation, "orientation_unit": orientation_unit}
    if point_format == "sa-text":
        kw["name_fields"] = name_fields
    elif name_fields is not None:
        raise ValueError("--name-fields is for --format sa-text (SpatialAnalyzer text exports)")
    points = POINT_FORMATS[point_format](points_file, length_unit=length_unit, **kw)
    log = read_joint_log(joints_file, angle_unit=angle_unit, joint_columns=joint_columns or None)
    if pair == "index":
        pairing = pair_by_index(points, log, robot=model)
    elif pair == "id":
        pairing = pair_by_id(points, log, match=id_match, robot=model)
    else:
        if tolerance_s is None:
            raise ValueError("pairing by time needs a tolerance in seconds (--time-tolerance)")
        pairing = pair_by_time(points, log, tolerance=tolerance_s, offset=offset_s, robot=model)
    notes = list(pairing.notes)
    meas = _joints_named_as_robot(pairing.measurements, model, notes)
    meas.metadata["robot"] = robot if Path(robot).suffix.lower() in (".toml", ".urdf") else model.name
    return {"measurements": meas, "pairing": pairing, "notes": notes}


def import_campaign(points_file, joints_file, out_file, *, robot: str, point_format: str = "tracker-csv",
                    pair: str = "index", tolerance_s: float | None = None, offset_s: float = 0.0,
                    id_match: str = "exact", length_unit: str | None = None, angle_unit: str | None = None,
                    overwrite: bool = False, name_fields: int | None = None, joint_columns=None,
                    orientation: str | None = None, orientation_unit: str | None = None) -> dict:
    """Read a tracker export and a joint log, pair them and write a robocal measurement file.

    point_format: a key of :data:`POINT_FORMATS`. pair: ``index`` (row order), ``id`` (point name
    = pose id; ``id_match="number"`` pairs ``P017`` with ``17``) or ``time`` (nearest time stamp
    within ``tolerance_s`` [s], joint clock + ``offset_s``). length_unit: of the point file
    (``mm``/``m``/``in``; default declared by the file or detected and said). angle_unit: of the
    joint log (``deg``/``rad``; required unless its header names it or the controller's column
    names fix it, as UR RTDE's). name_fields: SpatialAnalyzer name fields before X Y Z (0 .. 3).
    joint_columns: the joint log's joint column names in order (default: recognised by name).
    orientation / orientation_unit: convention and unit of the export's orientation angles
    (:mod:`robocal.io.importers.orientation`); the measurement file then carries the
    orientations (quaternion columns; Euler angles in the declared convention).

    Returns a dict with ``measurements`` (the written :class:`Measurements`), ``pairing`` (the
    :class:`~robocal.io.importers.Pairing`), ``notes`` (list of str) and ``file`` (Path).
    """
    from ...io.output_paths import check_outputs

    check_outputs(out_file, {"the points file": points_file, "the joint log": joints_file, "--robot": robot},
                  overwrite=overwrite)
    r = read_campaign(points_file, joints_file, robot=robot, point_format=point_format, pair=pair,
                      tolerance_s=tolerance_s, offset_s=offset_s, id_match=id_match, length_unit=length_unit,
                      angle_unit=angle_unit, name_fields=name_fields, joint_columns=joint_columns,
                      orientation=orientation, orientation_unit=orientation_unit)
    meas = r["measurements"]
    path = write_measurements(out_file, meas, length_unit="mm", angle_unit="deg", overwrite=overwrite,
                              float_format="short")
    return {**r, "file": path}
