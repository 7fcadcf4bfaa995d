"""Barrier events as the controller records them, and what the method extracts from them.

An executed motion is a :class:`MotionRecord`: the programmed motion, its start on the controller
clock and the :class:`BarrierEvent` s seen during it. From a circle's events come the blocked
intervals of each beam, the beam crossings (middles of those intervals, labelled X+/X-/Y+/Y- by
the side of the beam they lie on) and the four arc durations between consecutive crossings; from
the step-4 vertical moves come the flange positions at which each beam switched. Times in s on
the controller clock, positions in mm (base frame).
"""

from __future__ import annotations
from ...errors import InputError

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["BarrierEvent", "MotionRecord", "CrossLaserError"]


class CrossLaserError(InputError):
    """The recorded events cannot be evaluated (missing crossings, inconsistent pattern)."""


@dataclass(frozen=True)
class BarrierEvent:
    """A barrier state change seen by the controller.

    time_s: controller time of the I/O sample that showed the new state; barrier ``"x"`` or
    ``"y"``; state ``"blocked"`` or ``"clear"``; flange_mm (3,): flange position the controller
    reports at that time (base frame, ``None`` if not recorded).
    """

    time_s: float
    barrier: str
    state: str
    flange_mm: np.ndarray | None = None


@dataclass(frozen=True)
class MotionRecord:
    """One executed motion: the motion, its start on the controller clock [s], its events, its
    duration and the settling time after it [s]."""

    motion: object
    t_start_s: float
    events: tuple = ()
    duration_s: float = 0.0
    settle_s: float = 0.0


def blocked_intervals(events, barrier, t_lo, t_hi):
    """Blocked intervals ``[(t_blocked, t_clear), ...]`` [s] of one barrier fully inside [t_lo, t_hi]."""
    out = []
    t_on = None
    for e in sorted(events, key=lambda e: e.time_s):
        if e.barrier != barrier:
            continue
        if e.state == "blocked":
            t_on = e.time_s
        elif e.state == "clear" and t_on is not None:
            if t_on >= t_lo and e.time_s <= t_hi:
                out.append((t_on, e.time_s))
            t_on = None
    return out


def beam_crossings(record: MotionRecord, sensor):
    """The beam crossings of a circle record inside its constant-speed window.

    A crossing is the middle ``t`` [s] of a blocked interval, labelled ``X+``/``X-``/``Y+``/``Y-``
    by the side of the beam (seen from the sensor origin, sensor frame) where the programmed
    circle is at that time. ``sensor``: a :class:`~robocal.tcp.cross_laser.SensorFrame`.

    Returns ``(crossings, widths)``: ``[(t, label), ...]`` sorted by time, and ``{"x": [...],
    "y": [...]}`` the durations [s] of the blocked intervals per beam.
    """
    m = record.motion
    w0, w1 = m.constant_speed_window_s
    t0 = record.t_start_s
    beta = sensor.beta_rad
    Rs = sensor.R_base_sensor
    e1_s = Rs.T @ m.ref_dir
    e2_s = Rs.T @ np.cross(m.normal, m.ref_dir)
    ybeam = np.array([math.cos(beta), math.sin(beta)])
    crossings = []
    widths = {"x": [], "y": []}
    for b in ("x", "y"):
        for ta, tb in blocked_intervals(record.events, b, t0 + w0, t0 + w1):
            tm = 0.5 * (ta + tb)
            phi = float(m.phase(tm - t0))
            u = (math.cos(phi) * e1_s + math.sin(phi) * e2_s)[:2]
            side = u[0] if b == "x" else float(u @ ybeam)
            crossings.append((tm, ("X" if b == "x" else "Y") + ("+" if side > 0 else "-")))
            widths[b].append(tb - ta)
    crossings.sort()
    return crossings, widths


_ARC_OF = {frozenset(("X+", "Y+")): 0, frozenset(("Y+", "X-")): 1, frozenset(("X-", "Y-")): 2,
           frozenset(("Y-", "X+")): 3}


def arc_durations(crossings, step) -> list:
    """Durations [s] of the arcs 1..4 between consecutive crossings: four lists, one entry per
    period seen. ``step`` names the circle in errors. Raises :class:`CrossLaserError` for fewer
    than 5 crossings, an impossible pair of neighbours, or an arc never seen."""
    if len(crossings) < 5:
        raise CrossLaserError(f"circle (step {step}): {len(crossings)} complete beam crossings, need >= 5 "
                              "(is the tool within the circle radius of the sensor origin?)")
    per = [[] for _ in range(4)]
    for (ta, la), (tb, lb) in zip(crossings[:-1], crossings[1:]):
        k = _ARC_OF.get(frozenset((la, lb)))
        if k is None:
            raise CrossLaserError(f"circle (step {step}): crossings {la} then {lb} at {ta:.4f}/{tb:.4f} s: a beam "
                                  "crossing is missing or the tool is off the circle")
        per[k].append(tb - ta)
    if any(len(p) == 0 for p in per):
        raise CrossLaserError(f"circle (step {step}): not all four arcs were seen")
    return per


def switch_positions(down: MotionRecord, up: MotionRecord) -> dict:
    """Flange positions (3,) [mm, base] where each beam first became blocked on the ``down``
    move and clear on the ``up`` move, keyed ``x_blocked``, ``y_blocked``, ``x_clear``,
    ``y_clear``. Raises :class:`CrossLaserError` if a switch is missing or has no position."""
    pos = {}
    for rec, state in ((down, "blocked"), (up, "clear")):
        for b in ("x", "y"):
            ev = [e for e in rec.events if e.barrier == b and e.state == state]
            if not ev:
                raise CrossLaserError(f"step 4: beam {b} never became {state} during the "
                                      f"{'down' if state == 'blocked' else 'up'} move")
            if ev[0].flange_mm is None:
                raise CrossLaserError("step 4: events carry no flange position")
            pos[f"{b}_{state}"] = np.asarray(ev[0].flange_mm, float)
    return pos
