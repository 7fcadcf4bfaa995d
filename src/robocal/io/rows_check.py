"""Row-level checks of measurement data: duplicate pose ids and rows, and joint ranges.

Duplicates matter beyond tidiness: a repeated pose lands on both sides of the calibration /
held-out split, so the validation is no longer independent. They are an error, or, when asked,
every repeat after the first is dropped and reported. Joint values beyond one turn (+-2 pi) or
beyond the robot's limits (when a robot model is given) are an error naming row and column.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["duplicate_rows", "joint_ranges"]


def duplicate_rows(table, drop: bool, metadata: dict, fail):
    """``table`` (:class:`~robocal.io.stream.NumericTable`) without repeats: a pose id seen before,
    or a row whose numbers equal an earlier row's. Without ``drop`` the first repeat calls
    ``fail(message, line, column)``; with it, repeats are dropped and listed in
    ``metadata["dropped_duplicates"]`` (line numbers and ids). Vectorised (sorting), so a
    million rows take well under a second."""
    n = len(table)
    if n < 2:
        return table
    if len(set(table.ids)) == n:
        first_id = np.arange(n)
    else:
        first: dict = {}
        first_id = np.array([first.setdefault(pid, r) for r, pid in enumerate(table.ids)])
    # rows: a random projection finds candidates, an exact comparison confirms them
    numbers = table.values[:, 1:]
    key = numbers @ np.random.default_rng(0).normal(size=numbers.shape[1])
    first_row = _first_occurrence(key)
    cand = np.flatnonzero(first_row != np.arange(n))
    differ = ~np.all(numbers[cand] == numbers[first_row[cand]], axis=1)
    first_row[cand[differ]] = cand[differ]
    repeat = (first_id != np.arange(n)) | (first_row != np.arange(n))
    if not repeat.any():
        return table
    rows = np.flatnonzero(repeat)
    if not drop:
        r = int(rows[0])
        if first_id[r] != r:
            f, message, column = first_id[r], f"duplicate pose id {table.ids[r]!r}", "pose"
        else:
            f, message, column = first_row[r], "duplicate row: the same numbers as", None
            message += f" pose {table.ids[f]!r}"
        fail(f"{message} (first on line {table.lines[f]}); {len(rows)} repeated row(s) in the file: remove them, "
             "or pass --drop-duplicates to keep the first of each", int(table.lines[r]), column)
    metadata["dropped_duplicates"] = "; ".join(f"line {table.lines[r]} (pose {table.ids[r]})" for r in rows)
    return table.subset(np.flatnonzero(~repeat))


def _first_occurrence(keys) -> np.ndarray:
    """(N,) index of the first element equal to each element of ``keys``."""
    _, first, inverse = np.unique(keys, return_index=True, return_inverse=True)
    return first[np.ravel(inverse)]


def joint_ranges(q, lf: float, af: float, lines, joint_names, prismatic, robot, angle_unit: str, fail) -> None:
    """Revolute joint values ``q`` (N, n) [rad | mm] beyond +-2 pi, and any joint beyond the limits
    of ``robot`` (when given; controller joints in ``joint_names`` order) call ``fail`` naming the
    line and the column (values in the file's units: ``q`` / ``lf`` or ``af``)."""
    revolute = ~np.asarray(prismatic, dtype=bool)
    q_file = _FileValues(q, np.where(revolute, af, lf))
    turn = 2.0 * math.pi + 1e-9
    if revolute.any() and (q[:, revolute].max(initial=0.0) > turn or q[:, revolute].min(initial=0.0) < -turn):
        beyond = (np.abs(q) > turn) & revolute
        r, j = np.argwhere(beyond)[0]
        fail(f"joint value {q_file[r, j]:g} {angle_unit} is beyond one turn (+-{_turn(angle_unit)}): not a joint "
             "position a robot reports", int(lines[r]), joint_names[j])
    if robot is None:
        return
    lo, hi = robot.limits[:, 0], robot.limits[:, 1]
    if (q.min(axis=0, initial=np.inf) >= lo - 1e-9).all() and (q.max(axis=0, initial=-np.inf) <= hi + 1e-9).all():
        return
    outside = (q < lo - 1e-9) | (q > hi + 1e-9)
    if outside.any():
        r, j = np.argwhere(outside)[0]
        scale = 1.0 if prismatic[j] else (math.degrees(1.0) if angle_unit == "deg" else 1.0)
        unit = "mm" if prismatic[j] else angle_unit
        fail(f"joint value {q_file[r, j]:g} {unit} is outside the limits of {robot.name} "
             f"[{lo[j] * scale:.6g}, {hi[j] * scale:.6g}] {unit}: swapped joint columns or the wrong robot?",
             int(lines[r]), joint_names[j])


class _FileValues:
    """``q[r, j] / scale[j]`` on demand: a joint value in the file's unit for a message."""

    def __init__(self, q, scale):
        self.q, self.scale = q, scale

    def __getitem__(self, rj):
        r, j = rj
        return float(self.q[r, j] / self.scale[j])


def _turn(angle_unit: str) -> str:
    return "360 deg" if angle_unit == "deg" else f"{2.0 * math.pi:.4f} rad"
