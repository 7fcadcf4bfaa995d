"""Probe programs: a controller computes its own flange pose for given joint sets and prints pairs.

No motion and no instrument: each program evaluates the controller's forward kinematics at the
joint sets robocal chose and prints ``robocal-pair`` lines (:mod:`robocal.io.controller_pairs`),
which ``robocal controller probe`` reads back. One writer per controller language:

- ``ur`` (URScript): ``get_forward_kin(q, p[0,0,0,0,0,0])``, lines sent over a socket to a PC
  (``socket_open(host, port)``; listen with e.g. ``nc -l PORT > pairs.txt``);
- ``abb`` (RAPID): ``CalcRobT(jointtarget, tool0 \\WObj:=wobj0)``, lines written to a file on the
  controller (``HOME:/robocal_pairs.txt``);
- ``kuka`` (KRL, KSS 8): ``FORWARD(E6AXIS, ERR)`` with ``$TOOL = $NULLFRAME`` and
  ``$BASE = $ROBROOT`` -- the pose ``$POS_ACT`` shows when the arm stands at ``$AXIS_ACT`` --
  written with ``CWRITE($FCT_CALL, ..., "krl_fprintf", ...)`` to ``robocal_pairs.txt``;
- ``doosan`` (DRL): ``fkin(posj(...), ref=DR_BASE)``, lines sent over a client socket.

The programs are text; they have not been run on every controller release (docs/controller.md).
"""

from __future__ import annotations

import numpy as np

__all__ = ["PROBE_LANGUAGES", "probe_program_text"]

PROBE_LANGUAGES = ("ur", "abb", "kuka", "doosan")


def _f(x: float, digits: int = 12) -> str:
    return f"{float(x):.{digits}g}"


def _ur(q, host, port, name):
    lines = [f"def {name}():",
             "  # robocal controller probe-program ur: the controller's own forward kinematics at "
             f"{len(q)} joint sets; run it as a program (e.g. sent to the controller's port 30002)",
             "  # (no motion). Listen on the PC first, e.g.  nc -l " + str(port) + " > pairs.txt",
             f'  socket_open("{host}", {port}, "robocal")']
    for i, row in enumerate(q):
        lines.append(f"  q = [{', '.join(_f(v) for v in row)}]")
        lines.append(f'  socket_send_line(str_cat("robocal-pair,ur,{i},", str_cat(to_str(q), str_cat(",", '
                     'to_str(get_forward_kin(q, p[0,0,0,0,0,0]))))), "robocal")')
    lines += ['  socket_close("robocal")', "end", ""]
    return "\n".join(lines)


def _abb(q, name):
    qd = np.degrees(q)
    lines = [f"MODULE {name}",
             "  ! robocal controller probe-program abb: CalcRobT (the controller's own forward kinematics,",
             f"  ! tool0 in wobj0) at {len(q)} joint sets, no motion; writes HOME:/robocal_pairs.txt;",
             f"  ! load the module and call {name}_run",
             "  LOCAL VAR iodev f;",
             "  LOCAL PROC w(num i, jointtarget jt)",
             "    VAR robtarget p;",
             "    p := CalcRobT(jt, tool0 \\WObj:=wobj0);",
             '    Write f, "robocal-pair,abb," + NumToStr(i, 0) + "," \\NoNewLine;',
             '    Write f, NumToStr(jt.robax.rax_1, 6) + "," + NumToStr(jt.robax.rax_2, 6) + "," \\NoNewLine;',
             '    Write f, NumToStr(jt.robax.rax_3, 6) + "," + NumToStr(jt.robax.rax_4, 6) + "," \\NoNewLine;',
             '    Write f, NumToStr(jt.robax.rax_5, 6) + "," + NumToStr(jt.robax.rax_6, 6) + "," \\NoNewLine;',
             '    Write f, NumToStr(p.trans.x, 4) + "," + NumToStr(p.trans.y, 4) + "," \\NoNewLine;',
             '    Write f, NumToStr(p.trans.z, 4) + "," + NumToStr(p.rot.q1, 8) + "," \\NoNewLine;',
             '    Write f, NumToStr(p.rot.q2, 8) + "," + NumToStr(p.rot.q3, 8) + "," \\NoNewLine;',
             "    Write f, NumToStr(p.rot.q4, 8);",
             "  ENDPROC",
             f"  PROC {name}_run()",
             '    Open "HOME:" \\File:="robocal_pairs.txt", f \\Write;']
    for i, row in enumerate(qd):
        lines.append(f"    w {i}, [[{', '.join(_f(v, 10) for v in row)}], [9E9, 9E9, 9E9, 9E9, 9E9, 9E9]];")
    lines += ["    Close f;", "  ENDPROC", "ENDMODULE", ""]
    return "\n".join(lines)


def _kuka(q, name):
    qd = np.degrees(q)
    lines = [f"DEF {name}()",
             "; robocal controller probe-program kuka: FORWARD (the controller's own forward kinematics; the pose",
             f"; $POS_ACT shows at $AXIS_ACT) at {len(q)} joint sets, no motion; writes robocal_pairs.txt (KSS 8 CWRITE)",
             "  DECL E6AXIS AX", "  DECL E6POS P", "  DECL INT ERR, HANDLE", "  DECL STATE_T STAT", "  DECL MODUS_T MODE",
             "  MODE = #SYNC", "  $TOOL = $NULLFRAME", "  $BASE = $ROBROOT",
             '  CWRITE($FCT_CALL, STAT, MODE, "krl_fopen", "robocal_pairs.txt", "w", HANDLE)']
    for i, row in enumerate(qd):
        a = ", ".join(f"A{k + 1} {_f(v, 10)}" for k, v in enumerate(row))
        lines.append(f"  AX = {{{a}, E1 0, E2 0, E3 0, E4 0, E5 0, E6 0}}")
        lines.append("  P = FORWARD(AX, ERR)")
        lines.append('  CWRITE($FCT_CALL, STAT, MODE, "krl_fprintf", HANDLE, '
                     f'"robocal-pair,kuka,{i},%f,%f,%f,%f,%f,%f,%f,%f,%f,%f,%f,%f\\n", AX.A1, AX.A2, AX.A3, AX.A4, '
                     "AX.A5, AX.A6, P.X, P.Y, P.Z, P.A, P.B, P.C)")
    lines += ['  CWRITE($FCT_CALL, STAT, MODE, "krl_fclose", HANDLE)', "END", ""]
    return "\n".join(lines)


def _doosan(q, host, port):
    qd = np.degrees(q)
    lines = ["# robocal controller probe-program doosan: fkin (the controller's own forward kinematics) at "
             f"{len(q)} joint sets,",
             f"# no motion; lines go to a PC over a client socket (listen first, e.g.  nc -l {port} > pairs.txt)",
             f'sock = client_socket_open("{host}", {port})',
             "qs = ["]
    lines += [f"    [{', '.join(_f(v, 10) for v in row)}]," for row in qd]
    lines += ["]",
              "for i in range(len(qs)):",
              "    q = qs[i]",
              "    p = fkin(posj(q[0], q[1], q[2], q[3], q[4], q[5]), ref=DR_BASE)",
              '    line = "robocal-pair,doosan,%d,%s,%s\\n" % (i, ",".join([str(v) for v in q]), '
              '",".join([str(p[k]) for k in range(6)]))',
              '    client_socket_write(sock, line.encode("utf-8"))',
              "client_socket_close(sock)", ""]
    return "\n".join(lines)


def probe_program_text(language: str, q, *, host: str = "192.168.0.10", port: int = 30005,
                       name: str = "robocal_probe") -> str:
    """The probe program of ``language`` (:data:`PROBE_LANGUAGES`) for joint sets ``q`` (N, 6) [rad].

    ``host``/``port``: the PC that collects the lines (UR, Doosan: socket programs).
    """
    q = np.atleast_2d(np.asarray(q, dtype=float))
    if q.shape[1] != 6:
        raise ValueError(f"probe programs are written for 6-joint arms, got {q.shape[1]} joints")
    if not np.isfinite(q).all():
        raise ValueError("joint sets contain non-finite values")
    if language == "ur":
        return _ur(q, host, port, name)
    if language == "abb":
        return _abb(q, name)
    if language == "kuka":
        return _kuka(q, name)
    if language == "doosan":
        return _doosan(q, host, port)
    raise ValueError(f"probe program language {language!r}: expected one of {', '.join(PROBE_LANGUAGES)}")
