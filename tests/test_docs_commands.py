"""The command-line session in docs/calibration.md runs as written, with the targets file and the
UR program shown there (issue 10: the documented example used to fail)."""

from __future__ import annotations

import os
import re
import shlex
from pathlib import Path

from click.testing import CliRunner

from robocal.cli import main

DOC = Path(__file__).resolve().parents[1] / "docs" / "calibration.md"


def _blocks(text, section):
    part = text[text.index(section):]
    part = part[:part.index("\n## ", 1)] if "\n## " in part[1:] else part
    return re.findall(r"```(\w*)\n(.*?)```", part, re.S)


def test_command_line_session_in_the_docs_runs(tmp_path):
    text = DOC.read_text(encoding="utf-8")
    blocks = _blocks(text, "## Command line")
    commands = [ln for ln in blocks[0][1].splitlines() if ln.startswith("robocal ")]
    (tmp_path / "cell.script").write_text(blocks[1][1], encoding="utf-8")
    (tmp_path / "targets.csv").write_text(blocks[2][1], encoding="utf-8")
    assert len(commands) == 5
    cwd = os.getcwd()
    os.chdir(tmp_path)
    try:
        for line in commands:
            r = CliRunner().invoke(main, shlex.split(line)[1:])
            assert r.exit_code == 0, (line, r.output)
    finally:
        os.chdir(cwd)
    corrected = (tmp_path / "corrected.csv").read_text()
    assert "P1" in corrected and "not reached" not in corrected
    new_script = (tmp_path / "cell_corrected.script").read_text()
    assert new_script != blocks[1][1] and new_script.count("\n") == blocks[1][1].count("\n")
