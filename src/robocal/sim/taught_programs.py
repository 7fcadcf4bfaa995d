"""Robot programs taught offline with the nominal model at known joints (KRL, RAPID, FANUC TP, UR
script), the configuration data derived from those joints: the programs the at-the-robot tests
(``tests/test_program_at_robot.py``) and the documented figures of docs/testing.md
(:mod:`robocal.docs.figures`) correct and run on a simulated true robot. Poses in mm and degrees
as the languages write them (UR script: m and rad)."""

from __future__ import annotations

import numpy as np

from ..io.programs.configuration import configuration_text
from ..io.programs.controller import with_tool
from ..kinematics.arm_configuration import arm_signature
from ..robots import load_robot
from ..transforms import euler_from_matrix, quaternion_from_matrix, rotvec_from_matrix, transform_from_pose

__all__ = ["fanuc_program", "krl_program", "rapid_program", "ur_program"]


class _Config:
    def __init__(self, config):
        self.config = config


def _taught(robot, q_deg, tool, base, euler="kuka_abc"):
    """Nominal model, joints [rad] and the TCP poses in the base frame (targets as taught offline)."""
    nom = load_robot(robot)
    q = np.radians(q_deg)
    T = np.linalg.inv(transform_from_pose(base, euler)) @ with_tool(nom, transform_from_pose(tool, euler)).fk(q)
    return nom, q, T


def _fmt(v, digits=7):
    return ",".join(f"{x:.{digits}g}" for x in v)


def krl_program(robot, q_deg, home_deg, tool, base):
    """KRL ``.dat`` text and the ``$config.dat`` text (TOOL_DATA[1], BASE_DATA[1]): XHOME at
    ``home_deg`` and one E6POS per row of ``q_deg`` (M, 6) [deg], taught with ``tool`` / ``base``
    (X, Y, Z [mm], A, B, C [deg])."""
    nom, q, T = _taught(robot, q_deg, tool, base)
    lines = ["&ACCESS RVP", "DEFDAT cell ; taught offline",
             "DECL E6AXIS XHOME={" + ",".join(f"A{i + 1} {v:.1f}" for i, v in enumerate(home_deg))
             + ",E1 0.0,E2 0.0,E3 0.0,E4 0.0,E5 0.0,E6 0.0}"]
    for k in range(len(q)):
        cfg = configuration_text(_Config({"S": "2", "T": "0"}), "krl", q[k], arm_signature(nom, q[k])[0])
        a, b, c = np.degrees(euler_from_matrix(T[k, :3, :3], "kuka_abc"))
        x, y, z = T[k, :3, 3]
        lines += [f"DECL E6POS XP{k + 1}={{X {x:.4f},Y {y:.4f},Z {z:.4f},A {a:.4f},B {b:.4f},C {c:.4f},"
                  f"S {cfg['S']},T {cfg['T']},E1 0.0,E2 0.0,E3 0.0,E4 0.0,E5 0.0,E6 0.0}}",
                  f"DECL FDAT FP{k + 1}={{TOOL_NO 1,BASE_NO 1,IPO_FRAME #BASE}}"]
    lines += ["ENDDAT", ""]
    config_dat = ("DEFDAT $CONFIG\r\nTOOL_DATA[1]={X %r,Y %r,Z %r,A %r,B %r,C %r}\r\n"
                  "BASE_DATA[1]={X %r,Y %r,Z %r,A %r,B %r,C %r}\r\nENDDAT\r\n" % (*tool, *base))
    return "\r\n".join(lines), config_dat


def rapid_program(robot, q_deg, home_deg, tool, base):
    """A RAPID module: tool data, a work object ``base``, jHome and one robtarget per row of
    ``q_deg`` (M, 6) [deg]."""
    nom, q, T = _taught(robot, q_deg, tool, base)
    tq = quaternion_from_matrix(transform_from_pose(tool, "kuka_abc")[:3, :3])
    bq = quaternion_from_matrix(transform_from_pose(base, "kuka_abc")[:3, :3])
    lines = ["MODULE cell",
             f"  PERS tooldata tSmr:=[TRUE,[[{_fmt(tool[:3], 12)}],[{_fmt(tq)}]],[1,[0,0,10],[1,0,0,0],0,0,0]];",
             f"  PERS wobjdata wTable:=[FALSE,TRUE,\"\",[[{_fmt(base[:3])}],[{_fmt(bq)}]],[[0,0,0],[1,0,0,0]]];",
             "  CONST jointtarget jHome:=[[" + _fmt(home_deg) + "],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];"]
    for k in range(len(q)):
        conf = configuration_text(_Config({"conf": ""}), "rapid", q[k], arm_signature(nom, q[k])[0])["conf"]
        lines.append(f"  CONST robtarget p{k + 1}:=[[{_fmt(T[k, :3, 3], 10)}],[{_fmt(quaternion_from_matrix(T[k, :3, :3]), 10)}],"
                     f"{conf},[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];")
    lines += ["  PROC main()", "    MoveAbsJ jHome,v1000,z50,tool0;"]
    lines += [f"    MoveJ p{k + 1},v1000,fine,tSmr\\WObj:=wTable;" for k in range(len(q))]
    return "\n".join(lines + ["  ENDPROC", "ENDMODULE", ""])


def fanuc_program(robot, q_deg, home_deg, tool, base):
    """A FANUC TP program (UTOOL / UFRAME 1: pass ``tool`` and ``base`` as options): the home
    joints and one position per row of ``q_deg`` (M, 6) [deg] with its CONFIG string."""
    nom, q, T = _taught(robot, q_deg, tool, base, "fanuc_wpr")
    lines = ["/PROG  CELL", "/ATTR", "/MN", "   1:J P[1] 100% FINE    ;", "/POS", "P[1:\"home\"]{", "   GP1:",
             "\tUF : 0, UT : 0,", "\t" + ",  ".join(f"J{i + 1}= {v:.3f} deg" for i, v in enumerate(home_deg)), "};"]
    for k in range(len(q)):
        conf = configuration_text(_Config({"CONFIG": ""}), "fanuc", q[k], arm_signature(nom, q[k])[0])["CONFIG"]
        w, p, r = np.degrees(euler_from_matrix(T[k, :3, :3], "fanuc_wpr"))
        x, y, z = T[k, :3, 3]
        lines += [f"P[{k + 2}]{{", "   GP1:", f"\tUF : 1, UT : 1,\t\tCONFIG : '{conf}',",
                  f"\tX = {x:.4f}  mm,\tY = {y:.4f}  mm,\tZ = {z:.4f}  mm,",
                  f"\tW = {w:.4f} deg,\tP = {p:.4f} deg,\tR = {r:.4f} deg", "};"]
    return "\n".join(lines + ["/END", ""])


def ur_program(robot, moves, tool):
    """``moves``: ("j", joints [deg]) commanded as joints, ("l", joints [deg]) taught as a movel pose."""
    tcp = transform_from_pose(tool, "kuka_abc")
    tv = list(tcp[:3, 3] / 1000) + list(rotvec_from_matrix(tcp[:3, :3]))
    nom = with_tool(load_robot(robot), tcp)
    lines = ["def cell():", f"  set_tcp(p[{', '.join(f'{v:.9f}' for v in tv)}])"]
    for kind, q_deg in moves:
        q = np.radians(q_deg)
        if kind == "j":
            lines.append(f"  movej([{', '.join(f'{v:.6f}' for v in q)}], a=1.4, v=1.05)")
        else:
            T = nom.fk(q)
            pv = list(T[:3, 3] / 1000) + list(rotvec_from_matrix(T[:3, :3]))
            lines.append(f"  movel(p[{', '.join(f'{v:.7f}' for v in pv)}], a=1.2, v=0.25)")
    return "\n".join(lines + ["end", ""])
