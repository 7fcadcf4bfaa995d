"""The targets of a robot program, as read from its source text."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

__all__ = ["ProgramTarget", "Program", "Skipped"]


@dataclass(frozen=True, eq=False)
class ProgramTarget:
    """One Cartesian or joint target declared in a program.

    name: the target's name in the program (``XP1``, ``p10``, ``P[3]``, ``movel@12``).
    kind: ``"cartesian"`` or ``"joint"``.
    declaration: the declared type or instruction (``E6POS``, ``robtarget``, ``P[]``, ``movel``).
    line: 1-based line of the declaration in the source text.
    spans: ``(start, end)`` character offsets of each number in the source text, in value order
        (Cartesian: x, y, z then the 3 or 4 orientation numbers; joint: one per axis).
    values: the numbers as written, in the program's units (``units``, one per value:
        ``"mm"``, ``"m"``, ``"deg"``, ``"rad"`` or ``"1"`` for quaternion components).
    convention: orientation convention of a Cartesian target (``kuka_abc``, ``fanuc_wpr``,
        ``quaternion``, ``rotvec``; see docs/conventions.md), ``None`` for joint targets.
    T_frame_tcp: (4, 4) pose of the TCP in the target's frame (base / user frame / work object)
        [mm], Cartesian targets only. joints: (n,) [rad; mm for linear axes], joint targets only.
    config: the controller's configuration data, verbatim text (KUKA ``S``, ``T``; ABB ``conf``,
        ``extax``; FANUC ``CONFIG``), keyed by the format's names.
    config_spans: ``{key: (start, end)}`` character offsets of each ``config`` item in the source
        text (so the configuration data can be rewritten), where known.
    tool, base: tool and base/user-frame/work-object ids where the format names them, else ``None``.
    label: a comment attached to the target (FANUC ``P[2:"approach"]``), else ``None``.
    other_frames: further ``(tool, base)`` pairs the program uses the target with (RAPID: move
        instructions with another tool or work object than the first), else empty.
    """

    name: str
    kind: str
    declaration: str
    line: int
    spans: tuple
    values: tuple
    units: tuple
    convention: str | None = None
    T_frame_tcp: np.ndarray | None = None
    joints: np.ndarray | None = None
    config: dict = field(default_factory=dict)
    config_spans: dict = field(default_factory=dict)
    tool: str | None = None
    base: str | None = None
    label: str | None = None
    other_frames: tuple = ()


@dataclass(frozen=True)
class Skipped:
    """A declaration that holds a target but was not read (array, inline target, expression)."""

    line: int
    text: str
    reason: str


@dataclass(frozen=True, eq=False)
class Program:
    """A robot program's source and its targets.

    text: the whole source (line endings as in the file); encoding: how the bytes were decoded
    (encoding ``text`` back gives the file's bytes). format: ``krl``, ``rapid``, ``fanuc`` or
    ``urscript``. skipped: target-like declarations that were not read, with the reason.
    """

    path: str
    format: str
    text: str
    encoding: str
    targets: tuple
    skipped: tuple = ()

    @property
    def names(self) -> tuple:
        return tuple(t.name for t in self.targets)

    def target(self, name: str) -> ProgramTarget:
        """The target called ``name`` (case-insensitive, as controllers compare names)."""
        hits = [t for t in self.targets if t.name.casefold() == name.casefold()]
        if not hits:
            raise KeyError(f"{self.path}: no target {name!r}; targets: {', '.join(self.names) or 'none'}")
        if len(hits) > 1:
            raise KeyError(f"{self.path}: target name {name!r} is declared {len(hits)} times "
                           f"(lines {', '.join(str(t.line) for t in hits)})")
        return hits[0]
