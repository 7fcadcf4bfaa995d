"""Issue 10, item 7: the README's user path (plan -> measure -> import -> calibrate -> correct a
program) runs as written, with a simulated tracker standing in for the measurement."""

import shlex
from pathlib import Path

import numpy as np
from click.testing import CliRunner

from robocal.cli import main
from robocal.io.programs import read_joint_program, read_program
from robocal.robots import load_robot
from robocal.sim import LaserTracker, VirtualRobot

README = Path(__file__).resolve().parent.parent / "README.md"


def user_path_commands():
    text = README.read_text(encoding="utf-8")
    block = text.split("# a whole user path", 1)[1].split("# end of the user path", 1)[0]
    return [shlex.split(line.split("#", 1)[0]) for line in block.splitlines()[1:] if line.strip()]


def measure(d: Path):
    """What the user does between plan and import: the planned poses measured (simulated)."""
    model = load_robot("ur10")
    q = read_joint_program(d / "poses.csv", model).joints
    rng = np.random.default_rng(4)
    virtual = VirtualRobot.perturbed(model, rng)
    meas = LaserTracker.placed(rng, 1, sigma_mm=0.02).measure(virtual, q, rng)
    lines = ["Leica Tracker Pilot export", "Einheit: m", "", "Name;X [m];Y [m];Z [m]"]
    lines += [f"P{i + 1:03d};" + ";".join(f"{v / 1000:.9f}".replace(".", ",") for v in p)
              for i, p in enumerate(meas.points[:, 0])]
    (d / "leica.csv").write_bytes(("\r\n".join(lines) + "\r\n").encode("latin-1"))
    log = ["id,A1,A2,A3,A4,A5,A6"] + [f"{i + 1}," + ",".join(f"{v:.10f}" for v in np.degrees(qi))
                                      for i, qi in enumerate(q)]
    (d / "log.csv").write_text("\n".join(log) + "\n", encoding="utf-8")
    T = model.replace(T_world_base=np.eye(4)).fk(np.radians([[20.0, -100.0, 80.0, -60.0, -90.0, 0.0],
                                                             [-30.0, -80.0, 100.0, -100.0, -90.0, 30.0]]))
    from robocal.transforms import rotvec_from_matrix

    moves = [f"  movel(p[{', '.join(f'{v:.6f}' for v in np.r_[t[:3, 3] / 1000, rotvec_from_matrix(t[:3, :3])])}], "
             "a=1.2, v=0.25)" for t in T]
    (d / "pick.script").write_text("def pick():\n  # pick cycle\n" + "\n".join(moves) + "\nend\n", encoding="utf-8")


def test_readme_user_path_runs_as_written(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    cmds = user_path_commands()
    assert [c[1] for c in cmds] == ["plan-poses", "import", "calibrate", "correct"]
    for cmd in cmds:
        assert cmd[0] == "robocal"
        r = CliRunner().invoke(main, cmd[1:])
        assert r.exit_code == 0, (cmd, r.output)
        if cmd[1] == "plan-poses":
            measure(tmp_path)
        if cmd[1] == "calibrate":
            assert "held-out poses, after" in r.output
    new = read_program(tmp_path / "pick_corrected.script")
    old = read_program(tmp_path / "pick.script")
    shift = [np.linalg.norm(a.T_frame_tcp[:3, 3] - b.T_frame_tcp[:3, 3]) for a, b in zip(old.targets, new.targets)]
    assert len(shift) == 2 and min(shift) > 0.1  # the calibrated robot differs from nominal by tenths of a mm
