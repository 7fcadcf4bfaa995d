"""Parallel consecutive joint axes of DH-family links, and Hayati's beta that models their tilt.

With two consecutive joint axes parallel (``alpha = 0`` or ``180 deg`` between them), the
common normal of the DH/MDH conventions is not unique: a small tilt of the second axis about the
common normal's orthogonal direction cannot be expressed by theta, d, a, alpha, and the offsets
along the parallel axes trade off against each other. Hayati's ``beta`` (a rotation ``Ry(beta)``,
links.py) is the parameter that carries that tilt (METHODS.md section 2, eq. 2-18).

* ``dh`` / ``dh_beta`` link ``k``: ``alpha_k`` is the angle between the axis of joint ``k`` (z of
  the frame before the link) and the axis of the next joint (z after it): the pair is (link ``k``,
  its child), ``beta`` on link ``k``.
* ``mdh`` link ``k``: ``alpha`` is the angle between the axis of its parent joint and its own:
  the pair is (parent, link ``k``), ``beta`` on link ``k``.
"""

from __future__ import annotations

import math

__all__ = ["PARALLEL_AXES_DEG", "ParallelPair", "parallel_axis_pairs"]

#: Axes within this angle [deg] of parallel (or antiparallel) count as "nearly parallel".
PARALLEL_AXES_DEG = 5.0


class ParallelPair(tuple):
    """``(first, second, beta_link)``: link indices of the two joints with (nearly) parallel axes
    and of the link that carries their ``beta``."""

    __slots__ = ()

    def __new__(cls, first: int, second: int, beta_link: int):
        return super().__new__(cls, (int(first), int(second), int(beta_link)))

    @property
    def first(self) -> int:
        return self[0]

    @property
    def second(self) -> int:
        return self[1]

    @property
    def beta_link(self) -> int:
        return self[2]


def _nearly_parallel(alpha_rad: float, tol_deg: float) -> bool:
    return abs(math.sin(alpha_rad)) <= math.sin(math.radians(tol_deg))


def parallel_axis_pairs(links, tol_deg: float = PARALLEL_AXES_DEG) -> list:
    """The (nearly) parallel consecutive joint-axis pairs of DH-family ``links``.

    links: sequence of objects with ``convention``, ``params`` (``alpha`` [rad]), ``parent``
    (index, -1 = base) and ``moves`` (:class:`~robocal.kinematics.links.Link`). tol_deg: largest
    angle [deg] between the axes. Returns a list of :class:`ParallelPair` in link order; links of
    the ``urdf`` and ``frame`` conventions never take part.
    """
    dh = ("dh", "dh_beta")
    out = []
    for k, L in enumerate(links):
        if L.convention not in dh + ("mdh",) or not L.moves or "alpha" not in L.params:
            continue
        if not _nearly_parallel(float(L.params["alpha"]), tol_deg):
            continue
        if L.convention in dh:
            children = [c for c, C in enumerate(links) if C.parent == k and C.moves and C.convention in dh]
            if children:
                out.append(ParallelPair(k, children[0], k))
        else:
            p = L.parent
            if p >= 0 and links[p].moves and links[p].convention == "mdh":
                out.append(ParallelPair(p, k, k))
    return out
