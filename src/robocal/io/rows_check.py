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
    ``metadata["dropped_duplicates"]`` (line numbers and ids)."""
    first_of_id: dict = {}
    repeats = []  # (row index, message)
    for r, pid in enumerate(table.ids):
        if pid in first_of_id:
            repeats.append((r, f"duplicate pose id {pid!r} (first on line {table.lines[first_of_id[pid]]})", "pose"))
        else:
            first_of_id[pid] = r
    values = table.values[:, 1:]
    if len(values):
        _, first, inverse = np.unique(values, axis=0, return_index=True, return_inverse=True)
        inverse = np.ravel(inverse)
        seen_ids = {r for r, _, _ in repeats}
        for r in np.flatnonzero(first[inverse] != np.arange(len(values))):
            if r not in seen_ids:
                f = int(first[inverse[r]])
                repeats.append((int(r), f"duplicate row: the same numbers as pose {table.ids[f]!r} on line "
                                        f"{table.lines[f]}", None))
    if not repeats:
        return table
    repeats.sort()
    if not drop:
        r, message, column = repeats[0]
        fail(f"{message}; {len(repeats)} repeated row(s) in the file: remove them, or pass --drop-duplicates to "
             "keep the first of each", int(table.lines[r]), column)
    gone = {r for r, _, _ in repeats}
    metadata["dropped_duplicates"] = "; ".join(f"line {table.lines[r]} (pose {table.ids[r]})" for r in sorted(gone))
    return table.subset([r for r in range(len(table)) if r not in gone])


def joint_ranges(q, q_file, lines, joint_names, prismatic, robot, angle_unit: str, fail) -> None:
    """Revolute joint values ``q`` (N, n) [rad] beyond +-2 pi, and any joint beyond the limits of
    ``robot`` (when given; controller joints in ``joint_names`` order) call ``fail`` naming the
    line and the column."""
    revolute = ~np.asarray(prismatic, dtype=bool)
    beyond = (np.abs(q) > 2.0 * math.pi + 1e-9) & revolute
    if beyond.any():
        r, j = np.argwhere(beyond)[0]
        fail(f"joint value {q_file[r, j]:g} {angle_unit} is beyond one turn (+-{_turn(angle_unit)}): not a joint "
             "position a robot reports", int(lines[r]), joint_names[j])
    if robot is None:
        return
    lo, hi = robot.limits[:, 0], robot.limits[:, 1]
    outside = (q < lo - 1e-9) | (q > hi + 1e-9)
    if outside.any():
        r, j = np.argwhere(outside)[0]
        scale = 1.0 if prismatic[j] else (math.degrees(1.0) if angle_unit == "deg" else 1.0)
        unit = "mm" if prismatic[j] else angle_unit
        fail(f"joint value {q_file[r, j]:g} {unit} is outside the limits of {robot.name} "
             f"[{lo[j] * scale:.6g}, {hi[j] * scale:.6g}] {unit}: swapped joint columns or the wrong robot?",
             int(lines[r]), joint_names[j])


def _turn(angle_unit: str) -> str:
    return "360 deg" if angle_unit == "deg" else f"{2.0 * math.pi:.4f} rad"
