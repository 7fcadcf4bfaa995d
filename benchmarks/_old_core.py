"""The calibration core of an earlier commit, importable beside the current one (benchmarks only).

``load_old_core(rev)`` copies ``src/robocal/calib/{problem,solve,identifiability,initial}.py`` of
git revision ``rev`` into a temporary package ``_robocal_old_core_<rev>`` (relative imports of the
rest of robocal rewritten to absolute ones, so kinematics, transforms and the compiled kernels are
shared) and returns it: ``pkg.problem.CalibrationProblem``, ``pkg.solve.solve``. Used by
``bench_calibration.py --old-core`` to time the old and the new core in one process.
"""

from __future__ import annotations

import importlib
import re
import subprocess
import sys
import tempfile
from pathlib import Path

MODULES = ("problem", "solve", "identifiability", "initial")


def load_old_core(rev: str, repo: Path | None = None):
    repo = Path(repo or Path(__file__).resolve().parent.parent)
    sha = subprocess.run(["git", "-C", str(repo), "rev-parse", "--short", rev], check=True,
                         capture_output=True, text=True).stdout.strip()
    name = f"_robocal_old_core_{sha}"
    if name in sys.modules:
        return sys.modules[name]
    root = Path(tempfile.mkdtemp(prefix="robocal_old_core_"))
    pkg = root / name
    pkg.mkdir()
    (pkg / "__init__.py").write_text(f'"""robocal.calib core of {sha} (benchmark copy)."""\n')
    for m in MODULES:
        src = subprocess.run(["git", "-C", str(repo), "show", f"{sha}:src/robocal/calib/{m}.py"], check=True,
                             capture_output=True, text=True).stdout
        # "from ..x import y" (robocal) -> "from robocal.x import y"; "from .x" stays inside the copy
        src = re.sub(r"from \.\.(\w)", r"from robocal.\1", src)
        (pkg / f"{m}.py").write_text(src)
    sys.path.insert(0, str(root))
    try:
        mod = importlib.import_module(name)
        for m in MODULES:
            importlib.import_module(f"{name}.{m}")
    finally:
        sys.path.remove(str(root))
    mod.rev = sha
    return mod
