"""Issue 29: every error names its cause. The unclear cases of the issue get one `Error:` line (or
click's usage line) naming the option or file; a missing optional dependency names the extra to
install; a closed pipe (`robocal ... | head`) ends quietly."""

from __future__ import annotations

import subprocess
import sys

import pytest
from click.testing import CliRunner

from robocal.cli.main import main


def run(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


@pytest.mark.parametrize("args, words", [
    (("tcp", "simulate", "--beta", "0", "--collisions", "1"), ["--beta", "84"]),
    (("tcp", "simulate", "--beta", "180", "--collisions", "1"), ["--beta"]),
    (("tcp", "simulate", "--tilt", "89", "--collisions", "1"), ["--tilt", "10"]),
    (("plan-poses", "ur10", "--count", "10", "--noise", "-0.02", "--out", "x.csv"), ["--noise"]),
    (("plan-poses", "ur10", "--count", "10", "--tracker-at", "2500;0;500", "--out", "x.csv"),
     ["--tracker-at", "three numbers", "2500;0;500"]),
])
def test_unclear_errors_now_name_the_option(tmp_path, monkeypatch, args, words):
    monkeypatch.chdir(tmp_path)
    r = run(*args)
    assert r.exit_code in (1, 2), r.output
    assert "unexpected" not in r.output and "bug in robocal" not in r.output and "Traceback" not in r.output
    for w in words:
        assert w in r.output, (w, r.output)


@pytest.mark.parametrize("module, extra, args", [
    ("cv2", "camera", ["camera", "calibrate", "IMAGES", "--board", "charuco:9x7:30mm:22mm:DICT_5X5_100", "--out", "OUT"]),
    ("yaml", "yaml", ["handeye", "solve", "CAL_DATA", "--out", "OUT"]),
])
def test_a_missing_extra_names_the_extra(tmp_path, monkeypatch, module, extra, args):
    (tmp_path / "imgs").mkdir()
    (tmp_path / "imgs" / "a.png").write_bytes(b"\x89PNG\r\n\x1a\n")
    (tmp_path / "cal_data.yaml").write_text("data: []\n")
    paths = {"IMAGES": tmp_path / "imgs", "CAL_DATA": tmp_path / "cal_data.yaml", "OUT": tmp_path / "out"}
    args = [str(paths[a]) if a in paths else a for a in args]
    monkeypatch.setitem(sys.modules, module, None)  # as if not installed
    r = CliRunner().invoke(main, args)
    assert r.exit_code == 1, r.output
    assert f"pip install 'robocal[{extra}]'" in r.output and "bug in robocal" not in r.output


def test_a_closed_pipe_ends_quietly():
    """`robocal robots | head -0` and `robocal fk ... | head -0`: exit 0, nothing on stderr."""
    code = ("import sys; from robocal.cli.main import main; sys.argv = ['robocal'] + sys.argv[1:]; main()")
    for args in (["robots"], ["fk", "ur10", "0", "0", "0", "0", "0", "0"]):
        p = subprocess.Popen([sys.executable, "-c", code, *args], stdout=subprocess.PIPE, stderr=subprocess.PIPE)
        p.stdout.close()  # the reader is gone before the command writes a line
        err = p.stderr.read().decode()
        assert p.wait(timeout=60) == 0, err
        assert "Error" not in err and "Traceback" not in err and "Broken pipe" not in err, err
