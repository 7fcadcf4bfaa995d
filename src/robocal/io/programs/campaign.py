"""A measurement campaign as a program the controller runs: joint targets in driving order with a
wait / trigger comment at each measurement point, in KUKA KRL, ABB RAPID, FANUC TP or UR script.

The program is written as a skeleton with zero-valued joint targets, read back by the language's
reader (:func:`~robocal.io.programs.parse_program`) and filled in by the program writer
(:func:`~robocal.io.programs.updated_text`), so the numbers are written, and read, by the same code
that corrects real programs.
"""

from __future__ import annotations


from pathlib import Path

import numpy as np

from ..atomic import atomic_write_text
from .reader import parse_program
from .writer import updated_text

__all__ = ["CAMPAIGN_LANGUAGES", "campaign_program_text", "write_campaign_program"]

#: Language -> (reader format, file suffix).
CAMPAIGN_LANGUAGES = {"krl": ("krl", ".dat"), "rapid": ("rapid", ".mod"), "tp": ("fanuc", ".ls"),
                      "urscript": ("urscript", ".script")}
_WAIT = "measure {name} here: trigger the instrument, wait for the reading"


def _krl(names, n):
    axes = ",".join(f"A{k + 1} 0.000" for k in range(n)) + "," + ",".join(f"E{k} 0.0" for k in range(1, 7))
    dat = ["&ACCESS RVP", "DEFDAT  ROBOCAL_PLAN PUBLIC"] + [f"DECL E6AXIS X{nm}={{{axes}}}" for nm in names]
    dat += ["ENDDAT", ""]
    src = ["&ACCESS RVP", "DEF ROBOCAL_PLAN()", "  ; robocal plan-poses: measurement poses in driving order"]
    for nm in names:
        src += [f"  PTP X{nm}", f"  WAIT SEC 1.0 ; {_WAIT.format(name=nm)}"]
    src += ["END", ""]
    return "\n".join(dat), "\n".join(src), [f"X{nm}" for nm in names]


def _rapid(names, n):
    zeros = ",".join(["0.000"] * n)
    lines = ["MODULE RobocalPlan", "  ! robocal plan-poses: measurement poses in driving order"]
    lines += [f"  CONST jointtarget j{nm}:=[[{zeros}],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];" for nm in names]
    lines += ["", "  PROC main()"]
    for nm in names:
        lines += [f"    MoveAbsJ j{nm}\\NoEOffs, v200, fine, tool0;", f"    WaitTime 1; ! {_WAIT.format(name=nm)}"]
    lines += ["  ENDPROC", "ENDMODULE", ""]
    return "\n".join(lines), None, [f"j{nm}" for nm in names]


def _tp(names, n):
    mn, pos = [], []
    for i, nm in enumerate(names):
        mn += [f"J P[{i + 1}] 20% FINE    ;", f"  ! {_WAIT.format(name=nm)} ;", "  WAIT 1.00(sec) ;"]
        js = [f"J{k + 1}=     0.000 deg" for k in range(n)]
        rows = [",\t".join(js[k:k + 3]) for k in range(0, n, 3)]
        pos += [f"P[{i + 1}]{{", "   GP1:", "\tUF : 0, UT : 0,\t", *("\t" + r + ("," if k < len(rows) - 1 else "")
                                                                     for k, r in enumerate(rows)), "};"]
    lines = ["/PROG  ROBOCAL_PLAN", "/ATTR", 'COMMENT\t\t= "robocal plan-poses";', "DEFAULT_GROUP\t= 1,*,*,*,*;",
             "/MN"] + [f"{k + 1:4d}:{line}" for k, line in enumerate(mn)] + ["/POS"] + pos + ["/END", ""]
    return "\r\n".join(lines), None, [f"P[{i + 1}]" for i in range(len(names))]


def _urscript(names, n):
    zeros = ", ".join(["0.00000"] * n)
    lines = ["def robocal_plan():", "  # robocal plan-poses: measurement poses in driving order"]
    targets = []
    for nm in names:
        lines.append(f"  movej([{zeros}], a=0.5, v=0.5)")
        targets.append(f"movej@{len(lines)}")
        lines += [f"  # {_WAIT.format(name=nm)}", "  sleep(1.0)"]
    lines += ["end", ""]
    return "\n".join(lines), None, targets


_SKELETONS = {"krl": _krl, "rapid": _rapid, "tp": _tp, "urscript": _urscript}


def campaign_program_text(language: str, q, names, *, prismatic=None) -> tuple[str, str | None]:
    """``(text, companion)``: the program of the joint targets ``q`` (N, n) [rad; mm for linear
    axes] named ``names`` in ``language`` (``krl``: the ``.dat`` text and its ``.src`` companion;
    other languages: one text and None)."""
    if language not in _SKELETONS:
        raise ValueError(f"--language: expected one of {', '.join(_SKELETONS)}, got {language!r}")
    q = np.atleast_2d(np.asarray(q, dtype=float))
    if prismatic is not None and np.any(prismatic):
        raise ValueError("--language: a campaign program with linear axes is not supported")
    text, companion, targets = _SKELETONS[language](list(names), q.shape[1])
    fmt = CAMPAIGN_LANGUAGES[language][0]
    program = parse_program(text, fmt, f"<{language} campaign>")
    filled, _ = updated_text(program, dict(zip(targets, q)))
    return filled, companion


def write_campaign_program(path, language: str, q, names, *, overwrite: bool = False, prismatic=None) -> list:
    """Write the campaign program to ``path`` (its suffix replaced by the language's: ``.dat`` and
    ``.src`` for KRL, ``.mod``, ``.ls``, ``.script``); returns the paths written."""
    text, companion = campaign_program_text(language, q, names, prismatic=prismatic)
    path = Path(path).with_suffix(CAMPAIGN_LANGUAGES[language][1])
    out = [path]
    if companion is not None:
        out.append(path.with_suffix(".src"))
    if not overwrite:
        for p in out:
            if p.exists():
                raise FileExistsError(f"{p}: file exists; pass --overwrite to replace it")
    atomic_write_text(out[0], text, overwrite=overwrite)
    if companion is not None:
        atomic_write_text(out[1], companion, overwrite=overwrite)
    return out



