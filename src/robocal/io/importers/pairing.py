"""Pairing tracker points with controller joint rows: by index, by id or by time stamp.

The result is robocal's :class:`~robocal.io.measurements.Measurements` (one target per pose)
plus an honest account of what did not pair: every point and every joint row left over is listed
with its line and the reason.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

import numpy as np

from ..header import FileFormatError
from ..measurements import DEFAULT_TARGET, Measurements

__all__ = ["Unmatched", "Pairing", "pair_by_index", "pair_by_id", "pair_by_time"]


@dataclass(frozen=True)
class Unmatched:
    """A point (``source="points"``) or joint row (``source="joints"``) that found no partner."""

    source: str
    id: str
    path: str
    line: int
    reason: str

    def __str__(self) -> str:
        what = "point" if self.source == "points" else "joint row"
        return f"{self.path}, line {self.line}: {what} {self.id!r} not paired: {self.reason}"


@dataclass(frozen=True, eq=False)
class Pairing:
    """Paired data and what was left over.

    measurements: one pose per pair, in tracker-file order; pose ids are the point ids.
    unmatched: leftover points and joint rows with reasons. time_differences: (N,) joint time
    minus point time [s] per pair (``pair_by_time`` only). notes: what was assumed.
    """

    measurements: Measurements
    unmatched: tuple
    time_differences: np.ndarray | None = None
    notes: tuple = ()

    def report(self) -> str:
        """A few lines for the console: pairs, leftovers with reasons, notes."""
        n = self.measurements.n_poses
        lines = [f"{n} pose(s) paired; {len(self.unmatched)} row(s) not paired"]
        lines += [f"  {u}" for u in self.unmatched]
        lines += [f"  note: {note}" for note in self.notes]
        return "\n".join(lines)

    def summary(self, max_listed: int = 10) -> list:
        """Console lines: one summary line (paired, points and joint rows not paired, and with time
        pairing the median and largest |dt| [s]), then every unpaired *point* (up to
        ``max_listed``, a count beyond); unpaired joint rows only as a count (a streamed log has
        many more rows than poses) unless there are at most ``max_listed`` of them."""
        pts = [u for u in self.unmatched if u.source == "points"]
        rows = [u for u in self.unmatched if u.source == "joints"]
        head = (f"{self.measurements.n_poses} pose(s) paired; {len(pts)} point(s) and {len(rows)} joint row(s) "
                "not paired")
        dt = self.time_differences
        if dt is not None and len(dt):
            a = np.abs(dt)
            head += f"; |dt| median {np.median(a):.3g} s, max {np.max(a):.3g} s"
        lines = [head]
        lines += [f"  not paired: {u}" for u in pts[:max_listed]]
        if len(pts) > max_listed:
            lines.append(f"  ... and {len(pts) - max_listed} more point(s) not paired")
        if rows and len(rows) <= max_listed:
            lines += [f"  not paired: {u}" for u in rows]
        return lines


def _build(points, log, pairs, unmatched, how, robot, target, dt=None) -> Pairing:
    if not pairs:
        detail = "; ".join(str(u) for u in unmatched[:5])
        raise ValueError(f"no point of {points.path} paired with a joint row of {log.path} ({how}): {detail}")
    ip = [i for i, _ in pairs]
    jl = [j for _, j in pairs]
    notes = (*points.notes, *log.notes, f"paired {how}")
    metadata = {"length_unit": points.length_unit, "angle_unit": log.angle_unit, "frame": "tracker",
                "note": "\n".join([f"imported from {points.path} and {log.path}", *notes])}
    if robot is not None:
        metadata["robot"] = getattr(robot, "name", str(robot))
    rotations = getattr(points, "rotations", None)
    if rotations is not None:
        metadata["orientation"] = points.orientation
    meas = Measurements(joints=log.joints[jl], points=points.points[ip][:, None, :], targets=(target,),
                        joint_names=log.joint_names, pose_ids=[points.ids[i] for i in ip],
                        prismatic=log.prismatic, metadata=metadata,
                        rotations=None if rotations is None else rotations[ip])
    return Pairing(measurements=meas, unmatched=tuple(unmatched), time_differences=dt, notes=notes)


def pair_by_index(points, log, *, robot=None, target: str = DEFAULT_TARGET) -> Pairing:
    """Pair the k-th point with the k-th joint row; extra rows of the longer file are reported."""
    n = min(len(points), len(log))
    unmatched = [Unmatched("points", points.ids[k], points.path, points.lines[k], f"only {len(log)} joint rows")
                 for k in range(n, len(points))]
    unmatched += [Unmatched("joints", log.ids[k], log.path, log.lines[k], f"only {len(points)} points")
                  for k in range(n, len(log))]
    return _build(points, log, [(k, k) for k in range(n)], unmatched, "by row index", robot, target)


def _id_key(pid: str, match: str):
    if match == "exact":
        return pid.strip().casefold()
    numbers = re.findall(r"\d+", pid)
    return int(numbers[-1]) if numbers else pid.strip().casefold()


def _index_ids(ids, lines, path, match) -> dict:
    out: dict = {}
    for k, (pid, ln) in enumerate(zip(ids, lines)):
        key = _id_key(pid, match)
        if key in out:
            raise FileFormatError(path, f"id {pid!r} also on line {lines[out[key]]}: ids must be unique to pair "
                                        "by id", ln)
        out[key] = k
    return out


def pair_by_id(points, log, *, match: str = "exact", robot=None, target: str = DEFAULT_TARGET) -> Pairing:
    """Pair points and joint rows with equal ids.

    match: ``"exact"`` (case-insensitive text) or ``"number"`` (the last integer in the id, so
    ``P017``, ``17`` and ``pose_17`` pair). Duplicate ids in either file are an error.
    """
    if match not in ("exact", "number"):
        raise ValueError(f"match: expected 'exact' or 'number', got {match!r}")
    rows = _index_ids(log.ids, log.lines, log.path, match)
    _index_ids(points.ids, points.lines, points.path, match)
    pairs, used, unmatched = [], set(), []
    for i, pid in enumerate(points.ids):
        j = rows.get(_id_key(pid, match))
        if j is None:
            unmatched.append(Unmatched("points", pid, points.path, points.lines[i], "no joint row with this id"))
        else:
            pairs.append((i, j))
            used.add(j)
    unmatched += [Unmatched("joints", log.ids[j], log.path, log.lines[j], "no point with this id")
                  for j in range(len(log)) if j not in used]
    return _build(points, log, pairs, unmatched, f"by id ({match})", robot, target)


def pair_by_time(points, log, *, tolerance: float, offset: float = 0.0, robot=None,
                 target: str = DEFAULT_TARGET) -> Pairing:
    """Pair each point with the joint row nearest in time, if within ``tolerance`` [s].

    offset: added to the joint log's times before comparing [s] (a known clock difference).
    A joint row claimed by several points goes to the nearest; the others are reported.
    """
    if points.times is None or log.times is None:
        missing = points.path if points.times is None else log.path
        raise ValueError(f"pair_by_time: {missing} has no time-stamp column")
    if points.time_kind != log.time_kind:
        raise ValueError(f"pair_by_time: {points.path} has {points.time_kind} time stamps but {log.path} has "
                         f"{log.time_kind}; both must be on the same kind of clock")
    if not tolerance > 0:
        raise ValueError(f"tolerance: expected a positive number of seconds, got {tolerance!r}")
    t_log = log.times + offset
    nearest = np.argmin(np.abs(points.times[:, None] - t_log[None, :]), axis=1)
    dt = t_log[nearest] - points.times
    owner: dict[int, int] = {}
    unmatched = []
    for i in np.argsort(np.abs(dt), kind="stable"):
        j = int(nearest[i])
        if abs(dt[i]) > tolerance:
            reason = f"nearest joint row (line {log.lines[j]}) is {dt[i]:+.3f} s away (tolerance {tolerance:g} s)"
        elif j in owner:
            reason = f"its nearest joint row (line {log.lines[j]}) is paired with closer point {points.ids[owner[j]]!r}"
        else:
            owner[j] = int(i)
            continue
        unmatched.append(Unmatched("points", points.ids[i], points.path, points.lines[i], reason))
    unmatched.sort(key=lambda u: u.line)
    unmatched += [Unmatched("joints", log.ids[j], log.path, log.lines[j],
                            f"no point within {tolerance:g} s") for j in range(len(log)) if j not in owner]
    pairs = sorted((i, j) for j, i in owner.items())
    return _build(points, log, pairs, unmatched, f"by time stamp (tolerance {tolerance:g} s, offset {offset:g} s)",
                  robot, target, dt=np.array([dt[i] for i, _ in pairs]))
