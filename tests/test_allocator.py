"""glibc's allocator thresholds in robocal's processes (robocal._allocator): fewer page faults in
repeated calibrations, and the user's own settings win."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap

import pytest

pytestmark = pytest.mark.skipif(not sys.platform.startswith("linux"), reason="glibc's mallopt: Linux only")

_LOOP = textwrap.dedent("""
    import json, os, resource, sys, tempfile
    from pathlib import Path
    import robocal._allocator as A
    applied = A.tune_allocator() if sys.argv[1] == "tune" else False
    from robocal.io.measurements import read_measurements
    from robocal.robots import load_robot
    from robocal.workflows.calibration.calibrate import compute_calibration
    from robocal.workflows.calibration.simulate import simulate_tracker
    d = Path(tempfile.mkdtemp())
    simulate_tracker("ur10", d / "m.csv", n_poses=100, noise_mm=0.02, seed=3)
    nominal = load_robot("ur10")
    meas = read_measurements(d / "m.csv", robot=nominal)
    def run():
        return compute_calibration(nominal, meas, robot_label="ur10", data_label="m.csv")
    run(); run()  # warm: kernels, caches
    f0 = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
    for _ in range(8):
        run()
    print(json.dumps({"applied": applied, "faults": resource.getrusage(resource.RUSAGE_SELF).ru_minflt - f0}))
""")


def _run(mode: str, **env) -> dict:
    e = {k: v for k, v in os.environ.items() if not k.startswith("MALLOC_") and k != "GLIBC_TUNABLES"}
    e.update(env)
    out = subprocess.run([sys.executable, "-c", _LOOP, mode], capture_output=True, text=True, env=e, timeout=300)
    assert out.returncode == 0, out.stderr[-2000:]
    return json.loads(out.stdout.strip().splitlines()[-1])


def _glibc() -> bool:
    import ctypes

    try:
        ctypes.CDLL(None).gnu_get_libc_version  # noqa: B018
    except AttributeError:
        return False
    return True


@pytest.mark.skipif(sys.platform.startswith("linux") and not _glibc(), reason="not glibc")
def test_tuned_allocator_removes_most_page_faults_of_repeated_calibrations():
    """8 calibrations of 100 poses: under glibc's dynamic thresholds each refaults megabytes the
    heap gave back (~2,600 faults a calibration measured); with the fixed thresholds almost none."""
    default = _run("default")
    tuned = _run("tune")
    assert tuned["applied"] is True
    assert default["faults"] > 4000, default  # the effect the setting is for is there at all
    assert tuned["faults"] < 0.25 * default["faults"], (tuned, default)


def test_users_own_settings_win():
    assert _run("tune", MALLOC_TRIM_THRESHOLD_="65536")["applied"] is False
    assert _run("tune", ROBOCAL_MALLOC="system")["applied"] is False


def test_cli_tunes_its_process():
    code = ("import sys; from robocal.cli.main import main\n"
            "try:\n    main(['robots'], standalone_mode=False)\nexcept SystemExit:\n    pass\n"
            "import robocal._allocator as A; print('APPLIED', A._applied)")
    e = {k: v for k, v in os.environ.items() if not k.startswith("MALLOC_") and k != "GLIBC_TUNABLES"}
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=e, timeout=120)
    assert out.returncode == 0, out.stderr[-2000:]
    assert f"APPLIED {_glibc()}" in out.stdout
