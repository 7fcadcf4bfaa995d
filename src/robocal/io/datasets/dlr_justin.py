"""Reader of ``dlr_justin``: DLR Agile Justin (19 joints) measured by Vicon, 2 hand markers, 500 poses."""

from __future__ import annotations

import csv
import re
from pathlib import Path

import numpy as np

from ._common import DatasetError, RealDataset, dataset_file, number

__all__ = ["DLR_JUSTIN_JOINTS", "read_dlr_justin"]

#: The 19 joints of the file, in its order (dataset README: 0-2 torso, 3-9 right arm, 10-16 left
#: arm, 17-18 head), named as the controller joints of the robot ``dlr_justin19``.
DLR_JUSTIN_JOINTS = ("torso_0", "torso_1", "torso_2") + tuple(f"right_j{i}" for i in range(1, 8)) + \
    tuple(f"left_j{i}" for i in range(1, 8)) + ("head_j1", "head_j2")

_BRACKETS = re.compile(r"[\[\]]")
_MARKERS_MAX_M = 50.0  # a marker farther from the Vicon origin is not in metres


def _numpy_printed(text, n: int, where: str) -> np.ndarray:
    """The ``n`` numbers of a numpy-printed array (``[[1. 2.] [3. 4.]]``)."""
    body = _BRACKETS.sub(" ", text).split()
    if len(body) != n:
        raise DatasetError(f"{where}: expected {n} numbers in a numpy-printed array, got {len(body)}")
    return np.array([number(b, where) for b in body])


def _records(p: Path):
    """``(line, index, joints (19,) [rad], markers (6,) [m])`` per record of the CSV file."""
    with open(p, newline="", encoding="utf-8") as fh:
        reader = csv.reader(fh)
        try:
            header = next(reader)
        except StopIteration:
            raise DatasetError(f"{p}: empty file") from None
        if [h.strip() for h in header] != ["", "joints", "markers"]:
            raise DatasetError(f"{p}: line 1: expected header ',joints,markers', got {','.join(header)!r}")
        for rec in reader:
            line = reader.line_num
            if not rec:
                continue
            if len(rec) != 3:
                raise DatasetError(f"{p}: record ending on line {line}: expected 3 cells (index, joints, "
                                   f"markers), got {len(rec)}")
            index = int(number(rec[0], f"{p}: line {line}, column 'index'"))
            joints = _numpy_printed(rec[1], 19, f"{p}: record ending on line {line}, column 'joints'")
            mk = _numpy_printed(rec[2], 6, f"{p}: record ending on line {line}, column 'markers'")
            if np.max(np.abs(mk)) > _MARKERS_MAX_M:
                raise DatasetError(f"{p}: record ending on line {line}, column 'markers': {mk.tolist()} is not "
                                   f"plausible in metres")
            yield line, index, joints, mk


def read_dlr_justin(root=None, path=None) -> RealDataset:
    """``dlr_justin/raw/measurements.csv``: columns ``index, joints, markers``.

    ``joints``: numpy-printed vector of the 19 commanded joints [rad] (:data:`DLR_JUSTIN_JOINTS`,
    the controller order of ``dlr_justin19``); ``markers``: numpy-printed 2x3 array [right; left]
    in the Vicon frame [m], returned in mm as targets ``right`` and ``left``: points (N, 2, 3).
    """
    p = Path(path) if path is not None else dataset_file(root, "dlr_justin", "raw", "measurements.csv")
    records = list(_records(p))
    if not records:
        raise DatasetError(f"{p}: no data rows")
    index = np.array([r[1] for r in records])
    joints = np.array([r[2] for r in records])
    pts = np.array([r[3] for r in records]).reshape(-1, 2, 3) * 1000.0
    return RealDataset(
        name="dlr_justin", joints=joints, points=pts, targets=("right", "left"), joint_names=DLR_JUSTIN_JOINTS,
        stations=np.zeros(len(pts), dtype=int), station_labels=["vicon"], per_pose={"index": index},
        metadata={"file": str(p), "instrument": "Vicon", "frame": "vicon", "file_units": "rad, m",
                  "robot": "dlr_justin19", "note": "joints are commanded values; head joints always 0"})
