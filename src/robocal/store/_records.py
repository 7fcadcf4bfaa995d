"""What the history store returns: cycle records, time series, stored cycles, lookup errors.

Times are UTC; values are in the unit stored with them (mm, rad, s, 1, ...).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from datetime import datetime
from typing import NamedTuple

import numpy as np

from ._backends import HistoryError

__all__ = [
    "CycleRecord", "HistoryLookupError", "ParameterRow", "Quantity", "Series", "StoredCycle", "UnknownRobotError",
]


class HistoryLookupError(HistoryError, LookupError):
    """A robot, cycle, parameter or metric asked for is not in the database."""


class UnknownRobotError(HistoryLookupError):
    """The robot id is not in the database; ``known`` lists the ids that are."""

    def __init__(self, robot: str, known: list, where: str):
        self.robot = robot
        self.known = list(known)
        listing = f"known robots: {', '.join(self.known)}" if self.known else "the database has no robots yet"
        super().__init__(f"robot {robot!r} is not in the history database {where}; {listing}")


class Quantity(NamedTuple):
    """A stored number with its unit."""

    value: float
    unit: str


class ParameterRow(NamedTuple):
    """One stored parameter: change from nominal, identified value and std (None if not stored), unit."""

    delta: float
    value: float | None
    std: float | None
    unit: str


@dataclass(frozen=True)
class CycleRecord:
    """One cycle as listed by :meth:`HistoryStore.cycles`. Times are UTC."""

    id: int
    robot: str
    kind: str
    status: str
    started_at: datetime
    finished_at: datetime | None
    notes: str | None
    meta: dict
    metrics: dict = field(default_factory=dict)  # name -> Quantity
    n_measurements: int = 0
    n_parameters: int = 0
    n_corrections: int = 0


@dataclass(frozen=True)
class Series:
    """A time series over committed cycles, oldest first.

    ``times`` are ``datetime64[us]`` in UTC (numpy keeps no zone); ``values`` shape (N,) in
    ``unit``; ``std`` shape (N,), NaN where no uncertainty was stored; ``cycle_ids`` and
    ``kinds`` say which cycle each value comes from.
    """

    name: str
    unit: str
    times: np.ndarray
    values: np.ndarray
    std: np.ndarray
    cycle_ids: np.ndarray
    kinds: tuple

    def __len__(self) -> int:
        return int(self.values.shape[0])


@dataclass(frozen=True)
class StoredCycle:
    """Everything one cycle stored (:meth:`HistoryStore.load_cycle`).

    Measurements: ``pose_index`` (N,), ``targets``/``sensors`` (N,) labels, ``joints`` (N, n) in
    ``joint_units`` (rad revolute, mm prismatic), ``points_mm`` (N, 3). Corrections:
    ``corrections_joints_before``/``_after`` (M, n), ``correction_programs``/``_point_names`` (M,),
    ``correction_point_index`` (M,).
    """

    record: CycleRecord
    pose_index: np.ndarray
    targets: tuple
    sensors: tuple
    joints: np.ndarray
    joint_units: tuple
    points_mm: np.ndarray
    parameters: dict  # name -> ParameterRow
    correction_programs: tuple
    correction_point_index: np.ndarray
    correction_point_names: tuple
    corrections_joints_before: np.ndarray
    corrections_joints_after: np.ndarray

