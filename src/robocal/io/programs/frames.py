"""The tool and the base / user frame / work object of every target, as the controller would use them.

A Cartesian target is the pose of the tool centre point (TCP) in a frame; the controller moves
the flange so that ``T_base_frame @ T_frame_tcp = T_base_flange @ T_flange_tcp``. Where the
values come from:

- KUKA KRL: ``TOOL_NO``/``BASE_NO`` of the point's ``FDAT``; values ``TOOL_DATA[n]`` /
  ``BASE_DATA[n]`` from the robot's ``$config.dat`` (``config_dat=``) or the ``tool=``/``base=``
  options. Tool and base 0 are the flange and the robot base.
- ABB RAPID: the tool and ``\\WObj`` of the move instruction; ``tooldata`` / ``wobjdata``
  declared in the module (``tool0``/``wobj0`` are the flange / base; a work object is
  ``uframe @ oframe``), or the options.
- FANUC TP: ``UT``/``UF`` numbers; 0 is the faceplate / world; other numbers need the options.
- UR script: the last ``set_tcp(p[...])`` before the motion in the script's text order (the
  installation's TCP, i.e. the option, or the flange before any); poses are in the base frame.

Options ``tool``/``base`` are ``(x, y, z[, a, b, c])`` [mm, deg] in the program's Euler convention
(KRL A, B, C = Rz Ry Rx; FANUC W, P, R; RAPID and UR: KUKA A, B, C). A frame that cannot be
resolved raises :class:`FrameError`.
"""

from __future__ import annotations

import re

import numpy as np

from ...errors import InputError
from ...transforms import transform_from_pose
from .source import NUMBER, mask

__all__ = ["FrameError", "TargetFrames", "frame_from_option", "resolve_frames", "urscript_motions"]

_DEFAULT_TOOLS = {"", "0", "tool0"}
_DEFAULT_BASES = {"", "0", "wobj0", "$nullframe", "#base"}


class FrameError(InputError):
    """A target's tool or frame cannot be resolved (no values for the number or name it uses)."""


class TargetFrames(dict):
    """``{target name: (T_flange_tcp (4, 4), T_base_frame (4, 4), description)}`` [mm]."""


def frame_from_option(values, fmt: str, what: str) -> np.ndarray:
    """(4, 4) [mm] from ``(x, y, z[, a, b, c])`` [mm, deg] in the program's Euler convention."""
    v = [float(x) for x in values]
    if len(v) not in (3, 6):
        raise FrameError(f"--{what}: expected X,Y,Z or X,Y,Z,A,B,C [mm, deg], got {len(v)} values")
    v += [0.0] * (6 - len(v))
    conv = "fanuc_wpr" if fmt == "fanuc" else "kuka_abc"
    return transform_from_pose(v, conv, length_unit="mm", angle_unit="deg")


def _krl_data(text: str, kind: str) -> dict:
    """``{n: (4, 4)}`` of ``TOOL_DATA[n]={X ..,Y ..,Z ..,A ..,B ..,C ..}`` in a ``$config.dat`` text."""
    out = {}
    masked = mask(text, ";")
    for m in re.finditer(rf"\b{kind}_DATA\[(\d+)\]\s*=\s*\{{([^}}]*)\}}", masked, re.I):
        comps = dict(re.findall(rf"\b([XYZABC])\s+({NUMBER})", m.group(2), re.I))
        comps = {k.upper(): float(v) for k, v in comps.items()}
        if set(comps) >= set("XYZABC"):
            out[m.group(1)] = transform_from_pose([comps[k] for k in "XYZABC"], "kuka_abc")
    return out


def _rapid_numbers(s: str) -> list:
    return [float(x) for x in s.split(",")]


def _rapid_pose(trans: str, rot: str) -> np.ndarray:
    return transform_from_pose(_rapid_numbers(trans) + _rapid_numbers(rot), "quaternion", length_unit="mm")


_TOOLDATA = re.compile(r"\btooldata\s+(\w+)\s*:=\s*\[\s*(TRUE|FALSE)\s*,\s*\[\s*\[([^\]]*)\]\s*,\s*\[([^\]]*)\]",
                       re.I)
_WOBJDATA = re.compile(r"\bwobjdata\s+(\w+)\s*:=\s*\[\s*(TRUE|FALSE)\s*,\s*(TRUE|FALSE)\s*,\s*\"[^\"]*\"\s*,"
                       r"\s*\[\s*\[([^\]]*)\]\s*,\s*\[([^\]]*)\]\s*\]\s*,\s*\[\s*\[([^\]]*)\]\s*,\s*\[([^\]]*)\]", re.I)


def _rapid_data(text: str):
    masked = mask(text, "!", quotes="")
    tools, wobjs = {}, {}
    for m in _TOOLDATA.finditer(masked):
        if m.group(2).upper() == "TRUE":
            tools[m.group(1).casefold()] = _rapid_pose(m.group(3), m.group(4))
        else:
            tools[m.group(1).casefold()] = "stationary"
    for m in _WOBJDATA.finditer(masked):
        if m.group(2).upper() == "TRUE":
            wobjs[m.group(1).casefold()] = "robot-held"
        else:
            wobjs[m.group(1).casefold()] = _rapid_pose(m.group(4), m.group(5)) @ _rapid_pose(m.group(6), m.group(7))
    return tools, wobjs


_MOVE = re.compile(r"\b(movel|movej|movep|movec)\s*\(\s*", re.I)
_SET_TCP = re.compile(r"\bset_tcp\s*\(\s*p\[([^\]]*)\]\s*\)")


def urscript_motions(program):
    """The motions of a UR script in text order: list of ``(target name or None, line,
    T_flange_tcp (4, 4) or None)``, the TCP set by the last literal ``set_tcp`` before it (None:
    the installation's TCP). A target is named as :mod:`.urscript` names it."""
    text = program.text
    masked = mask(text, "#", quotes="\"'")
    names = {t.name.casefold() for t in program.targets}
    events = [(m.start(), "tcp", m) for m in _SET_TCP.finditer(masked)]
    events += [(m.start(), "move", m) for m in _MOVE.finditer(masked)]
    out, tcp = [], None
    for pos, kind, m in sorted(events, key=lambda e: e[0]):
        line = text.count("\n", 0, pos) + 1
        if kind == "tcp":
            v = [float(x) for x in text[m.start(1):m.end(1)].split(",")]
            tcp = transform_from_pose(v, "rotvec", length_unit="m", angle_unit="rad")
            continue
        func, rest = m.group(1).lower(), masked[m.end():]
        ident = re.match(r"[A-Za-z_]\w*", rest)
        if ident and not rest.startswith("p["):
            name = ident.group(0)
            out.append((name if name.casefold() in names else None, line, tcp))
        else:
            parts = (".via", ".to") if func == "movec" else ("",)
            for part in parts:
                name = f"{func}@{line}{part}"
                out.append((name if name.casefold() in names else None, line, tcp))
    return out


def resolve_frames(program, *, tool=None, base=None, config_dat=None) -> TargetFrames:
    """Tool and frame of every Cartesian target of ``program`` (see the module docstring).

    tool, base: option values ``(x, y, z[, a, b, c])`` [mm, deg] or None; config_dat: the text
    of a KUKA ``$config.dat``. Raises :class:`FrameError` naming the target and what is missing.
    """
    fmt = program.format
    T_tool_opt = None if tool is None else frame_from_option(tool, fmt, "tool")
    T_base_opt = None if base is None else frame_from_option(base, fmt, "base")
    eye = np.eye(4)
    out = TargetFrames()
    if fmt == "urscript":
        if base is not None:
            raise FrameError("--base: UR script poses are in the robot base frame; a base frame does not apply")
        first = {}
        for name, line, tcp in urscript_motions(program):
            if name is not None:
                first.setdefault(name.casefold(), (tcp, line))
        for t in program.targets:
            if t.kind != "cartesian":
                continue
            tcp, line = first.get(t.name.casefold(), (None, None))
            if tcp is not None:
                out[t.name] = (tcp, eye, f"set_tcp active at line {line}")
            elif T_tool_opt is not None:
                out[t.name] = (T_tool_opt, eye, "--tool")
            else:
                out[t.name] = (eye, eye, "flange")
        return out
    tools, bases = {}, {}
    if fmt == "krl" and config_dat is not None:
        tools, bases = _krl_data(config_dat, "TOOL"), _krl_data(config_dat, "BASE")
    if fmt == "rapid":
        tools, bases = _rapid_data(program.text)
    names = {"krl": ("TOOL_DATA[{}]", "BASE_DATA[{}]"), "rapid": ("tooldata {}", "wobjdata {}"),
             "fanuc": ("UTOOL {}", "UFRAME {}")}[fmt]
    hint = {"krl": "give $config.dat (--config-dat) or --tool/--base X,Y,Z,A,B,C",
            "rapid": "declare it in the module or give --tool/--base X,Y,Z,A,B,C",
            "fanuc": "give its values with --tool/--base X,Y,Z,W,P,R"}[fmt]
    for t in program.targets:
        if t.kind != "cartesian":
            continue
        frames, what = [], []
        for ident, table, opt, defaults, label, tmpl in (
                (t.tool, tools, T_tool_opt, _DEFAULT_TOOLS, "tool", names[0]),
                (t.base, bases, T_base_opt, _DEFAULT_BASES, "base", names[1])):
            key = "" if ident is None else str(ident).strip()
            if key.casefold() in defaults:
                frames.append(opt if opt is not None and ident is None else eye)
                what.append(f"{label} {key or 'default'}" + (" (--" + label + ")" if opt is not None and ident is None
                                                             else ""))
                continue
            value = table.get(key.casefold() if fmt == "rapid" else key)
            if isinstance(value, str):
                raise FrameError(f"{t.name}: {tmpl.format(key)} is {value}; only robot-held tools and fixed "
                                 "work objects are supported")
            if value is None and opt is not None:
                value, src = opt, f"--{label}"
            elif value is None:
                raise FrameError(f"{t.name} (line {t.line}): {tmpl.format(key)} has no values; {hint}")
            else:
                src = "config.dat" if fmt == "krl" else "module"
            frames.append(value)
            what.append(f"{tmpl.format(key)} ({src})")
        out[t.name] = (frames[0], frames[1], ", ".join(what))
    return out
