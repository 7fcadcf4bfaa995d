"""Writing a program with new target values: only the numbers that changed are replaced.

Everything else (comments, spacing, line endings, other declarations, the configuration data)
stays byte-for-byte as it was. A changed number is written in the program's style: the decimals
it had (at least enough for 0.01 mm, 0.001 deg, 1e-5 rad or 1e-6 of a quaternion, so a
correction is never rounded away), its exponent form, sign and leading-zero style.
"""

from __future__ import annotations

import os
from pathlib import Path

from ..atomic import atomic_write_bytes
from .encode import target_values
from .source import format_like

__all__ = ["MIN_DECIMALS", "updated_text", "write_program"]

#: Fewest decimals of a changed number, per unit.
MIN_DECIMALS = {"mm": 2, "m": 5, "in": 4, "deg": 3, "rad": 5, "1": 6}


def updated_text(program, updates, config_updates=None) -> tuple[str, dict]:
    """``(text, changes)``: the program text with ``updates`` applied, and per target the number of
    numbers (and configuration items) replaced.

    updates: target name -> new value: a (4, 4) pose [mm] in the target's frame for a Cartesian
        target, (n,) joints [rad; mm for linear axes] for a joint target.
    config_updates: target name -> ``{key: text}`` new configuration data (keys of the target's
        ``config``, e.g. ``S``, ``T``, ``conf``, ``CONFIG``), written verbatim in place of the old.
    """
    edits, changes = [], {}
    for name, new in (config_updates or {}).items():
        target = program.target(name)
        for key, text in new.items():
            if key not in target.config_spans:
                raise ValueError(f"{program.path}: {name}: no configuration item {key!r} to rewrite")
            start, end = target.config_spans[key]
            if program.text[start:end] != text:
                edits.append((start, end, text))
                changes[target.name] = changes.get(target.name, 0) + 1
    for name, new in updates.items():
        target = program.target(name)
        values = target_values(target, new)
        count = 0
        for (start, end), value, unit in zip(target.spans, values, target.units):
            old = program.text[start:end]
            text = format_like(value, old, MIN_DECIMALS.get(unit, 0))
            if float(text) != float(old):
                edits.append((start, end, text))
                count += 1
        changes[target.name] = changes.get(target.name, 0) + count
    edits.sort()
    for (_s0, e0, _), (s1, _, _) in zip(edits, edits[1:]):
        if s1 < e0:
            raise ValueError(f"{program.path}: two updates change the same number (offset {s1}); "
                             "a target was given twice")
    pieces, pos = [], 0
    for start, end, text in edits:
        pieces += [program.text[pos:start], text]
        pos = end
    pieces.append(program.text[pos:])
    return "".join(pieces), changes


def _same_file(a: Path, b: Path) -> bool:
    if a.resolve() == b.resolve():
        return True
    try:
        return b.exists() and os.path.samefile(a, b)
    except OSError:
        return False


def write_program(program, updates, out, *, overwrite: bool = False, config_updates=None) -> dict:
    """Write ``program`` with ``updates`` (see :func:`updated_text`) to ``out``, atomically.

    ``out`` must not be the program's own file (``ValueError``); an existing ``out`` raises
    ``FileExistsError`` unless ``overwrite=True``. The text is encoded as the program was decoded,
    so unchanged parts are byte-identical. Returns the changes per target.
    """
    out = Path(out)
    if _same_file(Path(program.path), out):
        raise ValueError(f"{out}: is the input program {program.path}; write the corrected program to a new file")
    text, changes = updated_text(program, updates, config_updates)
    atomic_write_bytes(out, text.encode(program.encoding), overwrite=overwrite)
    return changes
