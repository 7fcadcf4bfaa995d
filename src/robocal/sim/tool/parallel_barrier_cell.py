"""The parallel-light-barrier method (thesis 4.1.2, (4-6), (4-7)) run through the light-barrier
simulator: the robot moves, the beams report, the recorded values come from the events.

The rig (:class:`ParallelBarrierRig`): two beams along base Y at base x = ``x_mm``, heights
``h_up_mm`` > ``h_down_mm``. The procedure, in a :class:`~robocal.sim.tool.light_barrier.LightBarrierCell`
built on the rig's beams (any realism of the cell applies):

0. :func:`measure_beam_heights`: the flange face (a flat disc on the flange, Z_e down) moves down
   through both beams; ``h_up`` / ``h_down`` are the flange-origin z at the first block of each;
1. steps 1-2 (flange ``R_FLANGE_STEP12``) and step 3 (``R_FLANGE_STEP3``): the tool, its nominal
   tip ``tip_below_mm`` under the lower beam so that both beams cross it, moves along +X_b:
   flange-origin x at block / clear of each beam (``x_up1..4``, ``x_down1..4``);
2. the tool turned vertical (:func:`~robocal.tcp.parallel_barriers.flange_rotation_for_vertical_tool`),
   the same crossing (``x_up5, 6``, ``x_down5, 6``, the check of steps 5-6);
3. the flange centred at ``(x_down5 + x_down6) / 2`` moves down until the tip blocks the upper
   beam: ``z7`` (4-7).

:func:`record_parallel_barriers` returns the keyword arguments of
:func:`robocal.tcp.parallel_barriers.parallel_barriers_tool` and the cycle time. Positions are
the controller's (commanded) flange positions at the events. Lengths mm, speeds mm/s.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...transforms import transforms_from
from .light_barrier import CylinderTool, LightBarrier, LightBarrierCell

__all__ = ["ParallelBarrierRig", "measure_beam_heights", "record_parallel_barriers"]


@dataclass(frozen=True)
class ParallelBarrierRig:
    """Two beams along base Y at base x ``x_mm``, heights ``h_up_mm`` > ``h_down_mm``; the tool
    crosses them at base y ``y_mm``."""

    x_mm: float = -850.0
    y_mm: float = -170.0
    h_up_mm: float = 240.0
    h_down_mm: float = 200.0

    def beams(self) -> dict:
        """``{"up": LightBarrier, "down": LightBarrier}`` (base frame)."""
        return {"up": LightBarrier("up", [self.x_mm, 0.0, self.h_up_mm], [0.0, 1.0, 0.0]),
                "down": LightBarrier("down", [self.x_mm, 0.0, self.h_down_mm], [0.0, 1.0, 0.0])}


def _line(p0, p1, R, speed, role):
    from ...tcp.cross_laser import LinearMove

    return LinearMove(np.asarray(p0, float), np.asarray(p1, float), R, R, speed, 1.0, 2000.0, 1, role)


def _edges(rec, beam: str, axis: int):
    """Flange coordinate ``axis`` at the first block and the last clear of ``beam``."""
    ev = [e for e in rec.events if e.barrier == beam]
    on = [e.flange_mm[axis] for e in ev if e.state == "blocked"]
    off = [e.flange_mm[axis] for e in ev if e.state == "clear"]
    if not on or not off:
        raise RuntimeError(f"{rec.motion.role}: the tool did not cross the {beam} beam")
    return float(on[0]), float(off[-1])


def measure_beam_heights(rig: ParallelBarrierRig, rng, *, flange_radius_mm: float = 31.5, speed_mm_s: float = 2.0,
                         **cell_kw) -> tuple:
    """``(h_up, h_down)`` [mm]: the flange face moving down through the beams (step 0).
    ``cell_kw``: keywords of :class:`LightBarrierCell` (clock, noise, realism)."""
    from ...tcp.parallel_barriers import R_FLANGE_STEP12

    disc = CylinderTool(np.eye(4), flange_radius_mm, 2.2 * flange_radius_mm, "flat")      # face + wrist body
    cell = LightBarrierCell(rig.beams(), disc, rng, **cell_kw)
    top = [rig.x_mm, rig.y_mm, rig.h_up_mm + 5.0]
    rec = cell.run(_line(top, [rig.x_mm, rig.y_mm, rig.h_down_mm - 3.0], R_FLANGE_STEP12, speed_mm_s, "heights"))
    h = {}
    for b in ("up", "down"):
        first = [e for e in rec.events if e.barrier == b and e.state == "blocked"]
        if not first:
            raise RuntimeError(f"heights: the flange face did not block the {b} beam")
        h[b] = float(first[0].flange_mm[2])
    return h["up"], h["down"]


def _cross(cell, rig, R, tcp_nominal, tip_z, speed, travel, role):
    """Move along +X_b with flange orientation ``R`` so the nominal tip passes at ``tip_z``:
    ``((x_up_on, x_up_off), (x_down_on, x_down_off))``."""
    p = np.array([rig.x_mm, rig.y_mm, tip_z]) - R @ tcp_nominal
    rec = cell.run(_line(p - [travel, 0.0, 0.0], p + [travel, 0.0, 0.0], R, speed, role))
    return _edges(rec, "up", 0), _edges(rec, "down", 0)


def record_parallel_barriers(cell: LightBarrierCell, rig: ParallelBarrierRig, T_flange_tool_nominal, h_up_mm: float,
                             h_down_mm: float, *, speed_mm_s: float = 5.0, travel_mm: float = 20.0,
                             tip_below_mm: float = 20.0) -> tuple:
    """Steps 1-3 and the length move (module docstring) in ``cell`` (its tool is the real one,
    its beams the rig's); ``T_flange_tool_nominal`` (4, 4) is the estimate used to aim.
    Returns ``(kwargs of parallel_barriers_tool, cycle time [s])``."""
    from ...tcp.parallel_barriers import (
        R_FLANGE_STEP3,
        R_FLANGE_STEP12,
        flange_rotation_for_vertical_tool,
        tool_axis_from_barriers,
    )

    t0 = cell.time_s
    tcp_nom = np.asarray(T_flange_tool_nominal, float)[:3, 3]
    tip_z = h_down_mm - tip_below_mm
    (u1, u2), (d1, d2) = _cross(cell, rig, R_FLANGE_STEP12, tcp_nom, tip_z, speed_mm_s, travel_mm, "steps12")
    (u3, u4), (d3, d4) = _cross(cell, rig, R_FLANGE_STEP3, tcp_nom, tip_z, speed_mm_s, travel_mm, "step3")
    x_up, x_down = [u1, u2, u3, u4], [d1, d2, d3, d4]
    a = tool_axis_from_barriers(x_up, x_down, h_up_mm - h_down_mm)
    Rv = flange_rotation_for_vertical_tool(a)
    (u5, u6), (d5, d6) = _cross(cell, rig, Rv, tcp_nom, tip_z, speed_mm_s, travel_mm, "vertical")
    xc = 0.5 * (d5 + d6)
    length = float(np.linalg.norm(tcp_nom))
    start = np.array([xc, rig.y_mm, h_up_mm + length + 8.0])
    rec = cell.run(_line(start, start - [0.0, 0.0, 16.0], Rv, 0.4 * speed_mm_s, "length"))
    first = [e for e in rec.events if e.barrier == "up" and e.state == "blocked"]
    if not first:
        raise RuntimeError("length move: the tip did not block the upper beam")
    kw = dict(x_up=x_up, x_down=x_down, h_up_mm=h_up_mm, h_down_mm=h_down_mm, z7_mm=float(first[0].flange_mm[2]),
              x_up_vertical=[u5, u6], x_down_vertical=[d5, d6])
    return kw, cell.time_s - t0


def straight_tool(length_mm: float = 180.0, radius_mm: float = 3.0) -> CylinderTool:
    """A straight tool on the flange Z axis (the nominal tool of the studies)."""
    return CylinderTool(transforms_from(np.eye(3), [0.0, 0.0, length_mm]), radius_mm, length_mm, "spherical")
