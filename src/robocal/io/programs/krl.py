"""KUKA KRL programs (``.src`` / ``.dat``): ``E6POS``, ``POS``, ``FRAME``, ``E6AXIS``, ``AXIS``.

Reads declarations with an initial value, e.g. in a ``.dat`` file::

    DECL E6POS XP1={X 1200.5,Y -310.25,Z 1450.0,A 12.5,B 80.0,C -4.0,S 2,T 35,E1 0.0,E2 0.0}
    DECL E6AXIS XHOME={A1 0.0,A2 -90.0,A3 90.0,A4 0.0,A5 0.0,A6 0.0}
    DECL FDAT FP1={TOOL_NO 1,BASE_NO 2,IPO_FRAME #BASE}

X, Y, Z [mm] and A, B, C [deg] (``kuka_abc``: Rz(A) Ry(B) Rx(C)); A1 .. A6 [deg]. S, T and
external axes E1 .. E6 are kept verbatim in ``config``. The tool and base of ``XP1`` come from the
``FDAT`` called ``FP1`` when the file declares one (inline forms link them by name). Comments
(``;`` to the end of the line) are ignored; KRL names are case-insensitive.
"""

from __future__ import annotations

import re

import numpy as np

from ...transforms import transform_from_pose
from ..header import FileFormatError
from .source import NUMBER_FULL, LineIndex, mask
from .target import ProgramTarget, Skipped

__all__ = ["parse_krl"]

_TYPES = {"E6POS": "cartesian", "POS": "cartesian", "FRAME": "cartesian", "E6AXIS": "joint", "AXIS": "joint"}
_CARTESIAN = ("X", "Y", "Z", "A", "B", "C")
_JOINTS = ("A1", "A2", "A3", "A4", "A5", "A6")
_VERBATIM = {"E6POS": ("S", "T", "E1", "E2", "E3", "E4", "E5", "E6"), "POS": ("S", "T"), "FRAME": (),
             "E6AXIS": ("E1", "E2", "E3", "E4", "E5", "E6"), "AXIS": ()}
_DECL = re.compile(r"^[ \t]*((?:(?:DECL|GLOBAL|CONST)[ \t]+)*)(E6POS|E6AXIS|POS|AXIS|FRAME|FDAT)[ \t]+"
                   r"([A-Za-z_$][\w$]*)[ \t]*(\[[^\]\n]*\])?[ \t]*(=)?", re.I | re.M)
_OPEN = re.compile(r"[ \t]*\{")
_COMPONENT = re.compile(r"\s*([A-Za-z_]\w*)\s+(\S(?:.*\S)?)\s*$", re.S)


def _components(text, masked, start, end, fail, line):
    """``{NAME: (value text, start, end)}`` of the aggregate ``{...}`` body ``text[start:end]``."""
    out = {}
    pos = start
    for piece in masked[start:end].split(","):
        m = _COMPONENT.match(piece)
        if m is None:
            fail(f"expected 'NAME value' in the aggregate, found {text[pos:pos + len(piece)].strip()!r}", line)
        name = m.group(1).upper()
        if name in out:
            fail(f"component {name} given twice", line, name)
        s, e = pos + m.start(2), pos + m.end(2)
        out[name] = (text[s:e], s, e)
        pos += len(piece) + 1
    return out


def _aggregate_end(masked, start, fail, line) -> int:
    """Offset of the ``}`` closing the aggregate that opens at ``start`` (on the same line)."""
    newline = masked.find("\n", start)
    close = masked.find("}", start, None if newline == -1 else newline)
    if close == -1:
        fail("expected '}' closing the aggregate on the same line", line)
    return close


def _target(decl, name, comps, fail, line) -> ProgramTarget:
    kind = _TYPES[decl]
    keys = _CARTESIAN if kind == "cartesian" else _JOINTS
    allowed = set(keys) | set(_VERBATIM[decl])
    for key in comps:
        if key not in allowed:
            fail(f"{decl} {name}: unknown component {key} (expected {', '.join(keys + _VERBATIM[decl])})", line, key)
    missing = [k for k in keys if k not in comps]
    if missing:
        fail(f"{decl} {name}: missing component(s) {', '.join(missing)} (expected {', '.join(keys)})", line, missing[0])
    for k in keys:
        if not NUMBER_FULL.match(comps[k][0]):
            fail(f"{decl} {name}: {comps[k][0]!r} is not a number (component {k})", line, k)
    values = tuple(float(comps[k][0]) for k in keys)
    spans = tuple((comps[k][1], comps[k][2]) for k in keys)
    config = {k: comps[k][0] for k in _VERBATIM[decl] if k in comps}
    config_spans = {k: (comps[k][1], comps[k][2]) for k in config}
    if kind == "joint":
        return ProgramTarget(name=name, kind=kind, declaration=decl, line=line, spans=spans, values=values,
                             units=("deg",) * 6, joints=np.radians(values), config=config)
    T = transform_from_pose(values, "kuka_abc", length_unit="mm", angle_unit="deg")
    return ProgramTarget(name=name, kind=kind, declaration=decl, line=line, spans=spans, values=values,
                         units=("mm",) * 3 + ("deg",) * 3, convention="kuka_abc", T_frame_tcp=T, config=config,
                         config_spans=config_spans)


def parse_krl(text: str, path) -> tuple[list, list]:
    """Targets and skipped declarations of a KRL source text (``.src`` or ``.dat``).

    Raises :class:`~robocal.io.header.FileFormatError` for a malformed declaration (file, line,
    the component and what was expected).
    """
    masked = mask(text, ";")
    index = LineIndex(text)
    targets, skipped, fdat = [], [], {}
    for m in _DECL.finditer(masked):
        line = index.line(m.start(2))

        def fail(message, ln=line, column=None):
            raise FileFormatError(path, message, ln, column)

        decl, name = m.group(2).upper(), m.group(3)
        if m.group(4):
            skipped.append(Skipped(line, text[m.start(2):m.end()].strip(), "array declaration (not read)"))
            continue
        if not m.group(5):
            continue  # declared without a value
        brace = _OPEN.match(masked, m.end())
        if brace is None:
            fail(f"{decl} {name}: expected '{{' after '='")
        close = _aggregate_end(masked, brace.end(), fail, line)
        if decl == "FDAT":
            fdat[name.upper()] = {k: v.group(1) for k in ("TOOL_NO", "BASE_NO")
                                  if (v := re.search(rf"\b{k}\s+(\d+)", masked[brace.end():close], re.I))}
            continue
        comps = _components(text, masked, brace.end(), close, fail, line)
        targets.append(_target(decl, name, comps, fail, line))
    return [_with_frames(t, fdat) for t in targets], skipped


def _with_frames(target, fdat) -> ProgramTarget:
    """Tool and base ids from the FDAT that goes with the target (``XP1`` -> ``FP1``)."""
    if not target.name.upper().startswith("X"):
        return target
    comps = fdat.get("F" + target.name[1:].upper())
    if comps is None:
        return target
    return ProgramTarget(**{**target.__dict__, "tool": comps.get("TOOL_NO"), "base": comps.get("BASE_NO")})
