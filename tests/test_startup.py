"""Start-up stays light: the command group and commands that need no kernels import no numba."""

import subprocess
import sys

import pytest

_PROBE = """
import sys
from click.testing import CliRunner
import robocal.cli
after_import = sorted(m for m in ("numba", "scipy", "matplotlib") if m in sys.modules)
result = CliRunner().invoke(robocal.cli.main, {args!r})
assert result.exit_code == 0, result.output
after_command = sorted(m for m in ("numba", "scipy", "matplotlib") if m in sys.modules)
print(after_import, after_command)
"""


def _heavy_modules(args):
    out = subprocess.run([sys.executable, "-c", _PROBE.format(args=args)], capture_output=True, text=True, check=True)
    return out.stdout.strip()


@pytest.mark.parametrize("args", [["--help"], ["robots"], ["history", "--help"], ["calibrate", "--help"],
                                  ["closed-chain", "calibrate", "--help"]])
def test_cli_start_imports_no_numba_scipy_matplotlib(args):
    assert _heavy_modules(args) == "[] []"


def test_help_lists_every_command_with_its_whole_summary():
    from click.testing import CliRunner

    from robocal.cli import main
    from robocal.cli.main import _COMMANDS

    out = CliRunner().invoke(main, ["--help"]).output
    for name, (_, _, summary, _) in _COMMANDS.items():
        assert f"{name} " in out and summary in out


def test_loading_a_robot_imports_no_numba():
    probe = "import sys; from robocal.robots import load_robot; load_robot('ur10'); print('numba' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"


@pytest.mark.parametrize("args", [["--help"], ["fleet", "--help"], ["fleet", "calibrate", "--help"],
                                  ["fleet", "study", "monte-carlo", "--help"]])
def test_help_imports_no_dask(args):
    """dask.distributed (the fleet extra) is imported only when a fleet command runs."""
    probe = ("import sys\nfrom click.testing import CliRunner\nimport robocal.cli\n"
             f"r = CliRunner().invoke(robocal.cli.main, {args!r})\nassert r.exit_code == 0, r.output\n"
             "print(sorted(m for m in ('dask', 'distributed', 'numba', 'matplotlib') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"
