"""Importers for other software's files (see docs/importers.md).

One module per source, each returning robocal types: :class:`TrackerPoints` (points [mm] with ids,
from SpatialAnalyzer text exports and tracker CSV exports), :class:`JointLog` (controller joint
logs [rad]) and, after pairing the two by index, id or time stamp, robocal's
:class:`~robocal.io.measurements.Measurements` (write it with
:func:`~robocal.io.measurements.write_measurements`). Every malformed row raises
:class:`~robocal.io.header.FileFormatError` naming file, line and column; every assumed unit is
said (``notes`` and a :class:`UnitAssumptionWarning`).
"""

from .joint_log import JointLog, read_joint_log
from .pairing import Pairing, Unmatched, pair_by_id, pair_by_index, pair_by_time
from .points import TrackerPoints
from .spatialanalyzer import read_spatialanalyzer
from .tracker_csv import read_tracker_csv
from .units import UnitAssumptionWarning

__all__ = [
    "JointLog",
    "Pairing",
    "TrackerPoints",
    "UnitAssumptionWarning",
    "Unmatched",
    "pair_by_id",
    "pair_by_index",
    "pair_by_time",
    "read_joint_log",
    "read_spatialanalyzer",
    "read_tracker_csv",
]
