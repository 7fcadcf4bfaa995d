"""Write a :class:`~robocal.kinematics.RobotModel` as a robot file (``robocal-robot/1``).

The file is the same format :func:`robocal.robots.load_robot` reads (docs/robot-files.md), so a
calibrated model can be shipped, versioned and loaded like any other robot. Numbers are written in
the model's declared units (``model.extra["length_unit"]`` / ``["angle_unit"]``, as recorded by the
loader; mm and deg otherwise) with enough digits that reading the file back gives the identical
float in mm / rad wherever one exists (link parameters, joint limits); frames that only exist as
matrices (base, tool, end effectors) go through roll-pitch-yaw and come back to rounding (~1e-16).
"""

from __future__ import annotations

import json
import math
import re
from pathlib import Path

import numpy as np

from ..io.atomic import atomic_write_text
from ..kinematics.links import ANGLE_PARAMS
from ..kinematics.model import RobotModel
from ..transforms import euler_from_matrix
from .loader import FORMAT

__all__ = ["save_robot", "robot_to_toml"]

_LENGTH = {"mm": 1.0, "m": 1000.0}
_ANGLE = {"deg": math.pi / 180.0, "rad": 1.0}
_BARE_KEY = re.compile(r"^[A-Za-z0-9_-]+$")


def _key(name: str) -> str:
    return name if _BARE_KEY.match(name) else json.dumps(name, ensure_ascii=False)


def _str(s: str) -> str:
    # JSON string escapes (\" \\ \n \t \uXXXX) are valid TOML basic-string escapes
    return json.dumps(str(s), ensure_ascii=False)


def _in_unit(x: float, scale: float) -> float:
    """The file number ``y`` with ``y * scale == x`` exactly when such a float exists nearby
    (the loader multiplies by ``scale``), else the closest quotient."""
    x = float(x)
    if scale == 1.0 or not math.isfinite(x):
        return x
    y = x / scale
    for digits in range(1, 18):  # the shortest decimal that reads back exactly (90.0, not 89.99999999999999)
        c = float(f"{y:.{digits}g}")
        if c * scale == x:
            return c
    up = down = y
    for _ in range(8):
        up, down = math.nextafter(up, math.inf), math.nextafter(down, -math.inf)
        if up * scale == x:
            return up
        if down * scale == x:
            return down
    return y


def _num(x: float) -> str:
    x = float(x)
    if math.isnan(x):
        raise ValueError("robot file: NaN cannot be written")
    if math.isinf(x):
        return "inf" if x > 0 else "-inf"
    if x == 0.0:
        return "0.0"  # no "-0.0" in the file
    return repr(x)


def _list(values) -> str:
    return "[" + ", ".join(_num(v) for v in values) + "]"


def _frame_lines(T, ls: float, as_: float) -> list[str]:
    T = np.asarray(T, dtype=float)
    rpy = euler_from_matrix(T[:3, :3], "rpy")  # (roll, pitch, yaw), R = Rz(yaw) Ry(pitch) Rx(roll)
    return [f"xyz = {_list(_in_unit(v, ls) for v in T[:3, 3])}",
            f"rpy = {_list(_in_unit(v, as_) for v in rpy)}"]


def robot_to_toml(model: RobotModel, *, length_unit: str | None = None, angle_unit: str | None = None,
                  comment: str | None = None) -> str:
    """The text of a ``robocal-robot/1`` file describing ``model``.

    length_unit / angle_unit: units of the numbers in the file (default: the units the model was
        read with, ``model.extra``, else mm and deg).
    comment: optional free text written as ``#`` lines at the top (provenance of a calibration).

    Raises ``ValueError`` for what the format cannot express (an end effector on the robot base).
    Per-joint ``source`` strings are not part of :class:`RobotModel` and are not written.
    """
    lu = length_unit or model.extra.get("length_unit", "mm")
    au = angle_unit or model.extra.get("angle_unit", "deg")
    if lu not in _LENGTH:
        raise ValueError(f"length_unit {lu!r}: expected 'mm' or 'm'")
    if au not in _ANGLE:
        raise ValueError(f"angle_unit {au!r}: expected 'deg' or 'rad'")
    ls, as_ = _LENGTH[lu], _ANGLE[au]
    out = [f"# {line}".rstrip() for line in str(comment).splitlines()] if comment else []
    out += _header_lines(model, lu, au)
    entry_limits, ctrl_limits = _split_limits(model)
    for k in range(len(model.links)):
        out += _joint_lines(model, k, entry_limits, ls, as_)
    out += _controller_limit_lines(model, ctrl_limits, ls, as_)
    if not np.array_equal(model.T_world_base, np.eye(4)):
        out += ["", "[base]"] + _frame_lines(model.T_world_base, ls, as_)
    out += _end_effector_lines(model, ls, as_)
    if model.extra.get("elastic") is not None:
        from .elastic_section import elastic_lines

        out += elastic_lines(model.extra["elastic"], ls)
    return "\n".join(out) + "\n"


def _header_lines(model: RobotModel, lu: str, au: str) -> list:
    return [
        f"format = {_str(FORMAT)}",
        f"name = {_str(model.name)}",
        f"title = {_str(model.title)}",
        f"model = {_str(model.kind)}",
        f"length_unit = {_str(lu)}",
        f"angle_unit = {_str(au)}",
        f"source = {_str(model.source)}",
        "controller_joints = [" + ", ".join(_str(c) for c in model.controller_joints) + "]",
    ]


def _split_limits(model: RobotModel):
    """Finite joint limits: on the joint entry of the same name when one moves (first dict), else in
    ``[controller_limits]`` (second dict); controller joint name -> (lo, hi) [rad | mm]."""
    names = [L.name for L in model.links]
    entry_limits, ctrl_limits = {}, {}
    for c, cname in enumerate(model.controller_joints):
        lo, hi = (float(v) for v in model.limits[c])
        if not (math.isfinite(lo) or math.isfinite(hi)):
            continue
        if cname in names and model.links[names.index(cname)].moves:
            entry_limits[cname] = (lo, hi)
        else:
            ctrl_limits[cname] = (lo, hi)
    return entry_limits, ctrl_limits


def _joint_lines(model: RobotModel, k: int, entry_limits: dict, ls: float, as_: float) -> list:
    """The ``[[joints]]`` table of link ``k``."""
    L = model.links[k]
    names = [link.name for link in model.links]
    out = ["", "[[joints]]", f"name = {_str(L.name)}", f"type = {_str(L.joint_type)}"]
    if L.parent != k - 1:
        out.append(f"parent = {_str('base' if L.parent < 0 else names[L.parent])}")
    p = L.params
    if L.convention in ("urdf", "frame"):
        out.append(f"xyz = {_list(_in_unit(p[c], ls) for c in ('x', 'y', 'z'))}")
        out.append(f"rpy = {_list(_in_unit(p[c], as_) for c in ('roll', 'pitch', 'yaw'))}")
        if L.convention == "urdf" and L.moves:
            out.append(f"axis = {_list(L.axis)}")
            off = "theta" if L.joint_type == "revolute" else "d"
            out.append(f"{off} = {_num(_in_unit(p[off], as_ if off == 'theta' else ls))}")
    else:
        if L.convention != model.kind:
            raise ValueError(f"link {L.name!r}: convention {L.convention!r} differs from the model kind "
                             f"{model.kind!r}; the robot file format cannot mix them")
        for pname, v in p.items():
            out.append(f"{pname} = {_num(_in_unit(v, as_ if pname in ANGLE_PARAMS else ls))}")
    if L.fixed:
        out.append("fixed = [" + ", ".join(_str(f) for f in p if f in L.fixed) + "]")
    if L.moves:
        out += _coupling_lines(model, k)
        if L.name in entry_limits:
            scale = as_ if L.joint_type == "revolute" else ls
            out.append(f"limits = {_list(_in_unit(v, scale) for v in entry_limits[L.name])}")
    return out


def _coupling_lines(model: RobotModel, k: int) -> list:
    """``sign = -1`` or ``coupling = {...}`` of moving link ``k``; nothing for the default coupling."""
    L = model.links[k]
    ctrl = list(model.controller_joints)
    moving_index = {int(j): m for m, j in enumerate(model.moving)}
    row = model.coupling[moving_index[k]]
    nz = np.flatnonzero(row)
    own = ctrl.index(L.name) if L.name in ctrl else None
    if own is not None and list(nz) == [own] and row[own] == 1.0:
        return []
    if own is not None and list(nz) == [own] and row[own] == -1.0:
        return ["sign = -1"]
    return ["coupling = { " + ", ".join(f"{_key(ctrl[i])} = {_num(row[i])}" for i in nz) + " }"
            if len(nz) else "coupling = {}"]


def _controller_limit_lines(model: RobotModel, ctrl_limits: dict, ls: float, as_: float) -> list:
    if not ctrl_limits:
        return []
    out = ["", "[controller_limits]"]
    ctrl = list(model.controller_joints)
    for cname, lim in ctrl_limits.items():
        col = model.coupling[:, ctrl.index(cname)]
        m = int(np.flatnonzero(col)[0]) if np.any(col) else None
        pris = m is not None and model.links[int(model.moving[m])].joint_type == "prismatic"
        scale = ls if pris else as_
        out.append(f"{_key(cname)} = {_list(_in_unit(v, scale) for v in lim)}")
    return out


def _end_effector_lines(model: RobotModel, ls: float, as_: float) -> list:
    """A ``[tool]`` table or ``[[end_effectors]]`` tables; nothing for a bare flange."""
    names = [L.name for L in model.links]
    ees = model.end_effectors
    out = []
    if len(ees) == 1 and ees[0].link == len(model.links) - 1 and ees[0].name in ("flange", "tool"):
        e = ees[0]
        identity = np.array_equal(np.asarray(e.T_link_ee, dtype=float), np.eye(4))
        if not (e.name == "flange" and identity):
            if e.name == "flange":
                out += ["", "[[end_effectors]]", f"name = {_str(e.name)}", f"link = {_str(names[e.link])}"]
            else:
                out += ["", "[tool]"]
            out += _frame_lines(e.T_link_ee, ls, as_)
        return out
    for e in ees:
        if e.link < 0:
            raise ValueError(f"end effector {e.name!r} sits on the robot base; a robot file needs a joint entry")
        out += ["", "[[end_effectors]]", f"name = {_str(e.name)}", f"link = {_str(names[e.link])}"]
        out += _frame_lines(e.T_link_ee, ls, as_)
    return out


def save_robot(model: RobotModel, path, overwrite: bool = False, *, length_unit: str | None = None,
               angle_unit: str | None = None, comment: str | None = None) -> Path:
    """Write ``model`` to ``path`` as a ``robocal-robot/1`` TOML file (atomic write).

    An existing file raises ``FileExistsError`` unless ``overwrite``; the text goes to a
    temporary file first, so a crash never leaves a half-written robot file. See
    :func:`robot_to_toml` for the units and ``comment``.
    """
    text = robot_to_toml(model, length_unit=length_unit, angle_unit=angle_unit, comment=comment)
    return atomic_write_text(path, text, overwrite=overwrite)
