"""docs/tutorial.md runs as written: its ``bash`` blocks (``robocal ...`` lines) through the command
line and its ``python`` blocks in one namespace, in order, in an empty folder."""

import os
import re
import shlex
from pathlib import Path

from click.testing import CliRunner

from robocal.cli import main

DOC = Path(__file__).resolve().parents[1] / "docs" / "tutorial.md"


def test_tutorial_runs(tmp_path, capsys):
    blocks = re.findall(r"```(bash|python)\n(.*?)```", DOC.read_text(encoding="utf-8"), re.S)
    assert sum(kind == "python" for kind, _ in blocks) >= 5
    namespace = {"__name__": "tutorial"}
    cwd = os.getcwd()
    os.chdir(tmp_path)
    try:
        for kind, code in blocks:
            if kind == "bash":
                for line in code.splitlines():
                    if line.startswith("robocal "):
                        r = CliRunner().invoke(main, shlex.split(line)[1:])
                        assert r.exit_code == 0, (line, r.output)
            else:
                exec(compile(code, str(DOC), "exec"), namespace)  # noqa: S102 - the tutorial's own code
    finally:
        os.chdir(cwd)
    out = capsys.readouterr().out
    assert "InputFileError" in out and "'result.json'" in out and "reached: True" in out
    assert (tmp_path / "calibration" / "calibrated_robot.toml").is_file()
