"""Reader of ``boby_fanuc``: a FANUC R-2000iC/165F measured by a laser tracker, 3 SMRs, 36 poses."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ._common import DatasetError, RealDataset, dataset_file, number

__all__ = ["read_boby_fanuc"]


def read_boby_fanuc(root=None, path=None) -> RealDataset:
    """``boby_fanuc/raw/N1N2N3Jval.csv``: 21 whitespace-separated columns per row.

    Columns 0-8: SMR N1, N2, N3 xyz [mm] in the tracker frame; 9-14: zeros (ignored); 15-20:
    J1..J6 [deg] in FANUC's controller convention (J3 against the horizontal) - returned in rad,
    to be used with ``fanuc_r2000ic_165f`` unchanged (the J2/J3 coupling is in the model).
    Returns points (36, 3, 3) [mm], targets N1, N2, N3, joints (36, 6) [rad].
    """
    p = Path(path) if path is not None else dataset_file(root, "boby_fanuc", "raw", "N1N2N3Jval.csv")
    rows = []
    with open(p, encoding="utf-8") as fh:
        for line_no, line in enumerate(fh, 1):
            cells = line.split()
            if not cells:
                continue
            if len(cells) != 21:
                raise DatasetError(f"{p}: line {line_no}: expected 21 whitespace-separated columns "
                                   f"(SMR N1..N3 xyz mm, 6 zeros, J1..J6 deg), got {len(cells)}")
            rows.append([number(c, f"{p}: line {line_no}, column {i}") for i, c in enumerate(cells)])
    if not rows:
        raise DatasetError(f"{p}: no data rows")
    a = np.array(rows)
    points = a[:, :9].reshape(-1, 3, 3)
    joints = np.deg2rad(a[:, 15:21])
    return RealDataset(
        name="boby_fanuc", joints=joints, points=points, targets=("N1", "N2", "N3"),
        joint_names=("J1", "J2", "J3", "J4", "J5", "J6"), stations=np.zeros(len(a), dtype=int),
        station_labels=["tracker"], per_pose={"row": np.arange(len(a))},
        metadata={"file": str(p), "instrument": "laser tracker", "frame": "tracker",
                  "file_units": "mm, deg (FANUC J2/J3 convention)", "robot": "fanuc_r2000ic_165f"})
