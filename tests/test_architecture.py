"""Architecture contracts (docs/architecture.md): the import-linter contracts in pyproject.toml
hold for the package, they do fail on a deliberately wrong import, and ruff's stated rule set is
clean. These run in CI with the rest of the suite, so a layering violation fails the build."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
BIN = Path(sys.executable).parent


def _tool(name: str) -> str:
    path = BIN / name
    if not path.exists():
        found = shutil.which(name)
        if found is None:
            pytest.fail(f"{name} is not installed: it is part of the 'test' extra (pip install -e '.[test]')")
        return found
    return str(path)


def _lint_imports(cwd: Path, pythonpath: Path) -> subprocess.CompletedProcess:
    env = dict(os.environ, PYTHONPATH=str(pythonpath))
    return subprocess.run([_tool("lint-imports"), "--config", str(cwd / "pyproject.toml"), "--no-cache"],
                          cwd=cwd, env=env, capture_output=True, text=True, timeout=300)


def test_import_contracts_hold():
    run = _lint_imports(ROOT, ROOT / "src")
    assert run.returncode == 0, run.stdout + run.stderr
    assert "0 broken" in run.stdout


@pytest.mark.parametrize("module, line, expected", [
    ("calib/__init__.py", "import matplotlib  # deliberate violation\n", "robocal.calib is not allowed to import matplotlib"),
    ("kinematics/__init__.py", "from ..io import header  # deliberate violation\n",
     "robocal.kinematics is not allowed to import robocal.io"),
    ("io/__init__.py", "from .. import workflows  # deliberate violation\n",
     "robocal.io is not allowed to import robocal.workflows"),
])
def test_contracts_fail_on_a_wrong_import(tmp_path, module, line, expected):
    """A copy of the package with one wrong import added must break a contract, named in the output."""
    shutil.copytree(ROOT / "src" / "robocal", tmp_path / "src" / "robocal",
                    ignore=shutil.ignore_patterns("__pycache__"))
    shutil.copy(ROOT / "pyproject.toml", tmp_path / "pyproject.toml")
    target = tmp_path / "src" / "robocal" / module
    target.write_text(target.read_text(encoding="utf-8") + line, encoding="utf-8")
    run = _lint_imports(tmp_path, tmp_path / "src")
    assert run.returncode != 0, run.stdout
    assert expected in run.stdout.replace("\n", " ")


def test_ruff_rule_set_is_clean():
    run = subprocess.run([_tool("ruff"), "check", "--no-cache", "src", "tests", "benchmarks"],
                         cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stdout + run.stderr
