"""Distances between capsules, planes, boxes and beams, vectorised over poses.

A capsule is a segment ``p0 -> p1`` swept by a sphere of radius ``r``; two capsules touch when the
distance between their segments is at most the sum of their radii. Every function takes arrays with
any leading batch shape ``(...)`` and points ``(..., 3)`` [mm] and broadcasts; no Python loop runs
over poses. :func:`link_segments` turns a robot model's link frames into the segments of its link
capsules (the polyline of its kinematic chain); the radii come from the robot file
(``link_radius`` per joint) or :func:`default_link_radii`.
"""

from __future__ import annotations

import numpy as np

__all__ = [
    "segment_segment_distance", "segment_plane_distance", "segment_box_distance", "point_box_distance",
    "link_segments", "default_link_radii", "LinkSegments",
]

_EPS = 1e-12


def segment_segment_distance(p0, p1, q0, q1) -> np.ndarray:
    """Shortest distance (...,) [mm] between the segments ``p0 -> p1`` and ``q0 -> q1`` (..., 3).

    The closest points are found on the infinite lines, clamped to the segments, and the other
    parameter re-projected (the standard clamped two-step solution); degenerate (zero-length)
    segments are points.
    """
    p0, p1, q0, q1 = (np.asarray(v, dtype=float) for v in (p0, p1, q0, q1))
    d1, d2, r = p1 - p0, q1 - q0, p0 - q0
    a = np.einsum("...i,...i->...", d1, d1)
    e = np.einsum("...i,...i->...", d2, d2)
    f = np.einsum("...i,...i->...", d2, r)
    c = np.einsum("...i,...i->...", d1, r)
    b = np.einsum("...i,...i->...", d1, d2)
    denom = a * e - b * b
    with np.errstate(invalid="ignore", divide="ignore"):
        s = np.where(denom > _EPS * np.maximum(a * e, _EPS), (b * f - c * e) / np.where(denom > 0, denom, 1.0), 0.0)
        s = np.clip(np.where(a > _EPS, s, 0.0), 0.0, 1.0)
        t = np.where(e > _EPS, (b * s + f) / np.where(e > _EPS, e, 1.0), 0.0)
        t = np.clip(t, 0.0, 1.0)
        s = np.where(a > _EPS, np.clip((b * t - c) / np.where(a > _EPS, a, 1.0), 0.0, 1.0), 0.0)
    diff = (p0 + s[..., None] * d1) - (q0 + t[..., None] * d2)
    return np.linalg.norm(diff, axis=-1)


def segment_plane_distance(p0, p1, point, normal) -> np.ndarray:
    """Smallest signed distance (...,) [mm] of the segment ``p0 -> p1`` (..., 3) from the plane
    through ``point`` (3,) with ``normal`` (3,) (its positive side is the free side): negative when
    the segment crosses or lies behind the plane."""
    n = np.asarray(normal, dtype=float)
    n = n / np.linalg.norm(n)
    o = np.asarray(point, dtype=float)
    return np.minimum((np.asarray(p0, float) - o) @ n, (np.asarray(p1, float) - o) @ n)


def point_box_distance(p, box_min, box_max) -> np.ndarray:
    """Distance (...,) [mm] of points ``p`` (..., 3) from the axis-aligned box ``[box_min, box_max]``
    (3,) each; 0 inside."""
    p = np.asarray(p, dtype=float)
    gap = np.maximum(np.maximum(np.asarray(box_min, float) - p, p - np.asarray(box_max, float)), 0.0)
    return np.linalg.norm(gap, axis=-1)


def segment_box_distance(p0, p1, box_min, box_max, iterations: int = 40) -> np.ndarray:
    """Distance (...,) [mm] of the segment ``p0 -> p1`` (..., 3) from an axis-aligned box.

    The distance of a point from a convex set is convex along a segment, so a golden-section search
    over the segment parameter finds its minimum (``iterations`` steps shrink the bracket to
    0.618^40 ~ 4e-9 of the segment length).
    """
    p0 = np.asarray(p0, dtype=float)
    d = np.asarray(p1, dtype=float) - p0
    lo = np.zeros(p0.shape[:-1])
    hi = np.ones(p0.shape[:-1])
    g = (np.sqrt(5.0) - 1.0) / 2.0

    def f(t):
        return point_box_distance(p0 + t[..., None] * d, box_min, box_max)

    for _ in range(int(iterations)):
        m1 = hi - g * (hi - lo)
        m2 = lo + g * (hi - lo)
        left = f(m1) <= f(m2)
        hi = np.where(left, m2, hi)
        lo = np.where(left, lo, m1)
    t = 0.5 * (lo + hi)
    return np.minimum(np.minimum(f(t), f(np.zeros_like(t))), f(np.ones_like(t)))


class LinkSegments:
    """The segments of a robot's link capsules at N poses.

    p0, p1: (N, S, 3) segment end points [mm] in the robot base frame; body: (S,) index of the
    moving link each segment moves with (0 = the base, k = the k-th moving link); chain_mm: (S, S)
    length of the kinematic chain between two segments (0 for touching ones), used to skip pairs
    that always touch by construction; is_tool: (S,) bool, the segment belongs to the tool.
    """

    def __init__(self, p0, p1, body, chain_mm, is_tool=None):
        self.p0, self.p1, self.body, self.chain_mm = p0, p1, np.asarray(body), np.asarray(chain_mm)
        self.is_tool = np.zeros(len(self.body), dtype=bool) if is_tool is None else np.asarray(is_tool, dtype=bool)

    @property
    def lengths_mm(self) -> np.ndarray:
        """(S,) segment lengths [mm] (of the first pose)."""
        return np.linalg.norm(self.p1[0] - self.p0[0], axis=-1)

    def __len__(self) -> int:
        return self.p0.shape[1]


def link_segments(model, q, *, tool_mm=None, min_length_mm: float = 1.0) -> LinkSegments:
    """The kinematic chain of a serial robot ``model`` at joints ``q`` (N, n_ctrl) [rad | mm] as a
    polyline of segments in the robot base frame (``T_world_base`` not applied).

    For the DH kinds each link contributes the piece along the previous joint axis (``d``) and the
    common normal (``a``): exactly the DH chain; for other kinds the segment between consecutive
    frame origins, which belongs to the parent body (the next frame sits on the next joint's axis,
    fixed in the parent). ``tool_mm`` (k, 3) [mm] in the last link's frame continues the polyline from its
    origin through the tool's points (body of the last link). Segments shorter than
    ``min_length_mm`` are dropped. Returns :class:`LinkSegments`.
    """
    F = model.link_frames(np.atleast_2d(np.asarray(q, dtype=float)))  # (N, n_model, 4, 4) in the world
    if not np.allclose(model.T_world_base, np.eye(4)):
        F = np.linalg.inv(model.T_world_base) @ F
    N, n = F.shape[:2]
    frames = np.concatenate([np.broadcast_to(np.eye(4), (N, 1, 4, 4)), F], axis=1)
    points, bodies, tool = [frames[:, 0, :3, 3]], [], []
    for k in range(n):
        link = model.links[int(model.moving[k])]
        prev = frames[:, k]
        if link.convention in ("dh", "dh_beta"):
            d = link.params.get("d", 0.0)
            mid = prev[:, :3, 3] + d * prev[:, :3, 2]
            points.append(mid)
            bodies.append(k)  # the piece along joint k+1's axis moves with the previous body
            tool.append(False)
        if link.convention == "mdh":
            # Craig's form: the common normal a_(k) along the previous x, then d along the new z
            a = link.params.get("a", 0.0)
            points.append(prev[:, :3, 3] + a * prev[:, :3, 0])
            bodies.append(k)
            tool.append(False)
        points.append(frames[:, k + 1, :3, 3])
        # DH: the common normal a_(k+1) lies along x_(k+1) and moves with body k+1. Other kinds
        # (MDH, URDF, frames): frame k+1 sits on joint k+1's axis, placed in body k (the parent),
        # so the segment to it is body k's -- a column standing on the base (MDH d1) is the base's
        body_of_segment = k + 1 if link.convention in ("dh", "dh_beta") else k
        bodies.append(body_of_segment)
        tool.append(False)
    if tool_mm is not None:
        last = frames[:, -1]
        for t in np.atleast_2d(np.asarray(tool_mm, dtype=float)):
            points.append(last[:, :3, 3] + last[:, :3, :3] @ t)
            bodies.append(n)
            tool.append(True)
    P = np.stack(points, axis=1)  # (N, M, 3)
    p0, p1 = P[:, :-1], P[:, 1:]
    L = np.linalg.norm(p1[0] - p0[0], axis=-1)
    keep = L >= min_length_mm
    p0, p1, body, L = p0[:, keep], p1[:, keep], np.asarray(bodies)[keep], L[keep]
    is_tool = np.asarray(tool, dtype=bool)[keep]
    cum = np.concatenate([[0.0], np.cumsum(L)])
    S = len(L)
    i, j = np.meshgrid(np.arange(S), np.arange(S), indexing="ij")
    lo, hi = np.minimum(i, j), np.maximum(i, j)
    chain = np.where(hi > lo, cum[hi] - cum[lo + 1], 0.0)
    return LinkSegments(p0, p1, body, chain, is_tool)


def default_link_radii(segments_length_mm, *, fraction: float = 0.08, smallest_mm: float = 30.0,
                       largest_mm: float = 150.0) -> np.ndarray:
    """A capsule radius per segment [mm] where the robot file gives none: ``fraction`` of the
    robot's longest segment (its upper arm or forearm), clipped to ``[smallest_mm, largest_mm]``;
    every segment of the robot gets the same radius (a UR10 gets 49 mm, a KR 150 108 mm)."""
    L = np.asarray(segments_length_mm, dtype=float)
    r = float(np.clip(fraction * L.max(initial=0.0), smallest_mm, largest_mm))
    return np.full(L.shape, r)
