"""Measured points without joint values, as imported from an instrument's export."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

__all__ = ["TrackerPoints"]


@dataclass(frozen=True, eq=False)
class TrackerPoints:
    """Points read from an instrument export; joints come from a controller log (see :mod:`.pairing`).

    ids: N point names as written (``"P17"``, ``"17"``; ``"1" .. "N"`` when the file has none).
    points: (N, 3) positions [mm] in the instrument's frame.
    lines: N 1-based line numbers of the rows in ``path``.
    groups: N group names (SpatialAnalyzer ``Collection::Group``) or ``None``.
    times: (N,) time stamps [s] on the clock ``time_kind`` (see :mod:`.timestamps`) or ``None``.
    length_unit: the unit of the file (``"mm"``, ``"m"``, ``"in"``); ``points`` are always mm.
    notes: what the importer assumed or found (units detected, encoding, rows skipped).
    rotations: (N, 3, 3) measured orientations of a 6-DoF probe in the instrument's frame, or ``None``.
    orientation: the convention the file's orientation columns were read in (``None`` without).
    """

    ids: tuple
    points: np.ndarray
    lines: tuple
    path: str
    groups: tuple | None = None
    times: np.ndarray | None = None
    time_kind: str | None = None
    length_unit: str = "mm"
    notes: tuple = field(default=())
    rotations: np.ndarray | None = None
    orientation: str | None = None

    def __post_init__(self):
        p = np.array(self.points, dtype=float).reshape(-1, 3)
        p.setflags(write=False)
        object.__setattr__(self, "points", p)
        n = len(p)
        for name in ("ids", "lines", "groups"):
            value = getattr(self, name)
            if value is not None and len(value) != n:
                raise ValueError(f"TrackerPoints.{name}: {len(value)} entries for {n} points")
        if self.times is not None:
            t = np.array(self.times, dtype=float)
            if t.shape != (n,):
                raise ValueError(f"TrackerPoints.times: expected shape ({n},), got {t.shape}")
            t.setflags(write=False)
            object.__setattr__(self, "times", t)
        if self.rotations is not None:
            R = np.array(self.rotations, dtype=float)
            if R.shape != (n, 3, 3):
                raise ValueError(f"TrackerPoints.rotations: expected shape ({n}, 3, 3), got {R.shape}")
            R.setflags(write=False)
            object.__setattr__(self, "rotations", R)

    def __len__(self) -> int:
        return len(self.points)
