"""FANUC TP programs in text form (``.ls``): the positions of the ``/POS`` section.

::

    /POS
    P[1:"approach"]{
       GP1:
        UF : 1, UT : 2,     CONFIG : 'N U T, 0, 0, 0',
        X =  1200.500  mm,  Y =  -310.250  mm,  Z =  1450.000  mm,
        W =   180.000 deg,  P =      .000 deg,  R =   -90.000 deg
    };
    P[2]{
       GP1:
        UF : 1, UT : 2,
        J1=     0.000 deg,  J2=   -30.000 deg,  J3=    30.000 deg,
        J4=     0.000 deg,  J5=   -90.000 deg,  J6=     0.000 deg
    };

Motion group 1 is read: X, Y, Z [mm] and W, P, R [deg] (``fanuc_wpr``: Rz(R) Ry(P) Rx(W)) in user
frame ``UF`` with tool ``UT``, or joints J1 .. Jn [deg, or mm for linear axes]. ``CONFIG`` and
extended axes E1 .. (``E1= 100.000 mm``) are kept verbatim in ``config``; other motion groups
are left untouched. Positions in other forms (e.g. remote-TCP ``RX =``) are listed as skipped.
"""

from __future__ import annotations

import re

import numpy as np

from ...transforms import transform_from_pose
from ..header import FileFormatError
from .source import NUMBER, LineIndex
from .target import ProgramTarget, Skipped

__all__ = ["parse_fanuc"]

_SECTION = re.compile(r"^/POS[ \t]*\r?$(.*?)(?=^/END\b|\Z)", re.M | re.S)
_HEADER = re.compile(r"^[ \t]*P\[(\d+)(?:[ \t]*:[ \t]*(\"[^\"]*\"|[^\]]*))?\][ \t]*\{", re.M)
_CLOSE = re.compile(r"^[ \t]*\};", re.M)
_GROUP = re.compile(r"\bGP(\d+)[ \t]*:")
_ASSIGN = re.compile(r"\b([A-Z]+\d*)[ \t]*=[ \t]*([^,\r\n]*)")
_VALUE = re.compile(rf"^({NUMBER})[ \t]*(mm|deg)[ \t]*$")
_FRAME = {"UF": re.compile(r"\bUF[ \t]*:[ \t]*(\w+)"), "UT": re.compile(r"\bUT[ \t]*:[ \t]*(\w+)")}
_CONFIG = re.compile(r"\bCONFIG[ \t]*:[ \t]*'([^']*)'")
_CARTESIAN = (("X", "mm"), ("Y", "mm"), ("Z", "mm"), ("W", "deg"), ("P", "deg"), ("R", "deg"))


def _assignments(text, start, end, fail, index):
    """``{NAME: (value, (start, end), unit)}`` of ``NAME = number unit`` in ``text[start:end]``."""
    out = {}
    for m in _ASSIGN.finditer(text, start, end):
        name, raw = m.group(1), m.group(2)
        v = _VALUE.match(raw)
        if v is None:
            fail(f"{name} = {raw.strip()!r}: expected a number followed by mm or deg", index.line(m.start()), name)
        s = m.start(2) + v.start(1)
        out[name] = (float(v.group(1)), (s, s + len(v.group(1))), v.group(2))
    return out


def _position(text, name, label, start, end, fail, index):
    line = index.line(start)
    groups = list(_GROUP.finditer(text, start, end))
    if not groups or groups[0].group(1) != "1":
        fail(f"{name}: expected 'GP1:' starting the position", line)
    g_end = groups[1].start() if len(groups) > 1 else end
    g_start = groups[0].end()
    values = _assignments(text, g_start, g_end, fail, index)
    body = text[g_start:g_end]
    frames = {k: (m.group(1) if (m := rx.search(body)) else None) for k, rx in _FRAME.items()}
    c = _CONFIG.search(text, g_start, g_end)
    config = {"CONFIG": c.group(1)} if c else {}
    config_spans = {"CONFIG": (c.start(1), c.end(1))} if c else {}
    config.update({k: f"{v[0]:g} {v[2]}" for k, v in values.items() if re.fullmatch(r"E\d+", k)})
    keys = [k for k, _ in _CARTESIAN]
    joints = sorted((k for k in values if re.fullmatch(r"J\d+", k)), key=lambda k: int(k[1:]))
    common = dict(name=name, line=line, config=config, config_spans=config_spans, tool=frames["UT"],
                  base=frames["UF"], label=label)
    if any(k in values for k in keys):
        missing = [k for k in keys if k not in values]
        if missing:
            fail(f"{name}: missing {', '.join(missing)} (expected X, Y, Z [mm], W, P, R [deg])", line, missing[0])
        for k, unit in _CARTESIAN:
            if values[k][2] != unit:
                fail(f"{name}: {k} in {values[k][2]}; expected {unit}", index.line(values[k][1][0]), k)
        nums = tuple(values[k][0] for k in keys)
        T = transform_from_pose(nums, "fanuc_wpr", length_unit="mm", angle_unit="deg")
        return ProgramTarget(kind="cartesian", declaration="P[]", spans=tuple(values[k][1] for k in keys),
                             values=nums, units=tuple(u for _, u in _CARTESIAN), convention="fanuc_wpr",
                             T_frame_tcp=T, **common)
    if joints:
        expected = [f"J{i + 1}" for i in range(len(joints))]
        if joints != expected:
            fail(f"{name}: joints {', '.join(joints)}; expected {', '.join(expected)}", line)
        nums = tuple(values[k][0] for k in joints)
        units = tuple(values[k][2] for k in joints)
        q = np.array([np.radians(v) if u == "deg" else v for v, u in zip(nums, units)])
        return ProgramTarget(kind="joint", declaration="P[]", spans=tuple(values[k][1] for k in joints),
                             values=nums, units=units, joints=q, **common)
    return None


def parse_fanuc(text: str, path) -> tuple[list, list]:
    """Targets and skipped positions of a FANUC ``.ls`` program text.

    Raises :class:`~robocal.io.header.FileFormatError` for a malformed position (file, line, the
    component and what was expected).
    """
    index = LineIndex(text)
    section = _SECTION.search(text)
    if section is None:
        return [], []
    targets, skipped = [], []
    headers = list(_HEADER.finditer(text, section.start(1), section.end(1)))
    for k, h in enumerate(headers):
        line = index.line(h.start())
        name = f"P[{h.group(1)}]"

        def fail(message, ln=line, column=None):
            raise FileFormatError(path, message, ln, column)

        limit = headers[k + 1].start() if k + 1 < len(headers) else section.end(1)
        close = _CLOSE.search(text, h.end(), limit)
        if close is None:
            fail(f"{name}: expected '}};' closing the position before line {index.line(limit)}")
        label = h.group(2).strip().strip('"') if h.group(2) else None
        target = _position(text, name, label, h.end(), close.start(), fail, index)
        if target is None:
            skipped.append(Skipped(line, text[h.start():h.end()].strip(),
                                   "position form not read (only X..R or J1.. in GP1)"))
        else:
            targets.append(target)
    return targets, skipped
