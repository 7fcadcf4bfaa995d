"""When is a light barrier blocked by a cylindrical tool? The geometry of
:mod:`robocal.sim.tool.light_barrier`, with an optional dirty beam.

A beam is a line (point, unit direction; treated as infinite). The tool is a capsule (spherical
tip: the axis segment ends r before the tip) or a finite cylinder (flat tip). Lengths mm.

**Dirt on the beam** (:class:`BeamDirt`): dust on the optics covers a share ``f`` of the beam's
cross-section (width ``w``) on one side ``n`` (unit, perpendicular to the beam). The receiver
switches at half the clean power, so a tool coming from the clean side needs to cover less of
the beam and blocks ``f w`` earlier; from the dirty side it first covers the dirt (no change)
and blocks where a clean beam would. Between the two the reach grows smoothly: the tool blocks
when the beam-to-axis distance is below ``r + f w (1 - u . n) / 2``, u the unit vector from the
beam to the nearest axis point (uniform beam profile, edge of the tool straight across the beam).
With ``f = 0`` or no dirt this is the clean criterion ``distance < r``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["BeamDirt", "barrier_blocked"]


@dataclass(frozen=True)
class BeamDirt:
    """Dirt on a beam: ``fraction`` (0..0.5) of the cross-section of width ``width_mm`` [mm]
    covered on the side ``side`` (3,) (unit, perpendicular to the beam, base frame)."""

    fraction: float
    width_mm: float
    side: np.ndarray

    def __post_init__(self):
        if not 0.0 <= self.fraction < 0.5 or not self.width_mm >= 0:
            raise ValueError("BeamDirt: need 0 <= fraction < 0.5 and width_mm >= 0")
        object.__setattr__(self, "side", np.asarray(self.side, float) / np.linalg.norm(self.side))


def _nearest_offsets(beam, B, E):
    """Vectors (N, 3) from the beam line to the nearest point of each axis segment B -> E (the
    component perpendicular to the beam) and their lengths (N,)."""
    d = beam.direction
    w = B - beam.point_mm
    u = E - B
    w_p = w - (w @ d)[:, None] * d
    u_p = u - (u @ d)[:, None] * d
    uu = np.einsum("ij,ij->i", u_p, u_p)
    s = np.where(uu > 1e-18, -np.einsum("ij,ij->i", w_p, u_p) / np.where(uu > 1e-18, uu, 1.0), 0.0)
    vec = w_p + np.clip(s, 0.0, 1.0)[:, None] * u_p
    return vec, np.linalg.norm(vec, axis=1)


def barrier_blocked(beam, base_pts, end_pts, radius_mm: float, tip: str = "spherical", dirt=None) -> np.ndarray:
    """(N,) bool: does the beam line (a :class:`~robocal.sim.tool.light_barrier.LightBarrier`) meet
    the tool whose axis runs from ``base_pts`` to ``end_pts`` (N, 3), base frame?
    ``tip="spherical"``: capsule (distance from the line to the axis segment < r; ``end_pts`` =
    ball centres); ``"flat"``: the finite cylinder. ``dirt``: a :class:`BeamDirt` on this beam
    (module docstring), which widens the tool's reach on the clean side."""
    B = np.atleast_2d(np.asarray(base_pts, float))
    E = np.atleast_2d(np.asarray(end_pts, float))
    d = beam.direction
    u = E - B
    if dirt is not None and dirt.fraction > 0:
        vec, dist = _nearest_offsets(beam, B, E)
        cos = np.einsum("ij,j->i", vec, dirt.side) / np.where(dist > 1e-12, dist, 1.0)
        radius_mm = radius_mm + dirt.fraction * dirt.width_mm * (1.0 - cos) / 2.0
    if tip == "spherical":
        return _nearest_offsets(beam, B, E)[1] < radius_mm
    # flat: line p0 + t d against the cylinder {B + h e + r', |r'| <= r, 0 <= h <= L}
    L = np.linalg.norm(u, axis=1)
    e = u / L[:, None]
    p = beam.point_mm - B                                        # line point relative to B
    de = e @ d
    pe = np.einsum("ij,ij->i", p, e)
    d_perp = d - de[:, None] * e
    p_perp = p - pe[:, None] * e
    a2 = np.einsum("ij,ij->i", d_perp, d_perp)
    b2 = np.einsum("ij,ij->i", p_perp, d_perp)
    c2 = np.einsum("ij,ij->i", p_perp, p_perp) - radius_mm ** 2
    par = a2 < 1e-15
    disc = b2 * b2 - a2 * c2
    sq = np.sqrt(np.maximum(disc, 0.0))
    a_safe = np.where(par, 1.0, a2)
    t1, t2 = (-b2 - sq) / a_safe, (-b2 + sq) / a_safe
    radial_ok = np.where(par, c2 <= 0, disc >= 0)
    t1 = np.where(par, -np.inf, t1)
    t2 = np.where(par, np.inf, t2)
    small = np.abs(de) < 1e-15
    de_safe = np.where(small, 1.0, de)
    h1, h2 = (0.0 - pe) / de_safe, (L - pe) / de_safe
    lo = np.where(small, np.where((pe >= 0) & (pe <= L), -np.inf, np.inf), np.minimum(h1, h2))
    hi = np.where(small, np.where((pe >= 0) & (pe <= L), np.inf, -np.inf), np.maximum(h1, h2))
    return radial_ok & (np.maximum(t1, lo) <= np.minimum(t2, hi))


