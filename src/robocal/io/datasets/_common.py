"""What the real data-set readers share: the error type, the in-memory data set, where the data
live, and numbers checked on reading."""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..header import FileFormatError

__all__ = ["DatasetError", "RealDataset", "datasets_root", "dataset_file", "number"]


class DatasetError(FileFormatError):
    """A data file is missing or malformed; the message names the file and the row / column or
    YAML key path (built by the reader, so ``path``, ``line`` and ``column`` are ``None``)."""

    def __init__(self, message: str):
        super().__init__(None, message)


@dataclass
class RealDataset:
    """One real data set in robocal's internal units.

    joints: (N, n) controller joints [rad | mm] in the robot model's controller order;
    points: (N, K, 3) measured target positions in the instrument frame [mm] (NaN = not measured);
    targets: K target names; joint_names: n names; stations: (N,) station / group index;
    station_labels: one label per station (e.g. ``(height_m, solution_space)``);
    per_pose: dict of further (N, ...) arrays (protocol-specific: roles, flags, ids, times);
    metadata: dict (source file, instrument, units of the file, notes).
    """

    name: str
    joints: np.ndarray
    points: np.ndarray
    targets: tuple
    joint_names: tuple
    stations: np.ndarray
    station_labels: list = field(default_factory=list)
    per_pose: dict = field(default_factory=dict)
    metadata: dict = field(default_factory=dict)

    @property
    def n_poses(self) -> int:
        return len(self.joints)

    def subset(self, idx) -> "RealDataset":
        """The poses ``idx`` (index array or boolean mask); stations are kept as they are."""
        idx = np.asarray(idx)
        per = {k: v[idx] for k, v in self.per_pose.items()}
        return RealDataset(self.name, self.joints[idx], self.points[idx], self.targets, self.joint_names,
                           self.stations[idx], list(self.station_labels), per, dict(self.metadata))


def datasets_root(root=None) -> Path:
    """The folder holding the data sets: ``root`` if given, else ``$ROBOCAL_DATASETS``, else
    ``../shared/datasets`` relative to the repository root (this file is
    ``<repo>/src/robocal/io/datasets/_common.py``; for a non-editable install, relative to the
    current directory taken as the repository root). The folder may not exist; callers check."""
    if root is not None:
        return Path(root)
    env = os.environ.get("ROBOCAL_DATASETS")
    if env:
        return Path(env)
    candidates = [Path(__file__).resolve().parents[4].parent / "shared" / "datasets",
                  Path.cwd().resolve().parent / "shared" / "datasets"]
    for c in candidates:
        if c.is_dir():
            return c
    return candidates[0]


def dataset_file(root, *parts) -> Path:
    """``<datasets_root(root)>/<parts...>``, which must be a file."""
    p = datasets_root(root).joinpath(*parts)
    if not p.is_file():
        raise DatasetError(f"{p}: no such file (data sets are read from {datasets_root(root)}; "
                           f"see docs/datasets.md)")
    return p


def number(text, where: str) -> float:
    """The finite float in ``text``; ``where`` (file and row / column or key path) for the error."""
    try:
        v = float(text)
    except ValueError:
        raise DatasetError(f"{where}: {text!r} is not a number") from None
    if not math.isfinite(v):
        raise DatasetError(f"{where}: {text!r} is not a finite number")
    return v
