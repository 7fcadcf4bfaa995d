"""ABB RAPID modules (``.mod``, ``.modx``, ``.prg``): ``robtarget`` and ``jointtarget`` data.

Reads data declarations with an initial value::

    CONST robtarget p10:=[[1200.5,-310.25,1450],[0.7071068,0,0.7071068,0],[0,-1,0,0],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];
    PERS jointtarget jHome:=[[0,-30,30,0,90,0],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];

``trans`` [mm]; ``rot`` is the quaternion q1..q4 = (w, x, y, z) (``quaternion``); ``robax``
[deg]. ``robconf`` and ``extax`` are kept verbatim in ``config`` (``conf``, ``extax``). RAPID
targets carry no tool or work object: they are taken from the first ``MoveL``/``MoveJ``/
``MoveC``/``MoveAbsJ`` that uses the target (``wobj0`` when it names none). Comments (``!``) and
strings are ignored; names are case-insensitive.
"""

from __future__ import annotations

import re

import numpy as np

from ...transforms import transform_from_pose
from ..header import FileFormatError
from .source import NUMBER_FULL, LineIndex, mask
from .target import ProgramTarget, Skipped

__all__ = ["parse_rapid"]

_DECL = re.compile(r"\b(?:(?:LOCAL|TASK)\s+)?(?:CONST|PERS|VAR)\s+(robtarget|jointtarget)\s+([A-Za-z]\w*)"
                   r"\s*(\{[^}]*\})?\s*(:=)?", re.I)
_MOVE = re.compile(r"\b(Move(?:L|J|C|AbsJ)(?:DO|Sync)?)\b([^;]*);", re.I)
_WS = re.compile(r"\s*")
_SCALAR = re.compile(r"[^\[\],;\s](?:[^\[\],;\n]*[^\[\],;\s])?")
_LAYOUT = {"robtarget": ((3, 4, 4, 6), "[[x,y,z],[q1,q2,q3,q4],[cf1,cf4,cf6,cfx],[eax_a,...,eax_f]]"),
           "jointtarget": ((6, 6), "[[rax_1,...,rax_6],[eax_a,...,eax_f]]")}


def _aggregate(masked, pos, fail):
    """Parse ``[...]`` starting at ``pos`` (after blanks): ``((start, end, items), end)`` where
    ``items`` is a list of such nodes, or ``None`` for a scalar."""
    pos = _WS.match(masked, pos).end()
    if masked[pos:pos + 1] != "[":
        fail("expected '[' starting an aggregate", pos)
    start, pos, items = pos, pos + 1, []
    close = _WS.match(masked, pos).end()
    if masked[close:close + 1] == "]":
        return (start, close + 1, items), close + 1
    while True:
        pos = _WS.match(masked, pos).end()
        if masked[pos:pos + 1] == "[":
            node, pos = _aggregate(masked, pos, fail)
        else:
            m = _SCALAR.match(masked, pos)
            if m is None:
                fail("expected a value or '['", pos)
            node, pos = (m.start(), m.end(), None), m.end()
        items.append(node)
        pos = _WS.match(masked, pos).end()
        ch = masked[pos:pos + 1]
        if ch == "]":
            return (start, pos + 1, items), pos + 1
        if ch != ",":
            fail("expected ',' or ']' in the aggregate", pos)
        pos += 1


def _numbers(text, nodes, what, fail):
    out = []
    for start, end, items in nodes:
        if items is not None or not NUMBER_FULL.match(text[start:end]):
            fail(f"{what}: {text[start:end]!r} is not a number", start)
        out.append((float(text[start:end]), (start, end)))
    return out


def _target(text, decl, name, tree, fail, line) -> ProgramTarget:
    shape, layout = _LAYOUT[decl]
    groups = tree[2]
    if len(groups) != len(shape) or any(g[2] is None or len(g[2]) != n for g, n in zip(groups, shape)):
        fail(f"{decl} {name}: expected {layout}", tree[0])
    config = {"conf": text[groups[2][0]:groups[2][1]]} if decl == "robtarget" else {}
    config["extax"] = text[groups[-1][0]:groups[-1][1]]
    if decl == "jointtarget":
        nums = _numbers(text, groups[0][2], f"jointtarget {name}", fail)
        values = tuple(v for v, _ in nums)
        return ProgramTarget(name=name, kind="joint", declaration=decl, line=line, spans=tuple(s for _, s in nums),
                             values=values, units=("deg",) * 6, joints=np.radians(values), config=config)
    nums = _numbers(text, groups[0][2] + groups[1][2], f"robtarget {name}", fail)
    values = tuple(v for v, _ in nums)
    try:
        T = transform_from_pose(values, "quaternion", length_unit="mm")
    except ValueError:
        fail(f"robtarget {name}: quaternion {values[3:]} has norm {np.linalg.norm(values[3:]):.6g}; expected a "
             "unit quaternion [q1,q2,q3,q4] = (w, x, y, z)", groups[1][0])
    return ProgramTarget(name=name, kind="cartesian", declaration=decl, line=line, spans=tuple(s for _, s in nums),
                         values=values, units=("mm",) * 3 + ("1",) * 4, convention="quaternion", T_frame_tcp=T,
                         config=config, config_spans={"conf": (groups[2][0], groups[2][1])})


def _split_args(args: str) -> list[str]:
    out, depth, start = [], 0, 0
    for i, ch in enumerate(args):
        if ch in "[(":
            depth += 1
        elif ch in "])":
            depth -= 1
        elif ch == "," and depth == 0:
            out.append(args[start:i].strip())
            start = i + 1
    out.append(args[start:].strip())
    return [a for a in out if a and not a.startswith("\\")]


def _frames_and_inline(masked, text, index):
    """``{name: (tool, wobj)}`` of the first move using each target, and inline targets skipped."""
    frames, skipped = {}, []
    for m in _MOVE.finditer(masked):
        args = _split_args(m.group(2))
        circular = m.group(1).upper().startswith("MOVEC")
        n_targets, tool_at = (2, 4) if circular else (1, 3)
        if len(args) <= tool_at:
            continue
        tool = args[tool_at].split("\\")[0].strip()
        wobj = re.search(r"\\WObj\s*:=\s*([A-Za-z]\w*)", m.group(2), re.I)
        for arg in args[:n_targets]:
            if arg.startswith("["):
                skipped.append(Skipped(index.line(m.start()), text[m.start():m.end()].strip()[:80],
                                       "inline target in a move instruction (not a declaration)"))
                continue
            name = arg.split("\\")[0].strip()
            if re.fullmatch(r"[A-Za-z]\w*", name):
                pair = (tool, wobj.group(1) if wobj else "wobj0")
                seen = frames.setdefault(name.casefold(), [])
                if all(tuple(x.casefold() for x in pair) != tuple(x.casefold() for x in p) for p in seen):
                    seen.append(pair)
    return frames, skipped


def parse_rapid(text: str, path) -> tuple[list, list]:
    """Targets and skipped declarations of a RAPID module text.

    Raises :class:`~robocal.io.header.FileFormatError` for a malformed declaration (file, line,
    what was expected).
    """
    masked = mask(text, "!")
    index = LineIndex(text)
    targets, skipped = [], []
    for m in _DECL.finditer(masked):
        line = index.line(m.start())

        def fail(message, offset=None, ln=line):
            raise FileFormatError(path, message, ln if offset is None else index.line(offset))

        decl, name = m.group(1).lower(), m.group(2)
        if m.group(3):
            skipped.append(Skipped(line, text[m.start():m.end()].strip(), "array declaration (not read)"))
            continue
        if not m.group(4):
            continue  # declared without a value
        value_at = _WS.match(masked, m.end()).end()
        if masked[value_at:value_at + 1] != "[":
            skipped.append(Skipped(line, text[m.start():value_at + 40].split(";")[0].strip(),
                                   "initial value is an expression, not a literal aggregate"))
            continue
        tree, end = _aggregate(masked, m.end(), fail)
        semicolon = _WS.match(masked, end).end()
        if masked[semicolon:semicolon + 1] != ";":
            fail(f"{decl} {name}: expected ';' after the aggregate", end - 1)
        targets.append(_target(text, decl, name, tree, fail, line))
    frames, inline = _frames_and_inline(masked, text, index)
    out = []
    for t in targets:
        pairs = frames.get(t.name.casefold(), [(None, None)])
        out.append(ProgramTarget(**{**t.__dict__, "tool": pairs[0][0], "base": pairs[0][1],
                                    "other_frames": tuple(pairs[1:])}))
    return out, skipped + inline
