"""Robot programs in and out: KRL, RAPID, FANUC TP and UR script targets (robocal.io.programs)."""

import numpy as np
import pytest

from robocal.io.header import FileFormatError
from robocal.io.programs import parse_program, read_program, updated_text, write_program
from robocal.io.programs.source import format_like, mask
from robocal.transforms import rot_x, rot_y, rot_z, transform_from_pose, transforms_from

DEG = np.pi / 180.0

KRL_DAT = "\r\n".join([
    "&ACCESS RVP",
    "&REL 12",
    "&PARAM EDITMASK = *",
    "DEFDAT  zelle4_pruefung",
    ";FOLD EXTERNAL DECLARATIONS;%{PE}%V3.2.0,%MKUKATPBASIS,%CEXT,%VCOMMON,%P",
    "EXT  BAS (BAS_COMMAND  :IN,REAL  :IN )",
    "DECL INT SUCCESS",
    ";ENDFOLD (EXTERNAL DECLARATIONS)",
    'DECL BASIS_SUGG_T LAST_BASIS={POINT1[] "P2                      ",CP_VEL[] "2.0                     "}',
    "DECL E6POS XP1={X 1250.0,Y -310.25,Z 1450.5,A 12.5,B 80.0,C -4.0,S 2,T 35,E1 0.0,E2 0.0,E3 0.0,E4 0.0,E5 0.0,E6 0.0}",
    'DECL FDAT FP1={TOOL_NO 3,BASE_NO 2,IPO_FRAME #BASE,POINT2[] " ",TQ_STATE FALSE}',
    "DECL PDAT PPDAT1={VEL 100.000,ACC 100.000,APO_DIST 100.000,APO_MODE #CDIS}",
    "DECL E6POS XP2={X 1410.75,Y 95.5,Z 1320.0,A -170.0,B 35.25,C 179.5,S 6,T 50,E1 0.0,E2 0.0,E3 0.0,E4 0.0,E5 0.0,E6 0.0}",
    'DECL FDAT FP2={TOOL_NO 3,BASE_NO 2,IPO_FRAME #BASE,POINT2[] " ",TQ_STATE FALSE}',
    ";DECL E6POS XP9={X 0.0,Y 0.0,Z 0.0,A 0.0,B 0.0,C 0.0} ; auskommentiert, Prüfpunkt entfällt",
    "DECL E6AXIS XHOME={A1 0.0,A2 -90.0,A3 90.0,A4 0.0,A5 0.0,A6 0.0,E1 0.0,E2 0.0,E3 0.0,E4 0.0,E5 0.0,E6 0.0}",
    "DECL POS P_ABLAGE={X 980.5,Y 0.0,Z 1100.0,A 0.0,B 90.0,C 0.0,S 'B010',T 'B100010'}",
    "DECL FRAME F_WERKZEUG={X 12.5,Y -3.0,Z 180.25,A 0.0,B 0.0,C 90.0}",
    "DECL AXIS A_PARK={A1 -45.5,A2 -100.0,A3 110.0,A4 0.0,A5 80.0,A6 12.0}",
    "DECL E6POS XP3={X 700.0,Y 20.0,Z 900.0,A 10.0,B 100.0,C 20.0,S 2,T 2}  ; B ueber 90 Grad",
    "ENDDAT",
    "",
])

RAPID_MOD = "\n".join([
    "%%%",
    "  VERSION:1",
    "  LANGUAGE:ENGLISH",
    "%%%",
    "",
    "MODULE Zelle4Pruefung",
    "  ! Pruefprogramm Zelle 4: Messposen fuer die Kalibrierung",
    "  PERS tooldata tGreifer:=[TRUE,[[12.5,-3,180.25],[1,0,0,0]],[2.5,[0,0,60],[1,0,0,0],0,0,0]];",
    '  TASK PERS wobjdata wobjTisch:=[FALSE,TRUE,"",[[800,-200,400],[1,0,0,0]],[[0,0,0],[1,0,0,0]]];',
    "  CONST robtarget pAnfahrt:=[[512.35,-120.5,610],[0.707107,0,0.707107,0],[-1,0,-1,0],"
    "[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];",
    "  CONST robtarget pMess10:=[[640.125,85.25,455.5],[0.5,-0.5,0.5,0.5],[0,-1,0,1],"
    "[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];",
    "  LOCAL PERS robtarget pMess20:=[[702,-15.75,398.25],[0,0,1,0],[0,0,0,0],"
    "[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];",
    "  CONST jointtarget jHome:=[[0,-20,30,0,80,0],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];",
    "  ! CONST robtarget pAlt:=[[1,2,3],[1,0,0,0],[0,0,0,0],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];",
    "  VAR robtarget pTemp;",
    "  VAR robtarget pAktuell := CRobT(\\Tool:=tGreifer \\WObj:=wobjTisch);",
    "  CONST robtarget pBahn{2}:=[[[1,2,3],[1,0,0,0],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]],"
    "[[4,5,6],[1,0,0,0],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]]];",
    "",
    "  PROC main()",
    "    MoveAbsJ jHome\\NoEOffs, v1000, z50, tGreifer;",
    "    MoveJ pAnfahrt, v500, z20, tGreifer\\WObj:=wobjTisch;",
    "    MoveL pMess10, v200, fine, tGreifer\\WObj:=wobjTisch;  ! Messpose 10",
    "    MoveL pMess20, v200, fine, tGreifer\\WObj:=wobjTisch;",
    "    MoveL [[700,0,500],[0,0,1,0],[0,0,0,0],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]], v100, fine, "
    "tGreifer\\WObj:=wobjTisch;",
    "  ENDPROC",
    "ENDMODULE",
    "",
])

FANUC_LS = "\r\n".join([
    "/PROG  ZELLE4_MESS",
    "/ATTR",
    "OWNER\t\t= MNEDITOR;",
    'COMMENT\t\t= "Messposen Zelle 4";',
    "PROG_SIZE\t= 1024;",
    "CREATE\t\t= DATE 24-03-12  TIME 10:15:02;",
    "DEFAULT_GROUP\t= 1,1,*,*,*;",
    "/APPL",
    "/MN",
    "   1:  UFRAME_NUM=1 ;",
    "   2:  UTOOL_NUM=2 ;",
    '   3:J P[1:"approach"] 100% FINE    ;',
    "   4:L P[2] 500mm/sec FINE    ;",
    "   5:J P[3] 50% CNT50    ;",
    "/POS",
    'P[1:"approach"]{',
    "   GP1:",
    "\tUF : 1, UT : 2,\t\tCONFIG : 'N U T, 0, 0, 0',",
    "\tX =  1200.500  mm,\tY =  -310.250  mm,\tZ =  1450.000  mm,",
    "\tW =   180.000 deg,\tP =      .000 deg,\tR =   -90.000 deg",
    "};",
    "P[2]{",
    "   GP1:",
    "\tUF : 1, UT : 2,\t\tCONFIG : 'F U T, 0, 0, -1',",
    "\tX =  1352.125  mm,\tY =    48.750  mm,\tZ =  1275.500  mm,",
    "\tW =  -172.500 deg,\tP =   -12.250 deg,\tR =    35.000 deg",
    "   GP2:",
    "\tUF : 1, UT : 2,\t",
    "\tJ1=   100.000  mm",
    "};",
    "P[3]{",
    "   GP1:",
    "\tUF : 1, UT : 2,\t",
    "\tJ1=     0.000 deg,\tJ2=   -30.000 deg,\tJ3=    30.000 deg,",
    "\tJ4=     0.000 deg,\tJ5=   -90.000 deg,\tJ6=   180.000 deg",
    "};",
    "/END",
    "",
])

UR_SCRIPT = "\n".join([
    "def zelle4_mess():",
    "  # Messposen fuer die Kalibrierung; movel(p[9,9,9,9,9,9]) in a comment is no target",
    "  set_tcp(p[0.0, 0.0, 0.1805, 0.0, 0.0, 0.0])",
    "  global Waypoint_1_p=p[.4521, -.1903, .3012, 0.0, 3.1416, 0.0]",
    "  global Waypoint_1_q=[0.1234, -1.5708, 1.5708, -1.5708, -1.5708, 0.0]",
    "  movej(Waypoint_1_q, a=1.4, v=1.05)",
    "  movel(p[0.4521, -0.1903, 0.3012, 0.0, 3.1416, 0.0], a=1.2, v=0.25)",
    "  movel(p[0.5100, 0.0250, 0.2800, 1.2092, 1.2092, 1.2092], a=1.2, v=0.25)",
    "  movej([-0.35, -1.9, 2.1, -1.77, -1.5708, 0.42], a=1.4, v=1.05, r=0.02)",
    "  movec(p[0.48, 0.10, 0.30, 0.0, 3.1416, 0.0], p[0.45, 0.15, 0.30, 0.0, 3.1416, 0.0], a=1.2, v=0.1, r=0)",
    "  x = 0.1",
    "  movel(p[x, -0.2, 0.3, 0, 3.1416, 0])",
    '  textmsg("movel(p[1,2,3,4,5,6]) done")',
    "end",
    "",
])

SAMPLES = {
    "zelle4.dat": (KRL_DAT, "latin-1"),
    "zelle4.mod": (RAPID_MOD, "utf-8"),
    "zelle4.ls": (FANUC_LS, "utf-8"),
    "zelle4.script": (UR_SCRIPT, "utf-8"),
}


def _write(tmp_path, name):
    text, encoding = SAMPLES[name]
    path = tmp_path / name
    path.write_bytes(text.encode(encoding))
    return path


def _value(target):
    return target.T_frame_tcp if target.kind == "cartesian" else target.joints


def _correction(seed):
    """A small rigid correction: ~0.3 mm and ~0.02 deg."""
    rng = np.random.default_rng(seed)
    R = rot_z(0.02 * DEG) @ rot_x(-0.015 * DEG)
    return transforms_from(R, rng.uniform(-0.4, 0.4, 3))


def _changed_lines(program, names):
    lines = set()
    for name in names:
        for start, end in program.target(name).spans:
            first = program.text.count("\n", 0, start)
            lines.update(range(first, program.text.count("\n", 0, end) + 1))
    return lines


# ---------------------------------------------------------------------------------------------
# reading: values checked against hand-computed numbers
# ---------------------------------------------------------------------------------------------


def test_krl_targets_and_values(tmp_path):
    prog = read_program(_write(tmp_path, "zelle4.dat"))
    assert prog.format == "krl" and prog.encoding == "latin-1"
    assert prog.names == ("XP1", "XP2", "XHOME", "P_ABLAGE", "F_WERKZEUG", "A_PARK", "XP3")
    xp1 = prog.target("xp1")
    assert xp1.kind == "cartesian" and xp1.declaration == "E6POS" and xp1.line == 10
    assert [prog.text[s:e] for s, e in xp1.spans] == ["1250.0", "-310.25", "1450.5", "12.5", "80.0", "-4.0"]
    R = rot_z(12.5 * DEG) @ rot_y(80.0 * DEG) @ rot_x(-4.0 * DEG)
    np.testing.assert_allclose(xp1.T_frame_tcp[:3, :3], R, atol=1e-15)
    np.testing.assert_allclose(xp1.T_frame_tcp[:3, 3], [1250.0, -310.25, 1450.5])
    assert xp1.config == {"S": "2", "T": "35", "E1": "0.0", "E2": "0.0", "E3": "0.0", "E4": "0.0", "E5": "0.0",
                          "E6": "0.0"}
    assert (xp1.tool, xp1.base) == ("3", "2")
    frame = prog.target("F_WERKZEUG")  # C = 90 deg: Rx(90)
    np.testing.assert_allclose(frame.T_frame_tcp[:3, :3], [[1, 0, 0], [0, 0, -1], [0, 1, 0]], atol=1e-15)
    assert frame.tool is None and frame.config == {}
    ablage = prog.target("P_ABLAGE")
    assert ablage.config == {"S": "'B010'", "T": "'B100010'"}
    np.testing.assert_allclose(ablage.T_frame_tcp[:3, :3], [[0, 0, 1], [0, 1, 0], [-1, 0, 0]], atol=1e-15)
    home = prog.target("XHOME")
    assert home.kind == "joint" and home.T_frame_tcp is None
    np.testing.assert_allclose(home.joints, [0, -np.pi / 2, np.pi / 2, 0, 0, 0], atol=1e-15)
    np.testing.assert_allclose(prog.target("A_PARK").joints[0], -45.5 * DEG)
    assert prog.skipped == ()


def test_rapid_targets_and_values(tmp_path):
    prog = read_program(_write(tmp_path, "zelle4.mod"))
    assert prog.format == "rapid"
    assert prog.names == ("pAnfahrt", "pMess10", "pMess20", "jHome")
    m10 = prog.target("pMess10")
    assert [prog.text[s:e] for s, e in m10.spans] == ["640.125", "85.25", "455.5", "0.5", "-0.5", "0.5", "0.5"]
    # hand-evaluated quaternion formula for (w, x, y, z) = (0.5, -0.5, 0.5, 0.5)
    np.testing.assert_allclose(m10.T_frame_tcp[:3, :3], [[0, -1, 0], [0, 0, 1], [-1, 0, 0]], atol=1e-15)
    assert m10.config == {"conf": "[0,-1,0,1]", "extax": "[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]"}
    assert (m10.tool, m10.base) == ("tGreifer", "wobjTisch")
    np.testing.assert_allclose(prog.target("pMess20").T_frame_tcp[:3, :3], np.diag([-1.0, 1.0, -1.0]), atol=1e-15)
    home = prog.target("jhome")
    assert home.kind == "joint" and (home.tool, home.base) == ("tGreifer", "wobj0")
    np.testing.assert_allclose(home.joints, np.radians([0, -20, 30, 0, 80, 0]))
    reasons = sorted(s.reason for s in prog.skipped)
    assert len(reasons) == 3 and "array" in reasons[0] and "expression" in reasons[1] and "inline" in reasons[2]


def test_krl_and_rapid_describe_the_same_rotation(tmp_path):
    """KUKA (A, B, C) = (0, 90, 0) and ABB q = (cos 45, 0, sin 45, 0) are both 90 deg about y."""
    krl = read_program(_write(tmp_path, "zelle4.dat")).target("P_ABLAGE")
    rapid = read_program(_write(tmp_path, "zelle4.mod")).target("pAnfahrt")
    np.testing.assert_allclose(krl.T_frame_tcp[:3, :3], rapid.T_frame_tcp[:3, :3], atol=1e-6)
    assert not np.allclose(krl.T_frame_tcp[:3, :3], rot_y(89.9 * DEG), atol=1e-6)


def test_fanuc_targets_and_values(tmp_path):
    prog = read_program(_write(tmp_path, "zelle4.ls"))
    assert prog.names == ("P[1]", "P[2]", "P[3]")
    p1 = prog.target("P[1]")
    assert p1.label == "approach" and (p1.base, p1.tool) == ("1", "2")
    assert p1.config == {"CONFIG": "N U T, 0, 0, 0"}
    assert [prog.text[s:e] for s, e in p1.spans] == ["1200.500", "-310.250", "1450.000", "180.000", ".000", "-90.000"]
    # W=180, P=0, R=-90: Rz(-90) Ry(0) Rx(180), multiplied out by hand
    np.testing.assert_allclose(p1.T_frame_tcp[:3, :3], [[0, -1, 0], [-1, 0, 0], [0, 0, -1]], atol=1e-15)
    p2 = prog.target("P[2]")
    assert p2.config == {"CONFIG": "F U T, 0, 0, -1"}  # GP2 is another motion group, not read
    np.testing.assert_allclose(p2.T_frame_tcp[:3, :3],
                               rot_z(35.0 * DEG) @ rot_y(-12.25 * DEG) @ rot_x(-172.5 * DEG), atol=1e-15)
    p3 = prog.target("P[3]")
    assert p3.kind == "joint" and p3.units == ("deg",) * 6
    np.testing.assert_allclose(p3.joints, np.radians([0, -30, 30, 0, -90, 180]))


def test_urscript_targets_and_values(tmp_path):
    prog = read_program(_write(tmp_path, "zelle4.script"))
    assert prog.names == ("Waypoint_1_p", "Waypoint_1_q", "movel@7", "movel@8", "movej@9", "movec@10.via",
                          "movec@10.to")
    wp = prog.target("Waypoint_1_p")
    np.testing.assert_allclose(wp.T_frame_tcp[:3, 3], [452.1, -190.3, 301.2], atol=1e-12)
    np.testing.assert_allclose(wp.T_frame_tcp[:3, :3], np.diag([-1.0, 1.0, -1.0]), atol=1e-4)  # pi about y
    # 120 deg about (1, 1, 1)/sqrt(3) cycles the axes: x -> y -> z -> x
    np.testing.assert_allclose(prog.target("movel@8").T_frame_tcp[:3, :3], [[0, 0, 1], [1, 0, 0], [0, 1, 0]],
                               atol=2e-4)
    q = prog.target("Waypoint_1_q")
    assert q.kind == "joint" and q.units == ("rad",) * 6
    np.testing.assert_allclose(q.joints, [0.1234, -1.5708, 1.5708, -1.5708, -1.5708, 0.0])
    assert prog.target("movec@10.to").values[:2] == (0.45, 0.15)
    assert [s.reason for s in prog.skipped] == ["not all values are literal numbers"]
    assert prog.skipped[0].line == 12


# ---------------------------------------------------------------------------------------------
# writing: byte-identical round trips, only corrected numbers change
# ---------------------------------------------------------------------------------------------


@pytest.mark.parametrize("name", sorted(SAMPLES))
def test_round_trip_unchanged_is_byte_identical(tmp_path, name):
    path = _write(tmp_path, name)
    prog = read_program(path)
    changes = write_program(prog, {t.name: _value(t) for t in prog.targets}, tmp_path / f"out_{name}")
    assert set(changes.values()) == {0}
    assert (tmp_path / f"out_{name}").read_bytes() == path.read_bytes()


CORRECTED = {"zelle4.dat": ("XP1", "XP3", "A_PARK"), "zelle4.mod": ("pMess10", "jHome"),
             "zelle4.ls": ("P[2]", "P[3]"), "zelle4.script": ("movel@8", "movej@9")}


@pytest.mark.parametrize("name", sorted(SAMPLES))
def test_corrected_targets_change_and_nothing_else(tmp_path, name):
    path = _write(tmp_path, name)
    prog = read_program(path)
    updates = {}
    for k, tname in enumerate(CORRECTED[name]):
        t = prog.target(tname)
        updates[tname] = (t.T_frame_tcp @ _correction(k) if t.kind == "cartesian"
                          else t.joints + np.radians([0.0123, -0.0456, 0.02, 0.0, 0.031, -0.01]))
    out = tmp_path / f"out_{name}"
    changes = write_program(prog, updates, out)
    assert all(changes[n] > 0 for n in CORRECTED[name])
    old_lines = path.read_bytes().splitlines(keepends=True)
    new_lines = out.read_bytes().splitlines(keepends=True)
    assert len(old_lines) == len(new_lines)
    differ = {i for i, (a, b) in enumerate(zip(old_lines, new_lines)) if a != b}
    assert differ and differ <= _changed_lines(prog, CORRECTED[name])
    new = read_program(out)
    assert new.names == prog.names
    for t_old, t_new in zip(prog.targets, new.targets):
        if t_old.name in updates:
            if t_old.kind == "cartesian":
                pos_tol = 5e-3 if t_old.units[0] == "mm" else 5e-3 + 1e-9  # 2 decimals mm, 5 decimals m
                np.testing.assert_allclose(t_new.T_frame_tcp[:3, 3], updates[t_old.name][:3, 3], atol=pos_tol)
                np.testing.assert_allclose(t_new.T_frame_tcp[:3, :3], updates[t_old.name][:3, :3], atol=2e-5)
                assert not np.allclose(t_new.T_frame_tcp, t_old.T_frame_tcp, atol=1e-3)
            else:
                np.testing.assert_allclose(t_new.joints, updates[t_old.name], atol=1e-5)
        else:
            assert t_new.values == t_old.values
        assert t_new.config == t_old.config and (t_new.tool, t_new.base) == (t_old.tool, t_old.base)


def test_krl_corrected_numbers_in_program_style(tmp_path):
    prog = read_program(_write(tmp_path, "zelle4.dat"))
    xp1 = prog.target("XP1")
    T = xp1.T_frame_tcp.copy()
    T[:3, 3] += [0.314, 0.0, -0.05]  # position only: the orientation numbers stay as they were
    text, changes = updated_text(prog, {"XP1": T})
    line = text.split("\r\n")[9]
    assert line == ("DECL E6POS XP1={X 1250.31,Y -310.25,Z 1450.45,A 12.5,B 80.0,C -4.0,S 2,T 35,"
                    "E1 0.0,E2 0.0,E3 0.0,E4 0.0,E5 0.0,E6 0.0}")
    assert changes == {"XP1": 2}


def test_krl_keeps_the_euler_solution_the_program_uses(tmp_path):
    """XP3 has B = 100 deg (the second solution); a tiny correction must not flip to B = 80."""
    prog = read_program(_write(tmp_path, "zelle4.dat"))
    xp3 = prog.target("XP3")
    text, _ = updated_text(prog, {"XP3": xp3.T_frame_tcp @ transforms_from(rot_x(0.01 * DEG), None)})
    new = parse_program(text, "krl").target("XP3")
    np.testing.assert_allclose(new.values[3:], [10.0, 100.0, 20.01], atol=2e-3)


def test_rapid_quaternion_sign_and_gimbal_numbers_kept(tmp_path):
    text = ("MODULE M\n  CONST robtarget pNeg:=[[100,200,300],[-0.5,0.5,-0.5,-0.5],[0,0,0,0],"
            "[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];\nENDMODULE\n")
    prog = parse_program(text, "rapid")
    t = prog.target("pNeg")
    new_text, _ = updated_text(prog, {"pNeg": t.T_frame_tcp @ transforms_from(rot_z(0.05 * DEG), None)})
    q = np.array(parse_program(new_text, "rapid").target("pNeg").values[3:])
    assert q[0] < 0 and np.linalg.norm(q - [-0.5, 0.5, -0.5, -0.5]) < 1e-3
    # KUKA B = 90 (gimbal lock): a position-only change keeps A and C as written
    krl = parse_program("DECL E6POS XP5={X 1.0,Y 2.0,Z 3.0,A 30.0,B 90.0,C 30.0,S 2,T 2}\n", "krl")
    T = krl.target("XP5").T_frame_tcp.copy()
    T[0, 3] = 1500.0
    assert updated_text(krl, {"XP5": T})[0] == "DECL E6POS XP5={X 1500.00,Y 2.0,Z 3.0,A 30.0,B 90.0,C 30.0,S 2,T 2}\n"


def test_ur_metres_written_with_enough_decimals(tmp_path):
    prog = read_program(_write(tmp_path, "zelle4.script"))
    t = prog.target("movej@9")
    text, _ = updated_text(prog, {"movej@9": t.joints + [0.0, 0.0, 0.0, 0.0, 0.0, 1e-4]})
    assert "movej([-0.35, -1.9, 2.1, -1.77, -1.5708, 0.42010], a=1.4" in text
    wp = prog.target("Waypoint_1_p")
    T = wp.T_frame_tcp.copy()
    T[:3, 3] += [0.25, 0.0, 0.0]  # mm
    text, _ = updated_text(prog, {"Waypoint_1_p": T})
    assert "global Waypoint_1_p=p[.45235, -.1903, .3012, 0.0, 3.1416, 0.0]" in text


def test_write_program_refuses_the_input_and_existing_files(tmp_path):
    path = _write(tmp_path, "zelle4.mod")
    prog = read_program(path)
    with pytest.raises(ValueError, match="input program"):
        write_program(prog, {}, path)
    with pytest.raises(ValueError, match="input program"):
        write_program(prog, {}, tmp_path / "." / "zelle4.mod", overwrite=True)
    (tmp_path / "taken.mod").write_text("x")
    with pytest.raises(FileExistsError):
        write_program(prog, {}, tmp_path / "taken.mod")
    assert (tmp_path / "taken.mod").read_text() == "x"
    with pytest.raises(KeyError, match="no target 'pNix'"):
        write_program(prog, {"pNix": np.eye(4)}, tmp_path / "new.mod")
    with pytest.raises(ValueError, match="expected 6 joint values"):
        write_program(prog, {"jHome": np.zeros(5)}, tmp_path / "new.mod")
    assert not (tmp_path / "new.mod").exists()


# ---------------------------------------------------------------------------------------------
# malformed declarations
# ---------------------------------------------------------------------------------------------


@pytest.mark.parametrize("fmt, text, line, needle", [
    ("krl", "DEFDAT x\nDECL E6POS XP1={X 1.0,Y 2.0,Z 3.0,A 0.0,C 0.0,S 2,T 2}\n", 2,
     "missing component(s) B (expected X, Y, Z, A, B, C)"),
    ("krl", "DECL E6POS XP1={X 1.0,Y abc,Z 3.0,A 0.0,B 0.0,C 0.0}\n", 1, "'abc' is not a number (component Y)"),
    ("krl", "\n\nDECL E6AXIS XH={A1 0.0,A2 -90.0,A3 90.0\n", 3, "expected '}' closing the aggregate"),
    ("krl", "DECL POS P1={X 1.0,Y 2.0,Z 3.0,A 0.0,B 0.0,C 0.0,E1 5.0}\n", 1, "unknown component E1"),
    ("rapid", "MODULE M\n CONST robtarget p1:=[[1,2,3],[1,0,0,0],[0,0,0,0]];\nENDMODULE\n", 2,
     "expected [[x,y,z],[q1,q2,q3,q4],[cf1,cf4,cf6,cfx],[eax_a,...,eax_f]]"),
    ("rapid", "MODULE M\n\n CONST robtarget p1:=[[1,2,3],[1,0,0.5,0],[0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]];\n", 3,
     "has norm 1.11803; expected a unit quaternion"),
    ("rapid", "MODULE M\n CONST jointtarget j1:=[[0,0,x,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]];\n", 2,
     "'x' is not a number"),
    ("rapid", "MODULE M\n CONST jointtarget j1:=[[0,0,0,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]]\n ENDMODULE", 2,
     "expected ';' after the aggregate"),
    ("fanuc", "/POS\nP[1]{\n   GP1:\n\tUF : 0, UT : 1,\n\tX = 1.0 mm, Y = 2.0 mm, Z = 3.0 mm,\n"
              "\tW = 0.0 deg, P = 0.0 deg\n};\n/END\n", 2, "missing R"),
    ("fanuc", "/POS\nP[1]{\n   GP1:\n\tUF : 0, UT : 1,\n\tX = 1.0 mm, Y = 2.0, Z = 3.0 mm,\n"
              "\tW = 0.0 deg, P = 0.0 deg, R = 0.0 deg\n};\n/END\n", 5, "expected a number followed by mm or deg"),
    ("fanuc", "/POS\nP[1]{\n   GP1:\n\tUF : 0, UT : 1,\n\tJ1= 0.0 deg\nP[2]{\n   GP1:\n\tJ1= 0.0 deg\n};\n/END\n",
     2, "expected '};' closing the position"),
    ("urscript", "def f():\n  movel(p[0.1, 0.2, 0.3, 0.0, 3.14], a=1.2)\nend\n", 2, "5 values; expected 6"),
])
def test_malformed_declarations_name_line_and_expectation(fmt, text, line, needle):
    with pytest.raises(FileFormatError) as info:
        parse_program(text, fmt, path=f"prog.{fmt}")
    err = info.value
    assert err.path == f"prog.{fmt}" and err.line == line, str(err)
    assert needle in str(err)
    assert str(err).startswith(f"prog.{fmt}, line {line}")


def test_unknown_suffix_asks_for_the_format(tmp_path):
    path = tmp_path / "prog.txt"
    path.write_text("movel(p[0.1, 0.2, 0.3, 0.0, 3.14, 0.0])\n")
    with pytest.raises(ValueError, match="pass format="):
        read_program(path)
    assert read_program(path, format="urscript").names == ("movel@1",)


# ---------------------------------------------------------------------------------------------
# helpers
# ---------------------------------------------------------------------------------------------


@pytest.mark.parametrize("value, original, minimum, expected", [
    (1200.27, "1200", 2, "1200.27"),
    (1200.2749, "1200.0", 2, "1200.27"),
    (-0.0004, ".000", 0, ".000"),
    (-0.25, ".000", 0, "-.250"),
    (0.4523, "-.1903", 0, ".4523"),
    (9.0e9, "9E+09", 0, "9E+09"),
    (1.5, "+1.0", 0, "+1.5"),
    (-1e-9, "-0.0", 0, "-0.0"),
    (-1e-9, "0.0", 0, "0.0"),
])
def test_format_like(value, original, minimum, expected):
    assert format_like(value, original, minimum) == expected


def test_mask_keeps_offsets_and_line_breaks():
    text = 'A 1 ; note "x"\r\nB "s;t" 2 ; c\nC'
    masked = mask(text, ";")
    assert len(masked) == len(text)
    assert masked.splitlines() == ["A 1           ", "B       2    ", "C"]
    assert masked.count("\r\n") == 1


def test_same_pose_through_transforms_matches_parsed_pose(tmp_path):
    prog = read_program(_write(tmp_path, "zelle4.ls"))
    p2 = prog.target("P[2]")
    np.testing.assert_allclose(p2.T_frame_tcp, transform_from_pose(p2.values, "fanuc_wpr"), atol=0)
