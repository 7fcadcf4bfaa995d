"""Tool centre point calibration in memory: the four-point (touch-up) method on flange poses."""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["ToolOptions", "calibrate_tool"]


@dataclass(frozen=True)
class ToolOptions:
    """Settings of :func:`calibrate_tool`, all with defaults.

    Parameters
    ----------
    min_spread_deg : float, default 20.0
        Smallest orientation spread of the poses [deg]; below it the poses are called degenerate.
    """

    min_spread_deg: float = 20.0


def calibrate_tool(T_base_flange, *, options: ToolOptions | None = None):
    """The tool centre point from flange poses touching one reference point (four-point method).

    Parameters
    ----------
    T_base_flange : array_like, shape (N, 4, 4)
        Flange poses in the robot base frame [mm], N >= 4, the tool tip on one fixed point.
    options : ToolOptions, optional
        Degeneracy threshold.

    Returns
    -------
    TouchUpResult
        ``tcp_mm`` (3,) in the flange frame [mm], ``reference_point_mm`` (3,) in the base frame,
        ``residuals_mm`` (N,), ``rms_mm``, ``tcp_std_mm`` (3,) and ``T_flange_tool`` (4, 4).

    Raises
    ------
    robocal.NotIdentifiableError
        The orientations spread less than ``min_spread_deg``.
    robocal.InputError
        The poses are not (N, 4, 4) rigid transforms.
    """
    from ..tcp import four_point_tcp

    o = options if options is not None else ToolOptions()
    return four_point_tcp(T_base_flange, min_spread_deg=o.min_spread_deg)
