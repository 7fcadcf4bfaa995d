"""Universal Robots scripts (``.script``, ``.urscript``): literal poses and joint vectors.

Read are the literal arguments of motion commands and named waypoints::

    movej([0.0, -1.5708, 1.5708, -1.5708, -1.5708, 0.0], a=1.4, v=1.05)
    movel(p[0.4521, -0.1903, 0.3012, 0.0, 3.1416, 0.0], a=1.2, v=0.25)
    movec(p[...], p[...], a=1.2, v=0.25)
    global Waypoint_1_p=p[0.4521, -0.1903, 0.3012, 0.0, 3.1416, 0.0]
    global Waypoint_1_q=[0.0, -1.5708, 1.5708, -1.5708, -1.5708, 0.0]   # joint: used by movej()

Poses ``p[x, y, z, rx, ry, rz]`` are metres and a rotation vector in radians (``rotvec``) in the
robot base frame; joint vectors are radians. Literal targets are named ``<command>@<line>``
(``movec`` gives ``.via`` and ``.to``), assigned ones by their variable. A list is a joint target
when it is an argument of ``movej`` or assigned to a variable that ``movej`` uses. Lists holding
expressions (``p[x, y, ...]``) are skipped and listed; UR scripts have no configuration data, and
the active TCP (``set_tcp``) is not tracked.
"""

from __future__ import annotations

import re

import numpy as np

from ...transforms import transform_from_pose
from ..header import FileFormatError
from .source import NUMBER_FULL, LineIndex, mask
from .target import ProgramTarget, Skipped

__all__ = ["parse_urscript"]

_MOVE = re.compile(r"\b(movel|movej|movep|movec)\s*\(\s*", re.I)
_ASSIGN = re.compile(r"^[ \t]*(?:(?:global|local)[ \t]+)?([A-Za-z_]\w*)[ \t]*=[ \t]*(p?)\[", re.M)
_LIST = re.compile(r"(p?)\[([^\[\]]*)\]")


def _list_values(text, masked, start, what, fail):
    """``((values, spans), end)`` of the list ``p[...]`` / ``[...]`` at ``start``; ``(None, end)`` if
    it is not a flat list of literal numbers; 6 literal numbers are required."""
    m = _LIST.match(masked, start)
    if m is None:  # nested brackets or an unclosed list: not a literal
        return None, start + 1
    values, spans, pos = [], [], m.start(2)
    for piece in masked[m.start(2):m.end(2)].split(","):
        lead = len(piece) - len(piece.lstrip())
        s, e = pos + lead, pos + len(piece.rstrip())
        if not NUMBER_FULL.match(text[s:e]):
            return None, m.end()
        values.append(float(text[s:e]))
        spans.append((s, e))
        pos += len(piece) + 1
    if len(values) != 6:
        fail(f"{what}: {len(values)} values; expected 6 (x, y, z [m], rx, ry, rz [rad] or 6 joints [rad])", start)
    return (tuple(values), tuple(spans)), m.end()


def _make(name, kind, decl, line, parsed) -> ProgramTarget:
    values, spans = parsed
    if kind == "joint":
        return ProgramTarget(name=name, kind="joint", declaration=decl, line=line, spans=spans, values=values,
                             units=("rad",) * 6, joints=np.array(values))
    T = transform_from_pose(values, "rotvec", length_unit="m", angle_unit="rad")
    return ProgramTarget(name=name, kind="cartesian", declaration=decl, line=line, spans=spans, values=values,
                         units=("m",) * 3 + ("rad",) * 3, convention="rotvec", T_frame_tcp=T)


def _move_targets(text, masked, index, fail):
    found, uses_movej = [], set()
    for m in _MOVE.finditer(masked):
        func, line, pos = m.group(1).lower(), index.line(m.start()), m.end()
        if masked[pos:pos + 1] not in ("p", "["):
            ident = re.match(r"[A-Za-z_]\w*", masked[pos:])
            if func == "movej" and ident:
                uses_movej.add(ident.group(0))
            continue
        is_pose = masked[pos] == "p"
        if not is_pose and func != "movej":
            continue  # a plain list in movel/movep/movec: not a pose
        parts = (".via", ".to") if func == "movec" else ("",)
        for part in parts:
            parsed, pos = _list_values(text, masked, pos, f"{func}()", lambda msg, off: fail(msg, index.line(off)))
            name = f"{func}@{line}{part}"
            kind = "cartesian" if is_pose else "joint"
            found.append((name, kind, func, line, parsed, text[m.start():pos]))
            comma = re.match(r"\s*,\s*(?=p\[)", masked[pos:])
            if comma is None:
                break
            pos += comma.end()
    return found, uses_movej


def parse_urscript(text: str, path) -> tuple[list, list]:
    """Targets and skipped lists of a URScript text.

    Raises :class:`~robocal.io.header.FileFormatError` for a pose or joint list with other than 6
    values (file, line, what was expected).
    """
    masked = mask(text, "#", quotes="\"'")
    index = LineIndex(text)

    def fail(message, line):
        raise FileFormatError(path, message, line)

    found, uses_movej = _move_targets(text, masked, index, fail)
    for m in _ASSIGN.finditer(masked):
        name, is_pose = m.group(1), bool(m.group(2))
        if not is_pose and name not in uses_movej:
            continue
        line = index.line(m.start(1))
        parsed, end = _list_values(text, masked, m.end() - 1 - is_pose, name, lambda msg, off, line=line: fail(msg, line))
        found.append((name, "cartesian" if is_pose else "joint", "assignment", line, parsed, text[m.start():end]))
    targets, skipped, seen = [], [], {}
    for name, kind, decl, line, parsed, source in sorted(found, key=lambda f: f[3]):
        if parsed is None:
            skipped.append(Skipped(line, source.strip()[:80], "not all values are literal numbers"))
            continue
        seen[name] = seen.get(name, 0) + 1
        unique = name if seen[name] == 1 else f"{name}.{seen[name]}"
        targets.append(_make(unique, kind, decl, line, parsed))
    return targets, skipped
