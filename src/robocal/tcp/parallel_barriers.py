"""Parallel light barriers: tool axis direction (4-6) and length (4-7), thesis 4.1.2.

Set-up (docs/tcp.md, "Parallel light barriers"): two light barriers parallel to the base Y axis,
one straight above the other (same base x), at heights ``h_up`` > ``h_down`` (base Z),
``delta_h = h_up - h_down`` > 0. The heights are found with the flange itself: the flange-origin z
when the flange face, moving down, first blocks each beam.

Recorded values (base-frame x of the flange origin, mm):

- steps 1-2: flange Z_e pointing down, Y_e = Y_b (so X_e = -X_b; ``R_base_flange = Ry(180 deg)``),
  the tool moves along +X_b across both beams: ``x_up1`` / ``x_down1`` where the upper / lower
  beam becomes blocked, ``x_up2`` / ``x_down2`` where it becomes free again;
- step 3: the flange turned about Z_e so that X_e = Y_b (then Y_e = X_b, Z_e = -Z_b), same move:
  ``x_up3``, ``x_down3`` (blocked), ``x_up4``, ``x_down4`` (free).

The midpoint of a block/unblock pair is where the tool axis crosses the beam (the tool's radius
and the beam's width cancel), so ``((x_up1 + x_up2) - (x_down1 + x_down2)) / 2`` is how far
(along +X_b) the tool axis is at the lower beam from where it is at the upper beam, per
``delta_h`` of descent. In the flange frame of steps 1-2 that base +X is -X_e (the thesis's sign
note after 4-6); in step 3 base +X is +Y_e. Hence (4-6), the tool axis pointing from the flange
towards the tip, in the flange frame:

``a = ( -((x_up1 + x_up2) - (x_down1 + x_down2)) / 2, ((x_up3 + x_up4) - (x_down3 + x_down4)) / 2, delta_h )``.

Length (4-7): with the tool turned so that its axis is vertical (:func:`flange_rotation_for_vertical_tool`)
and centred on the beams, the flange moves down until the tip first blocks the upper beam, at
flange-origin height ``z7``: ``D = z7 - h_up`` is the distance from the flange origin to the tip
along the (vertical) tool axis. If the tool axis passes through the flange origin (a straight
tool, bent about its mount), the TCP in the flange frame is ``D * a / |a|``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..transforms import rot_axis

__all__ = [
    "R_FLANGE_STEP12",
    "R_FLANGE_STEP3",
    "ParallelBarrierResult",
    "tool_axis_from_barriers",
    "tool_length_from_barriers",
    "tool_rotation_5d",
    "flange_rotation_for_vertical_tool",
    "parallel_barriers_tool",
]

#: flange orientation in steps 1-2: Z_e down, Y_e = Y_b, X_e = -X_b
R_FLANGE_STEP12 = np.diag([-1.0, 1.0, -1.0])
#: flange orientation in step 3: X_e = Y_b, Y_e = X_b, Z_e = -Z_b
R_FLANGE_STEP3 = np.array([[0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]])


def _pair4(x, name):
    a = np.asarray(x, dtype=float)
    if a.shape != (4,) or not np.all(np.isfinite(a)):
        raise ValueError(f"{name}: expected 4 finite values ({name}1..{name}4), got {x!r}")
    return a


def tool_axis_from_barriers(x_up, x_down, delta_h_mm) -> np.ndarray:
    """The thesis's vector ``a`` (4-6) in the flange frame (not normalized; z = ``delta_h_mm``).

    ``x_up`` = (x_up1, x_up2, x_up3, x_up4), ``x_down`` = (x_down1, ..., x_down4) [mm] as in the
    module docstring.
    """
    u = _pair4(x_up, "x_up")
    d = _pair4(x_down, "x_down")
    dh = float(delta_h_mm)
    if not dh > 0:
        raise ValueError(f"delta_h_mm must be > 0 (h_up - h_down), got {delta_h_mm!r}")
    return np.array([-((u[0] + u[1]) - (d[0] + d[1])) / 2.0, ((u[2] + u[3]) - (d[2] + d[3])) / 2.0, dh])


def tool_length_from_barriers(z7_mm, h_up_mm) -> float:
    """``D = z7 - h_up`` (4-7): flange origin to tool tip along the vertical tool axis [mm]."""
    D = float(z7_mm) - float(h_up_mm)
    if not D > 0:
        raise ValueError(f"z7 ({z7_mm}) must be above h_up ({h_up_mm}): D = {D:.4g} mm")
    return D


def tool_rotation_5d(axis) -> np.ndarray:
    """``Rz(psi) Rx(theta) Rz(-psi)`` (4-10) whose Z column is the unit ``axis`` (flange frame).

    The 5-D tool frame of the thesis: no rotation about the tool's own axis. ``theta`` = angle from
    Z_e; ``psi = atan2(a_x, -a_y)`` (4-13).
    """
    a = np.asarray(axis, dtype=float)
    a = a / np.linalg.norm(a)
    theta = math.acos(max(-1.0, min(1.0, float(a[2]))))
    psi = math.atan2(float(a[0]), float(-a[1])) if math.hypot(a[0], a[1]) > 1e-15 else 0.0
    c, s = math.cos(psi), math.sin(psi)
    Rz = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    ct, st = math.cos(theta), math.sin(theta)
    Rx = np.array([[1.0, 0.0, 0.0], [0.0, ct, -st], [0.0, st, ct]])
    return Rz @ Rx @ Rz.T


def flange_rotation_for_vertical_tool(axis, R_base_flange=R_FLANGE_STEP12, down=(0.0, 0.0, -1.0)) -> np.ndarray:
    """Flange orientation that points the tool ``axis`` (flange frame) along ``down`` (base).

    The smallest rotation of ``R_base_flange`` (default: the steps 1-2 orientation) doing so, as
    in the thesis's "adjust the robot so that the tool is parallel to Z_b" before (4-7).
    """
    a = np.asarray(axis, dtype=float)
    a = a / np.linalg.norm(a)
    R0 = np.asarray(R_base_flange, dtype=float)
    g = np.asarray(down, dtype=float)
    g = g / np.linalg.norm(g)
    cur = R0 @ a
    k = np.cross(cur, g)
    sk = np.linalg.norm(k)
    ang = math.atan2(sk, float(cur @ g))
    if sk < 1e-15:
        if ang < 1.0:
            return R0.copy()
        perp = np.cross(cur, [1.0, 0.0, 0.0])
        if np.linalg.norm(perp) < 0.1:
            perp = np.cross(cur, [0.0, 1.0, 0.0])
        return rot_axis(perp / np.linalg.norm(perp), math.pi) @ R0
    return rot_axis(k / sk, ang) @ R0


@dataclass(frozen=True, eq=False)
class ParallelBarrierResult:
    """Result of :func:`parallel_barriers_tool` (flange frame, mm, deg)."""

    axis: np.ndarray                 # (3,) unit tool axis, flange -> tip
    axis_raw_mm: np.ndarray          # (3,) the thesis's a (4-6)
    tilt_deg: float                  # angle between the tool axis and Z_e
    psi_deg: float                   # (4-13) rotation of the tilt direction about Z_e
    length_mm: float | None          # D (4-7)
    tcp_mm: np.ndarray | None        # D * axis (tool axis through the flange origin)
    vertical_residual_deg: float | None  # tool tilt left after alignment (steps 5-6), if recorded

    @property
    def T_flange_tool(self) -> np.ndarray:
        """5-D tool frame (4-10): Z along the axis, origin at the TCP (flange origin if no length)."""
        T = np.eye(4)
        T[:3, :3] = tool_rotation_5d(self.axis)
        if self.tcp_mm is not None:
            T[:3, 3] = self.tcp_mm
        return T

    def to_dict(self) -> dict:
        return {
            "axis": [float(x) for x in self.axis],
            "axis_raw_mm": [float(x) for x in self.axis_raw_mm],
            "tilt_deg": float(self.tilt_deg),
            "psi_deg": float(self.psi_deg),
            "length_mm": None if self.length_mm is None else float(self.length_mm),
            "tcp_mm": None if self.tcp_mm is None else [float(x) for x in self.tcp_mm],
            "vertical_residual_deg": None if self.vertical_residual_deg is None else float(self.vertical_residual_deg),
            "T_flange_tool": [[float(x) for x in row] for row in self.T_flange_tool],
        }


def parallel_barriers_tool(x_up, x_down, delta_h_mm=None, *, h_up_mm=None, h_down_mm=None, z7_mm=None,
                           x_up_vertical=None, x_down_vertical=None) -> ParallelBarrierResult:
    """Tool axis (4-6) and, with ``z7_mm`` and ``h_up_mm``, length (4-7) from the recorded values.

    ``delta_h_mm`` defaults to ``h_up_mm - h_down_mm``. ``x_up_vertical`` = (x_up5, x_up6) and
    ``x_down_vertical`` = (x_down5, x_down6), optional: the block/unblock x of both beams after the
    tool was turned vertical (flange moving along +X_b); their midpoints should coincide, and the
    tilt left is reported as ``vertical_residual_deg`` (in the X_b Z_b plane).
    """
    if delta_h_mm is None:
        if h_up_mm is None or h_down_mm is None:
            raise ValueError("give delta_h_mm, or h_up_mm and h_down_mm")
        delta_h_mm = float(h_up_mm) - float(h_down_mm)
    elif h_up_mm is not None and h_down_mm is not None and abs(float(h_up_mm) - float(h_down_mm) - float(delta_h_mm)) > 1e-6:
        raise ValueError(f"delta_h_mm = {delta_h_mm} contradicts h_up_mm - h_down_mm = {float(h_up_mm) - float(h_down_mm)}")
    a = tool_axis_from_barriers(x_up, x_down, delta_h_mm)
    axis = a / np.linalg.norm(a)
    tilt = math.degrees(math.acos(float(axis[2])))
    psi = math.degrees(math.atan2(float(axis[0]), float(-axis[1]))) if tilt > 1e-12 else 0.0
    D = tcp = None
    if z7_mm is not None:
        if h_up_mm is None:
            raise ValueError("z7_mm needs h_up_mm for the length D = z7 - h_up (4-7)")
        D = tool_length_from_barriers(z7_mm, h_up_mm)
        tcp = D * axis
    vres = None
    if (x_up_vertical is None) != (x_down_vertical is None):
        raise ValueError("give both x_up_vertical and x_down_vertical (x_up5, x_up6 / x_down5, x_down6)")
    if x_up_vertical is not None:
        u = np.asarray(x_up_vertical, dtype=float)
        d = np.asarray(x_down_vertical, dtype=float)
        if u.shape != (2,) or d.shape != (2,):
            raise ValueError("x_up_vertical and x_down_vertical: expected 2 values each")
        off = ((u[0] + u[1]) - (d[0] + d[1])) / 2.0
        vres = math.degrees(math.atan2(abs(off), float(delta_h_mm)))
    return ParallelBarrierResult(axis=axis, axis_raw_mm=a, tilt_deg=tilt, psi_deg=psi, length_mm=D, tcp_mm=tcp,
                                 vertical_residual_deg=vres)
