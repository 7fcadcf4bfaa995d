"""The numpy kernels agree with the compiled ones, and a small command runs without numba (issue 34 item 2).

Every shipped robot (DH, MDH, Hayati beta, URDF-style, prismatic joints, trees with several end
effectors): target points and their Jacobian (subsets of free parameters, points on different end
effectors, a moved base), the spatial twists, forward kinematics of every end effector, the link
frames and the one-pose FK, each computed by both implementations (to 1e-9 mm / 1e-12 rad:
rounding differs, the arithmetic is the same).
"""

import subprocess
import sys

import numpy as np
import pytest

from robocal.kinematics import _backend
from robocal.kinematics._backend_agreement import backend_difference, every_kernel_output
from robocal.robots import list_robots, load_robot


@pytest.fixture
def kernels_mode():
    def use(mode):
        _backend.set_kernels(mode)

    yield use
    _backend.set_kernels("auto")


_everything = every_kernel_output


@pytest.mark.parametrize("name", list_robots())
def test_numpy_kernels_equal_compiled(name, kernels_mode):
    results = backend_difference(load_robot(name), seed=3)
    for a, b in zip(results["compiled"], results["numpy"]):
        assert a.shape == b.shape
        np.testing.assert_allclose(b, a, rtol=0, atol=1e-9)


def test_numpy_kernels_in_blocks_equal_one_block(kernels_mode, monkeypatch):
    from robocal.kinematics import _numpy_kernels

    model = load_robot("dlr_justin19")
    kernels_mode("numpy")
    whole = _everything(model, np.random.default_rng(5))
    monkeypatch.setattr(_numpy_kernels, "BLOCK", 7)  # 23 poses: blocks of 7, 7, 7, 2
    blocked = _everything(model, np.random.default_rng(5))
    for a, b in zip(whole, blocked):
        np.testing.assert_allclose(b, a, rtol=0, atol=1e-12)


def test_one_pose_fk_refuses_a_non_finite_joint_in_both(kernels_mode):
    model = load_robot("ur10")
    q = np.array([0.1, np.nan, 0.3, 0.0, 0.2, 0.0])
    for mode in ("compiled", "numpy"):
        kernels_mode(mode)
        with pytest.raises(ValueError):
            model.fk(q)


def test_a_kernel_switches_to_compiled_when_the_work_pays(kernels_mode, monkeypatch):
    from robocal.kinematics import _numpy_kernels

    kernels_mode("auto")
    monkeypatch.setattr(_backend, "_spent", dict.fromkeys(_backend.NUMPY_COST_S, 0.0))
    monkeypatch.setattr(_backend, "_switched", set())
    assert _backend.kernel("target_points", 80) is _numpy_kernels.target_points
    big = int(_backend.CALL_MAX_S / _backend.NUMPY_COST_S["target_points"][1]) + 1
    assert _backend.kernel("target_points", big) is not _numpy_kernels.target_points  # one large call
    assert _backend.kernel("target_points", 1) is not _numpy_kernels.target_points  # and from then on
    calls = 0
    while _backend.kernel("op_twists", 1) is _numpy_kernels.op_twists:  # many small calls
        calls += 1
    per_call = sum(_backend.NUMPY_COST_S["op_twists"])
    assert calls == pytest.approx(_backend.BUDGET_S / per_call, abs=1)
    assert _backend.compiled_kernels() == {"target_points", "op_twists"}
    assert _backend.use_compiled("op_twists") and not _backend.use_compiled("fk_fused_into", 10)
    with pytest.raises(ValueError):
        _backend.set_kernels("fast")


def test_a_small_calibration_imports_no_numba(tmp_path):
    """The cold-start target: ``robocal calibrate`` of 100 poses compiles nothing (numpy kernels)."""
    from click.testing import CliRunner

    from robocal.cli import main

    r = CliRunner().invoke(main, ["simulate", "tracker", "abb_irb140", "--poses", "100",
                                  "--out", str(tmp_path / "m.csv")])
    assert r.exit_code == 0, r.output
    probe = ("import sys\nfrom click.testing import CliRunner\nimport robocal.cli\n"
             f"r = CliRunner().invoke(robocal.cli.main, ['calibrate', 'abb_irb140', {str(tmp_path / 'm.csv')!r}, "
             f"'--out', {str(tmp_path / 'out')!r}, '--no-report'])\nassert r.exit_code == 0, r.output\n"
             "print('numba' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, check=True,
                         env={**__import__("os").environ, "ROBOCAL_KERNELS": "auto"})
    assert out.stdout.strip() == "False"
