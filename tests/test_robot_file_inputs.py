"""Issue 29: robot files. A truncated file (fewer [[joints]] than its controller_joints) is refused
instead of becoming a robot with fewer joints; a UTF-8 BOM is accepted; a .urdf robot loads
wherever a robot file is accepted (load_robot, the command line)."""

from __future__ import annotations

import numpy as np
import pytest
from click.testing import CliRunner

from robocal.cli.main import main
from robocal.io.urdf import write_urdf
from robocal.robots import RobotFileError, load_robot
from robocal.robots.loader import robot_path


def _ur10_text():
    return robot_path("ur10").read_text(encoding="utf-8")


def test_a_truncated_robot_file_is_refused_naming_the_missing_joints(tmp_path):
    text = _ur10_text()
    first = text.index("[[joints]]")
    (tmp_path / "trunc.toml").write_text(text[:text.index("[[joints]]", first + 1)])
    with pytest.raises(RobotFileError, match=r"'J2', 'J3', 'J4', 'J5', 'J6' drive no joint .* truncated"):
        load_robot(tmp_path / "trunc.toml")
    r = CliRunner().invoke(main, ["fk", str(tmp_path / "trunc.toml"), "0", "0", "0", "0", "0", "0"])
    assert r.exit_code == 1 and "truncated robot file" in r.output and "Traceback" not in r.output


def test_a_robot_file_with_a_utf8_bom_loads(tmp_path):
    (tmp_path / "bom.toml").write_text(_ur10_text(), encoding="utf-8-sig")
    assert (tmp_path / "bom.toml").read_bytes()[:3] == b"\xef\xbb\xbf"
    m = load_robot(tmp_path / "bom.toml")
    q = np.radians([[10.0, -20.0, 30.0, 40.0, 50.0, 60.0]])
    assert np.allclose(m.fk(q), load_robot("ur10").fk(q), atol=1e-9)


def test_a_urdf_robot_loads_wherever_a_robot_file_is_accepted(tmp_path):
    ur10 = load_robot("ur10")
    write_urdf(ur10, tmp_path / "ur10.urdf")
    m = load_robot(tmp_path / "ur10.urdf")
    q = np.radians([[10.0, -20.0, 30.0, 40.0, 50.0, 60.0]])
    assert m.kind == "urdf" and np.allclose(m.fk(q), ur10.fk(q), atol=1e-6)
    r = CliRunner().invoke(main, ["fk", str(tmp_path / "ur10.urdf"), "10", "-20", "30", "40", "50", "60", "--deg"])
    assert r.exit_code == 0, r.output
    (tmp_path / "bad.urdf").write_text("<robot name='x'><joint name='j'/></robot>")
    r = CliRunner().invoke(main, ["fk", str(tmp_path / "bad.urdf"), "0"])
    assert r.exit_code == 1 and "bad.urdf" in r.output and "Traceback" not in r.output
