"""A tool frame ``T_flange_tool`` as each controller's tool-data record (docs/tcp.md, "Tool data").

Conventions (see docs/conventions.md, section 5):

| controller | record | values | robocal convention |
|---|---|---|---|
| ``kuka`` | ``TOOL_DATA[i]`` | X, Y, Z mm; A, B, C deg | ``kuka_abc`` (Rz(A) Ry(B) Rx(C)) |
| ``fanuc`` | UTOOL (tool frame, direct entry) | X, Y, Z mm; W, P, R deg | ``fanuc_wpr`` (Rz(R) Ry(P) Rx(W)) |
| ``abb`` | ``tooldata.tframe`` | trans x, y, z mm; rot q1..q4 = w, x, y, z | ``quaternion`` (w >= 0) |
| ``ur`` | TCP (``set_tcp``) | x, y, z m; rx, ry, rz rad (rotation vector) | ``rotvec`` |
| ``kawasaki`` | ``TOOL TRANS(...)`` | X, Y, Z mm; O, A, T deg | ``kawasaki_oat`` (Rz(O) Ry(A) Rz(T)) |
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..transforms import check_transforms, pose_from_transform

__all__ = ["CONTROLLERS", "ToolData", "tool_data", "tool_data_all"]

# name -> (convention, length_unit, angle_unit, value names, record title)
CONTROLLERS = {
    "kuka": ("kuka_abc", "mm", "deg", ("X", "Y", "Z", "A", "B", "C"), "KUKA TOOL_DATA"),
    "fanuc": ("fanuc_wpr", "mm", "deg", ("X", "Y", "Z", "W", "P", "R"), "FANUC UTOOL"),
    "abb": ("quaternion", "mm", None, ("x", "y", "z", "q1", "q2", "q3", "q4"), "ABB tooldata tframe"),
    "ur": ("rotvec", "m", "rad", ("x", "y", "z", "rx", "ry", "rz"), "Universal Robots TCP"),
    "kawasaki": ("kawasaki_oat", "mm", "deg", ("X", "Y", "Z", "O", "A", "T"), "Kawasaki TOOL"),
}


@dataclass(frozen=True, eq=False)
class ToolData:
    """One controller's tool-data record of a tool frame."""

    controller: str
    title: str
    convention: str
    length_unit: str
    angle_unit: str | None
    names: tuple
    values: np.ndarray
    text: str          # the record as typed into the controller

    def as_dict(self) -> dict:
        return {n: float(v) for n, v in zip(self.names, self.values)}

    def to_dict(self) -> dict:
        return {"controller": self.controller, "title": self.title, "convention": self.convention,
                "length_unit": self.length_unit, "angle_unit": self.angle_unit, "values": self.as_dict(),
                "text": self.text}


def _text(controller: str, v: np.ndarray, index: int) -> str:
    if controller == "kuka":
        return f"TOOL_DATA[{index}]={{X {v[0]:.3f},Y {v[1]:.3f},Z {v[2]:.3f},A {v[3]:.4f},B {v[4]:.4f},C {v[5]:.4f}}}"
    if controller == "fanuc":
        return (f"UTOOL[{index}]: X {v[0]:.3f}  Y {v[1]:.3f}  Z {v[2]:.3f}  "
                f"W {v[3]:.4f}  P {v[4]:.4f}  R {v[5]:.4f}")
    if controller == "abb":
        return f"tframe := [[{v[0]:.3f},{v[1]:.3f},{v[2]:.3f}],[{v[3]:.7f},{v[4]:.7f},{v[5]:.7f},{v[6]:.7f}]]"
    if controller == "ur":
        return "set_tcp(p[" + ", ".join(f"{x:.6f}" for x in v) + "])"
    if controller == "kawasaki":
        return "TOOL TRANS(" + ",".join(f"{x:.3f}" for x in v[:3]) + "," + ",".join(f"{x:.4f}" for x in v[3:]) + ")"
    raise AssertionError(controller)


def tool_data(T_flange_tool, controller: str, index: int = 1) -> ToolData:
    """``T_flange_tool`` (4, 4) [mm] as ``controller``'s tool data (``CONTROLLERS`` names)."""
    key = str(controller).strip().lower()
    if key not in CONTROLLERS:
        raise ValueError(f"unknown controller {controller!r}; valid: {', '.join(CONTROLLERS)}")
    T = check_transforms(T_flange_tool, "T_flange_tool")
    if T.shape != (4, 4):
        raise ValueError(f"T_flange_tool: expected shape (4, 4), got {T.shape}")
    conv, lu, au, names, title = CONTROLLERS[key]
    v = pose_from_transform(T, conv, lu, au or "deg")
    v = np.where(np.abs(v) < 5e-13, 0.0, v)   # no "-0.000" in the records
    return ToolData(controller=key, title=title, convention=conv, length_unit=lu, angle_unit=au, names=names,
                    values=v, text=_text(key, v, index))


def tool_data_all(T_flange_tool, index: int = 1) -> dict:
    """``{controller: ToolData}`` for every controller in ``CONTROLLERS``."""
    return {name: tool_data(T_flange_tool, name, index) for name in CONTROLLERS}
