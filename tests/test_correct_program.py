"""Issue 10, item 3: ``robocal correct MODEL PROGRAM --out NEW_PROGRAM`` writes the same program with
corrected targets (only their numbers change) and a per-target report; the corrected targets put
the calibrated robot where the nominal program meant it to go."""

import csv

import numpy as np
from click.testing import CliRunner

from robocal.cli import main
from robocal.io.programs import read_program
from robocal.kinematics.ik import ik_numeric
from robocal.robots import load_robot, save_robot
from robocal.sim import VirtualRobot
from robocal.transforms import euler_from_matrix

ROBOT = "kuka_kr150_r3100"
Q_CART = np.radians([[10.0, -80.0, 100.0, 5.0, 40.0, 20.0], [-25.0, -60.0, 85.0, -30.0, 60.0, -10.0]])
Q_JOINT = np.radians([15.0, -70.0, 95.0, 10.0, 30.0, 0.0])


def e6pos(name, T, s, t):
    a, b, c = np.degrees(euler_from_matrix(T[:3, :3], "kuka_abc"))
    x, y, z = T[:3, 3]
    return (f"DECL E6POS {name}={{X {x:.3f},Y {y:.3f},Z {z:.3f},A {a:.4f},B {b:.4f},C {c:.4f},S {s},T {t},"
            "E1 0.0,E2 0.0,E3 0.0,E4 0.0,E5 0.0,E6 0.0}")


def krl_program(nominal):
    T = nominal.replace(T_world_base=np.eye(4)).fk(Q_CART)
    j = np.degrees(Q_JOINT)
    # S 2 (front, elbow up, A5 > 0); T: bit i set when A(i+1) < 0 (KUKA's status and turn)
    lines = ["&ACCESS RVP", "DEFDAT zelle ; Messpunkte, Kommentar bleibt", e6pos("XP1", T[0], 2, 2),
             "DECL FDAT FP1={TOOL_NO 0,BASE_NO 0,IPO_FRAME #BASE}", e6pos("XP2", T[1], 2, 0b101011),
             "DECL E6POS XFAR={X 9000.0,Y 0.0,Z 500.0,A 0.0,B 90.0,C 0.0,S 2,T 35}  ; out of reach",
             "DECL E6AXIS XHOME={" + ",".join(f"A{i + 1} {v:.4f}" for i, v in enumerate(j))
             + ",E1 0.0,E2 0.0,E3 0.0,E4 0.0,E5 0.0,E6 0.0}", "ENDDAT", ""]
    return "\r\n".join(lines)


def test_correct_a_krl_program(tmp_path):
    nominal = load_robot(ROBOT)
    true = VirtualRobot.perturbed(nominal, np.random.default_rng(8)).true_model
    model = save_robot(true.replace(T_world_base=np.eye(4)), tmp_path / "cal.toml")
    src = tmp_path / "zelle.dat"
    src.write_bytes(krl_program(nominal).encode("latin-1"))
    before = src.read_bytes()
    r = CliRunner().invoke(main, ["correct", str(model), str(src), "--out", str(tmp_path / "zelle_corr.dat")])
    assert r.exit_code == 5, r.output  # XFAR is not reached (exit 5: targets not reached)
    assert src.read_bytes() == before
    assert "2/4 targets corrected, 1 joint target(s) kept" in r.output and "not reached" in r.output
    out = (tmp_path / "zelle_corr.dat").read_bytes().decode("latin-1").split("\r\n")
    old = before.decode("latin-1").split("\r\n")
    changed = [i for i, (a, b) in enumerate(zip(old, out)) if a != b]
    assert len(out) == len(old) and changed == [2, 4]  # XP1, XP2; comments, FDAT, XFAR, taught XHOME unchanged
    prog = read_program(tmp_path / "zelle_corr.dat")
    base = nominal.replace(T_world_base=np.eye(4))
    T_meant = base.fk(Q_CART)
    for k, name in enumerate(("XP1", "XP2")):
        T_new = prog.target(name).T_frame_tcp
        assert np.linalg.norm(T_new[:3, 3] - T_meant[k, :3, 3]) > 0.3  # a real correction
        q = np.atleast_2d(ik_numeric(base, T_new[None], Q_CART[k][None]).q)[0]  # what the controller commands
        reached = true.replace(T_world_base=np.eye(4)).fk(q)
        assert np.linalg.norm(reached[:3, 3] - T_meant[k, :3, 3]) < 0.05
    assert np.array_equal(prog.target("XHOME").joints, read_program(src).target("XHOME").joints)
    with open(tmp_path / "zelle_corr.dat.report.csv", newline="") as f:
        rows = list(csv.DictReader(line for line in f if not line.startswith("#")))
    status = {row["target"]: row["status"] for row in rows}
    assert status == {"XP1": "corrected", "XP2": "corrected", "XFAR": "not reached", "XHOME": "kept"}
    assert float(next(r_ for r_ in rows if r_["target"] == "XP1")["cartesian_correction_mm"]) > 0.3
    again = CliRunner().invoke(main, ["correct", str(model), str(src), "--out", str(src)])
    assert again.exit_code == 1 and "Error:" in again.output
