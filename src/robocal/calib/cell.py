"""The robot cell: where a pose can be measured and a path can be driven.

A :class:`Cell` holds, in the cell frame (z up), the robot's mounting (``T_cell_base``), the
mounting plane (an obstacle: nothing but the base may reach it), boxes (tables, fixtures, fences),
the measuring instrument (position, range, reflector acceptance angle, line of sight), the tool
(points on the flange and a capsule radius) and joint ranges the user restricts. The robot's links
are capsules (:mod:`robocal.kinematics.collision`). :func:`pose_feasibility` says per pose and per
reason whether a pose can be measured; :func:`path_feasible` checks the joint-space motion between
two poses at sampled points; :func:`order_poses` orders a campaign for a short path whose every
move is feasible. The file format (``robocal-cell/1``) is read by :mod:`robocal.io.cell_file`.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..kinematics.collision import default_link_radii, link_segments, segment_box_distance, \
    segment_plane_distance, segment_segment_distance

__all__ = ["Box", "Instrument", "Cell", "default_cell", "pose_feasibility", "feasible", "path_points",
           "path_feasible", "order_poses", "nearest_equivalent", "path_length", "sample_feasible", "REASONS", "PATH_REASONS",
           "PATH_STEP_DEG"]

#: Names of the feasibility checks, in the order they are reported.
REASONS = ("joint_range", "mounting_plane", "box", "self_collision", "range", "acceptance", "line_of_sight")
#: Largest joint move between two sampled points of a path [deg] (mm for a linear axis: this many mm).
PATH_STEP_DEG = 2.0


@dataclass(frozen=True)
class Box:
    """An axis-aligned box obstacle in the cell frame: ``lo``, ``hi`` (3,) [mm]."""

    name: str
    lo: tuple
    hi: tuple


@dataclass(frozen=True)
class Instrument:
    """A laser tracker (or another line-of-sight instrument) in the cell frame.

    position: (3,) [mm]; range_mm: (nearest, farthest) distance to the reflector [mm];
    acceptance_deg: largest angle between the reflector axis and the line of sight [deg] (a 1.5"
    SMR is read within about +-30 deg); line_of_sight: check that the arm does not block the beam.
    """

    position: tuple
    range_mm: tuple = (1000.0, 15000.0)
    acceptance_deg: float = 30.0
    line_of_sight: bool = True


@dataclass(frozen=True)
class Cell:
    """A robot cell (lengths mm, angles rad).

    mounting: ``floor``, ``ceiling``, ``wall`` or ``tilted`` (how ``T_cell_base`` was made);
    T_cell_base: (4, 4) the robot base in the cell frame; plane_point, plane_normal: (3,) the
    mounting plane in the cell frame, its normal pointing to the robot's side;
    boxes: obstacles; instrument: :class:`Instrument` or None; tool_mm: (k, 3) points of the tool in
    the flange frame, the last one the reflector; tool_axis: (3,) the reflector axis in the flange
    frame; tool_radius_mm: capsule radius of the tool; joint_ranges: (n, 2) [rad | mm] the user's
    restriction of the joint limits (None: the robot file's); link_radii_mm: capsule radius per
    chain segment (None: robot file or :func:`default_link_radii`); clearance_mm: distance kept
    from every obstacle [mm].
    """

    mounting: str = "floor"
    T_cell_base: np.ndarray = field(default_factory=lambda: np.eye(4))
    plane_point: tuple = (0.0, 0.0, 0.0)
    plane_normal: tuple = (0.0, 0.0, 1.0)
    boxes: tuple = ()
    instrument: Instrument | None = None
    tool_mm: tuple = ((0.0, 0.0, 100.0),)
    tool_axis: tuple = (0.0, 0.0, 1.0)
    tool_radius_mm: float = 25.0
    joint_ranges: np.ndarray | None = None
    link_radii_mm: tuple | None = None
    clearance_mm: float = 10.0
    source: str = "default: floor-mounted robot, its mounting plane an obstacle"

    @property
    def reflector_mm(self) -> np.ndarray:
        """(3,) the reflector (last tool point) in the flange frame [mm]."""
        return np.asarray(self.tool_mm[-1], dtype=float)

    def with_tool(self, tool_mm) -> "Cell":
        """The same cell with the reflector at ``tool_mm`` (3,) [mm] in the flange frame."""
        from dataclasses import replace

        return replace(self, tool_mm=(tuple(float(v) for v in tool_mm),))

    def with_instrument(self, instrument) -> "Cell":
        from dataclasses import replace

        return replace(self, instrument=instrument)

    def limits(self, model) -> np.ndarray:
        """(n, 2) joint ranges [rad | mm]: the robot's limits intersected with the user's."""
        lim = np.array(model.limits, dtype=float)
        if self.joint_ranges is not None:
            r = np.asarray(self.joint_ranges, dtype=float)
            lim = np.stack([np.maximum(lim[:, 0], r[:, 0]), np.minimum(lim[:, 1], r[:, 1])], axis=1)
        return lim


def default_cell(tool_mm=(0.0, 0.0, 100.0), instrument=None) -> Cell:
    """The cell without a cell file: a floor-mounted robot (base frame = cell frame), the floor
    ``z = 0`` an obstacle, the reflector at ``tool_mm`` (3,) [mm] on the flange."""
    return Cell(tool_mm=(tuple(float(v) for v in tool_mm),), instrument=instrument)


def _radii(cell: Cell, model, segs) -> np.ndarray:
    n_link = int((~segs.is_tool).sum())
    if cell.link_radii_mm is not None:
        r = np.asarray(cell.link_radii_mm, dtype=float)
    elif model.extra.get("link_radii_mm") is not None:  # per body: base, then each moving link
        r = np.asarray(model.extra["link_radii_mm"], dtype=float)[segs.body[~segs.is_tool]]
    else:
        r = default_link_radii(segs.lengths_mm[~segs.is_tool])
    if r.size == 1:
        r = np.full(n_link, float(r.ravel()[0]))
    if len(r) != n_link:
        raise ValueError(f"{model.name}: {len(r)} link radii for {n_link} link segments")
    return np.concatenate([r, np.full(int(segs.is_tool.sum()), cell.tool_radius_mm)])


def _segments_in_cell(cell: Cell, model, q):
    segs = link_segments(model, q, tool_mm=np.asarray(cell.tool_mm, dtype=float))
    T = np.asarray(cell.T_cell_base, dtype=float)
    segs.p0 = segs.p0 @ T[:3, :3].T + T[:3, 3]
    segs.p1 = segs.p1 @ T[:3, :3].T + T[:3, 3]
    return segs


def pose_feasibility(cell: Cell, model, q) -> dict:
    """Per reason of :data:`REASONS`, a (N,) bool array: pose ``q`` (N, n) [rad | mm] FAILS it.

    joint_range: outside the robot's limits or the cell's joint ranges. mounting_plane: a moving
    link or the tool closer than its radius + clearance to the mounting plane (or behind it). box:
    a moving link or the tool within radius + clearance of a box. self_collision: two link capsules
    (or a link and the tool) overlap; pairs of neighbouring links are not checked (bodies one joint
    apart, the base and the body two joints up -- the upper arm, which real arms carry beside the
    base column where the DH chain draws it above -- and pairs whose chain between them is shorter
    than their radii: they touch by construction). range / acceptance / line_of_sight (with an instrument): the
    reflector out of range, its axis farther than the acceptance angle from the line of sight, or
    the beam passing within a link's radius or through a box.
    """
    q = np.atleast_2d(np.asarray(q, dtype=float))
    lim = cell.limits(model)
    out = {"joint_range": np.any((q < lim[:, 0] - 1e-9) | (q > lim[:, 1] + 1e-9), axis=1)}
    segs = _segments_in_cell(cell, model, q)
    r = _radii(cell, model, segs)
    moving = segs.body > 0
    clear = cell.clearance_mm
    dplane = segment_plane_distance(segs.p0[:, moving], segs.p1[:, moving], cell.plane_point, cell.plane_normal)
    out["mounting_plane"] = np.any(dplane < r[moving] + clear, axis=1)
    hit_box = np.zeros(len(q), dtype=bool)
    for b in cell.boxes:
        d = segment_box_distance(segs.p0[:, moving], segs.p1[:, moving], b.lo, b.hi)
        hit_box |= np.any(d < r[moving] + clear, axis=1)
    out["box"] = hit_box
    S = len(segs)
    i, j = np.triu_indices(S, k=1)
    gap = np.abs(segs.body[i] - segs.body[j])
    pair = (gap >= np.where(np.minimum(segs.body[i], segs.body[j]) == 0, 3, 2)) & (segs.chain_mm[i, j] > r[i] + r[j])
    i, j = i[pair], j[pair]
    d = segment_segment_distance(segs.p0[:, i], segs.p1[:, i], segs.p0[:, j], segs.p1[:, j])
    out["self_collision"] = np.any(d < r[i] + r[j], axis=1)
    ins = cell.instrument
    for k in ("range", "acceptance", "line_of_sight"):
        out[k] = np.zeros(len(q), dtype=bool)
    if ins is not None:
        T = np.asarray(cell.T_cell_base) @ np.linalg.inv(model.T_world_base) @ model.fk(q)
        refl = T[:, :3, 3] + T[:, :3, :3] @ cell.reflector_mm
        axis = T[:, :3, :3] @ np.asarray(cell.tool_axis, dtype=float)
        sight = np.asarray(ins.position, dtype=float) - refl
        dist = np.linalg.norm(sight, axis=1)
        out["range"] = (dist < ins.range_mm[0]) | (dist > ins.range_mm[1])
        cos = np.einsum("ij,ij->i", sight, axis) / np.maximum(dist * np.linalg.norm(axis, axis=1), 1e-9)
        out["acceptance"] = cos < np.cos(np.radians(ins.acceptance_deg))
        if ins.line_of_sight:
            arm = ~segs.is_tool
            src = np.broadcast_to(np.asarray(ins.position, dtype=float), refl.shape)
            # the beam is checked from 2 link radii off the reflector on: the flange it sits on is
            # the acceptance angle's business
            start = refl + (2.0 * r[arm].max()) * sight / np.maximum(dist, 1e-9)[:, None]
            db = segment_segment_distance(segs.p0[:, arm], segs.p1[:, arm], start[:, None], src[:, None])
            blocked = np.any(db < r[arm], axis=1)
            for b in cell.boxes:
                blocked |= segment_box_distance(refl, src, b.lo, b.hi) <= 0.0
            out["line_of_sight"] = blocked
    return out


def feasible(cell: Cell, model, q, reasons=REASONS) -> np.ndarray:
    """(N,) bool: the poses ``q`` (N, n) pass every check named in ``reasons``."""
    fails = pose_feasibility(cell, model, q)
    bad = np.zeros(len(np.atleast_2d(q)), dtype=bool)
    for k in reasons:
        bad |= fails[k]
    return ~bad


def path_points(q_from, q_to, step: float = np.radians(PATH_STEP_DEG)) -> np.ndarray:
    """Sampled joint-space interpolation (m, n) from ``q_from`` to ``q_to`` (n,) each, no joint
    moving more than ``step`` [rad | mm] between samples; both end points included."""
    q_from, q_to = np.asarray(q_from, float), np.asarray(q_to, float)
    m = max(int(np.ceil(np.max(np.abs(q_to - q_from)) / step)), 1)
    t = np.linspace(0.0, 1.0, m + 1)[:, None]
    return q_from + t * (q_to - q_from)


#: Checks that apply along a path (the instrument need not see the reflector while moving).
PATH_REASONS = ("joint_range", "mounting_plane", "box", "self_collision")


def path_feasible(cell: Cell, model, q_from, q_to_many, step: float = np.radians(PATH_STEP_DEG)) -> np.ndarray:
    """(M,) bool: the joint-space motion from ``q_from`` (n,) to each of ``q_to_many`` (M, n) stays
    clear of the mounting plane, the boxes and itself at every sampled point (:func:`path_points`)."""
    q_to_many = np.atleast_2d(np.asarray(q_to_many, float))
    paths = [path_points(q_from, q, step) for q in q_to_many]
    ok = feasible(cell, model, np.vstack(paths), PATH_REASONS)
    ends = np.cumsum([len(p) for p in paths])
    return np.array([bool(np.all(ok[e - len(p):e])) for p, e in zip(paths, ends)], dtype=bool)


def nearest_equivalent(q, q_ref, limits, revolute) -> np.ndarray:
    """``q`` (M, n) with every revolute joint moved by whole turns (2 pi) to be nearest ``q_ref``
    (n,) while staying within ``limits`` (n, 2) [rad] and one turn: the same pose, a shorter move (a UR's
    +-360 deg joints)."""
    q = np.array(q, dtype=float, copy=True)
    lo, hi = limits[:, 0], limits[:, 1]
    for k in np.flatnonzero(revolute):
        for turn in (-2.0 * np.pi, 2.0 * np.pi):
            alt = q[:, k] + turn
            better = ((np.abs(alt - q_ref[k]) < np.abs(q[:, k] - q_ref[k])) & (alt >= lo[k]) & (alt <= hi[k])
                      & (np.abs(alt) <= 2.0 * np.pi))  # measurement files refuse more than a turn
            q[better, k] = alt[better]
    return q


def order_poses(cell: Cell, model, q, *, start: int = 0, batch: int = 6) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Order the poses ``q`` (N, n) for a short path whose every move is feasible.

    Greedy nearest neighbour in joint space (distance: the largest joint move, what sets the
    motion time) from pose ``start``, each move checked with :func:`path_feasible` (the ``batch``
    nearest tried at once); a revolute joint with more than a turn of range takes the equivalent
    angle nearest the previous pose (:func:`nearest_equivalent`). A pose the greedy path cannot
    reach is inserted between two poses it joins by feasible moves (cheapest first). Returns ``(q_driven, order,
    left_out)``: the poses in driving order (joint values as driven), their indices into ``q``, and
    the indices of poses that fit nowhere (the caller re-plans them).
    """
    q = np.atleast_2d(np.asarray(q, dtype=float))
    lim = cell.limits(model)
    revolute = ~model.prismatic_joints
    remaining = [i for i in range(len(q)) if i != start]
    order, driven = [start], [q[start]]
    left_out = []
    while remaining:
        cur = driven[-1]
        rem = np.array(remaining)
        qr = nearest_equivalent(q[rem], cur, lim, revolute)
        sort = np.argsort(np.max(np.abs(qr - cur), axis=1), kind="stable")
        rem, qr = rem[sort], qr[sort]
        nxt = None
        for k in range(0, len(rem), batch):
            ok = path_feasible(cell, model, cur, qr[k:k + batch])
            if ok.any():
                nxt = k + int(np.argmax(ok))
                break
        if nxt is None:
            break
        order.append(int(rem[nxt]))
        driven.append(qr[nxt])
        remaining.remove(int(rem[nxt]))
    for i in remaining:  # stuck: insert each pose left where both moves around it are feasible
        if not _insert(cell, model, q[i], i, order, driven, lim, revolute):
            left_out.append(i)
    return np.array(driven), np.array(order, dtype=int), np.array(sorted(left_out), dtype=int)


def _insert(cell, model, qi, i, order, driven, lim, revolute, tries: int = 24) -> bool:
    """Insert pose ``qi`` (index ``i``) into the path ``driven`` between two poses it joins by feasible
    moves (cheapest added motion first; at the end too); False when no place of ``tries`` works."""
    D = np.array(driven)
    cand = np.empty_like(D)
    for k in range(len(D)):
        cand[k] = nearest_equivalent(qi[None], D[k], lim, revolute)[0]
    step = np.max(np.abs(np.diff(D, axis=0)), axis=1) if len(D) > 1 else np.zeros(0)
    to_prev = np.max(np.abs(cand - D), axis=1)  # pose k -> qi
    cost = np.append(to_prev[:-1] + np.max(np.abs(cand[:-1] - D[1:]), axis=1) - step, to_prev[-1])
    for k in np.argsort(cost, kind="stable")[:tries]:  # insert after driven[k]
        qk = cand[k]
        if not path_feasible(cell, model, D[k], qk[None])[0]:
            continue
        if k + 1 < len(D) and not path_feasible(cell, model, qk, D[k + 1][None])[0]:
            continue
        order.insert(k + 1, i)
        driven.insert(k + 1, qk)
        return True
    return False


def path_length(q) -> float:
    """Sum over consecutive poses of the largest joint move [rad | mm] (what sets motion time)."""
    q = np.atleast_2d(np.asarray(q, dtype=float))
    return float(np.sum(np.max(np.abs(np.diff(q, axis=0)), axis=1))) if len(q) > 1 else 0.0


def sample_feasible(cell: Cell, model, n: int, rng, *, margin: float = 0.05, batch: int = 2000,
                    max_draws: int = 200000, reasons=REASONS) -> tuple[np.ndarray, int]:
    """``n`` feasible poses (n, n_joints) drawn uniformly within the cell's joint ranges (``margin``
    of each range kept free) by rejection. Returns ``(q, draws)``; ``ValueError`` when fewer than
    ``n`` of ``max_draws`` draws are feasible (the cell leaves too little room)."""
    lim = cell.limits(model)
    lo, hi = lim[:, 0], lim[:, 1]
    span = hi - lo
    kept, draws = [], 0
    total = 0
    while total < n:
        if draws >= max_draws:
            raise ValueError(f"only {total} of {draws} random poses of {model.name} are feasible in the cell "
                             f"({cell.source}); need {n}: move the instrument, widen the joint ranges or relax "
                             "the acceptance angle")
        q = rng.uniform(lo + margin * span, hi - margin * span, (batch, model.n_joints))
        draws += batch
        total += _keep_feasible(cell, model, q, reasons, n - total, kept)
    return np.vstack(kept)[:n], draws


def _keep_feasible(cell: Cell, model, q, reasons, need: int, kept: list) -> int:
    """Append to ``kept`` the feasible rows of the drawn batch ``q`` (N, n), in order, checking
    prefixes of the batch until ``need`` rows are found (each pose's check is its own: the rows
    kept are those a check of the whole batch keeps first). A 60-pose reference campaign checked
    ~130 poses instead of 2 000 (~5 ms of a 100-pose calibration's ~30 ms). Returns the count
    appended."""
    found, start, chunk = 0, 0, max(2 * need, 64)
    while start < len(q) and found < need:
        part = q[start:start + chunk]
        ok = feasible(cell, model, part, reasons)
        kept.append(part[ok])
        found += int(ok.sum())
        start += len(part)
        # next chunk: what the rate so far says is still missing, with room to spare
        rate = max(found / start, 1.0 / len(q))
        chunk = int(min(len(q), max(64, 1.5 * (need - found) / rate)))
    return found
