"""The numpy kernels agree with the compiled ones, a small command and a big calibration run without
numba, and the switch to compiled code follows the saving-pays-for-the-load policy of
``robocal.kinematics._backend`` (issue 34 items 2 and 4; decided by counts and estimates, not timings).

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


@pytest.fixture
def fresh_policy(kernels_mode, monkeypatch):
    """Auto mode with nothing counted and nothing switched (restored afterwards)."""
    kernels_mode("auto")
    monkeypatch.setattr(_backend, "_saved", dict.fromkeys(_backend.COST_S, 0.0))
    monkeypatch.setattr(_backend, "_switched", set())
    monkeypatch.setattr(_backend, "_price", dict.fromkeys(_backend.COST_S, _backend.KERNEL_LOAD_S))  # as if cached


def _saving(name, work):
    t_numpy, t_compiled = _backend.estimate(name, work)
    return t_numpy - t_compiled


def test_small_calls_load_compiled_code_once_it_has_paid_for_its_load(fresh_policy):
    from robocal.kinematics import _numpy_kernels

    calls = 0
    while _backend.kernel("op_twists", 15) is _numpy_kernels.op_twists:  # the demo's thermal simulation
        calls += 1
    assert calls == pytest.approx(_backend.LOAD_S / _saving("op_twists", 15), abs=1)
    assert _backend.use_compiled("op_twists", 1)  # and from then on
    # compiled code is loaded: another kernel pays only its own load (a few calls)
    calls = 0
    while not _backend.use_compiled("fk_fused_into", 100):
        calls += 1
    assert calls == pytest.approx(_backend.KERNEL_LOAD_S / _saving("fk_fused_into", 100), abs=1)
    assert _backend.compiled_kernels() == {"op_twists", "fk_fused_into"}
    # a kernel not in numba's cache (the first run after installing) must save a compile's worth
    _backend._price["target_points"] = _backend.KERNEL_COMPILE_S
    for _ in range(int(_backend.KERNEL_COMPILE_S / _saving("target_points", 100)) - 1):
        assert not _backend.use_compiled("target_points", 100)
    with pytest.raises(ValueError):
        _backend.set_kernels("fast")


def test_big_batches_stay_in_numpy(fresh_policy):
    """A calibration's blocks of normal equations (and big target-point batches generally) run within
    MIN_SPEEDUP of compiled code in numpy: however many there are, they do not load ~105 MiB of numba."""
    from robocal.calib._normal import POSE_BLOCK

    assert _backend.estimate("target_points", POSE_BLOCK)[0] < _backend.MIN_SPEEDUP * _backend.estimate(
        "target_points", POSE_BLOCK)[1]
    for _ in range(100_000):  # ~400 s of estimated numpy time
        assert not _backend.use_compiled("target_points", POSE_BLOCK)
    assert not _backend.compiled_kernels()
    # a single call that saves more than the load on its own runs compiled (a forward kinematics of 2 M poses)
    per_pose = _saving("fk_fused_into", 2) - _saving("fk_fused_into", 1)
    big = int(_backend.LOAD_S / per_pose) + 1
    assert not _backend.use_compiled("fk_fused_into", big // 3)
    assert _backend.use_compiled("fk_fused_into", big)
    # once loaded, the big batches switch too: one more kernel costs ~5 ms, a few blocks' savings
    calls = 0
    while not _backend.use_compiled("target_points", POSE_BLOCK):
        calls += 1
    assert calls == int(_backend.KERNEL_LOAD_S / _saving("target_points", POSE_BLOCK))


def test_the_mode_overrides_the_policy(fresh_policy, kernels_mode):
    kernels_mode("numpy")
    assert not _backend.use_compiled("fk_fused_into", 10**9)
    kernels_mode("compiled")
    assert _backend.use_compiled("fk_fused_single_checked")
    assert not _backend.compiled_kernels()  # nothing counted or switched by either mode
    kernels_mode("auto")
    assert _backend.use_compiled("fk_fused_into", 10**9)
    kernels_mode("numpy")  # a kernel auto switched earlier in the process runs numpy when numpy is asked for
    assert not _backend.use_compiled("fk_fused_into", 1)


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


def test_a_big_calibration_imports_no_numba(tmp_path):
    """Issue 34 item 4: a calibration of 12 000 poses (blocks of 4 096 poses, where the numpy kernels run
    within 2x of compiled ones) loads no numba either: its ~105 MiB would be ~9 KiB per pose here."""
    from robocal.sim import LaserTracker, VirtualRobot

    rngs = [np.random.default_rng(s) for s in (1, 2, 3)]
    robot = VirtualRobot.perturbed(load_robot("ur10"), rngs[0], joint_noise_deg=0.0)
    LaserTracker.placed(rngs[1], 1, sigma_mm=0.02).campaign(robot, 12_000, rngs[2], measurements_path=tmp_path / "m.csv",
                                                            cell=None)
    probe = ("import sys\nfrom robocal.cli.main import main\n"
             f"main(['calibrate', 'ur10', {str(tmp_path / 'm.csv')!r}, '--out', {str(tmp_path / 'out')!r}, '--no-report'], "
             "standalone_mode=False)\n"
             "from robocal.kinematics import _backend\nprint(sorted(_backend.compiled_kernels()), 'numba' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, check=True,
                         env={**__import__("os").environ, "ROBOCAL_KERNELS": "auto"})
    assert out.stdout.strip().splitlines()[-1] == "[] False"
    assert (tmp_path / "out" / "result.json").exists()


def test_programs_are_built_on_first_use_and_survive_pickling():
    """A model made only to be converted or written never builds the kernels' programs; the first
    forward kinematics builds them, and a pickled model (a fleet task's) computes the same poses."""
    import pickle

    from robocal.kinematics.model import _PROGRAM_ATTRIBUTES
    from robocal.robots import load_robot

    m = load_robot("ur10").with_params(load_robot("ur10").params.values + 1e-3)
    assert not _PROGRAM_ATTRIBUTES & set(vars(m))
    m2 = pickle.loads(pickle.dumps(m))
    q = np.random.default_rng(0).uniform(-2, 2, (5, 6))
    T = m.fk(q)
    assert _PROGRAM_ATTRIBUTES <= set(vars(m))
    np.testing.assert_allclose(m2.fk(q), T, rtol=0, atol=1e-9)
    with pytest.raises(AttributeError):
        m.no_such_attribute  # noqa: B018
