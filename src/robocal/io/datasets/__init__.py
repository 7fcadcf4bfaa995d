"""Readers for the third-party real measured data sets.

The data live outside the repository, in ``../shared/datasets`` relative to the repository root
(``/work/shared/datasets`` on the project machine; override with the ``ROBOCAL_DATASETS``
environment variable or the ``root`` argument). They are read in place, never copied. Each
folder's README gives source, license, units, traps and the reference numbers; docs/datasets.md
describes the protocols (:mod:`robocal.workflows.datasets`) and how to reproduce the figures.

Readers (internal units: mm, rad; every malformed entry raises :class:`DatasetError`, a
:class:`~robocal.io.header.FileFormatError`, naming the file and the row / column or YAML key path),
one module per data set:

* :func:`read_boby_fanuc`         FANUC 6R, laser tracker, 3 SMRs, 36 poses (:mod:`.boby_fanuc`);
* :func:`read_dlr_justin`         DLR Agile Justin (19 joints), Vicon, 2 hand markers, 500 poses
  (:mod:`.dlr_justin`);
* :func:`read_hilti_trailblazer`  Hilti Trailblazer (column + Doosan 6R), total station, one set
  (:mod:`.hilti_trailblazer`);
* :func:`read_ros_industrial_positioner`  a 2-axis part positioner, target poses measured by a fixed
  camera, 205 records (:mod:`.ros_industrial_positioner`).
"""

from ._common import DatasetError, RealDataset, datasets_root
from .boby_fanuc import read_boby_fanuc
from .dlr_justin import DLR_JUSTIN_JOINTS, read_dlr_justin
from .hilti_trailblazer import HILTI_CROSS_CMDS, HILTI_SETS, read_hilti_trailblazer
from .ros_industrial_positioner import read_ros_industrial_positioner

__all__ = [
    "DatasetError",
    "RealDataset",
    "HILTI_SETS",
    "HILTI_CROSS_CMDS",
    "DLR_JUSTIN_JOINTS",
    "datasets_root",
    "read_boby_fanuc",
    "read_dlr_justin",
    "read_hilti_trailblazer",
    "read_ros_industrial_positioner",
]
