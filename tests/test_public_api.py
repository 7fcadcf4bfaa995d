"""The public facade (issue 26): ``robocal.__all__`` is exactly the documented names; a script using
only them calibrates a simulated campaign in memory (recovering the hidden truth within the
noise), catches a bad file as ``robocal.RobocalError``, and writes what ``robocal calibrate``
writes; the hand-eye and tool entries recover known transforms."""

import json
import subprocess
import sys

import numpy as np
import pytest
from click.testing import CliRunner

import robocal
import robocal.cli

PUBLIC = {
    "load_robot", "read_measurements", "calibrate", "CalibrationOptions", "CalibrationResult", "correct_targets",
    "CorrectionOptions", "calibrate_hand_eye", "HandEyeOptions", "HandEyeResult", "calibrate_tool", "ToolOptions",
    "RobocalError", "InputError", "InputFileError", "NotIdentifiableError", "NotConvergedError", "SanityGateError",
    "OutputExistsError", "RobocalWarning",
}


def test_all_lists_exactly_the_public_names():
    assert set(robocal.__all__) == PUBLIC and len(robocal.__all__) == len(PUBLIC)
    for name in robocal.__all__:
        assert getattr(robocal, name).__doc__, name
    from robocal import errors

    assert robocal.RobocalError is errors.RobocalError
    with pytest.raises(AttributeError):
        robocal.run_calibration  # noqa: B018


def test_import_robocal_loads_no_heavy_module():
    probe = ("import sys, robocal; robocal.CalibrationOptions; robocal.RobocalError; "
             "print(sorted(m for m in ('numba', 'scipy', 'matplotlib') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"


def test_options_are_frozen_with_defaults():
    o = robocal.CalibrationOptions()
    assert o.holdout == 0.2 and o.method == "lm" and o.noise_mm is None
    with pytest.raises(AttributeError):
        o.holdout = 0.5  # frozen


@pytest.fixture(scope="module")
def campaign(tmp_path_factory):
    from robocal.workflows.calibration.simulate import simulate_tracker

    d = tmp_path_factory.mktemp("campaign")
    sim = simulate_tracker("ur10", d / "ur10.csv", n_poses=80, noise_mm=0.02, seed=5)
    return {"dir": d, "csv": sim["measurements"], "truth": json.loads(sim["truth"].read_text())}


@pytest.fixture(scope="module")
def result(campaign):
    before = sorted(p.name for p in campaign["dir"].iterdir())
    res = robocal.calibrate("ur10", campaign["csv"], options=robocal.CalibrationOptions(holdout=0.25, seed=3))
    assert sorted(p.name for p in campaign["dir"].iterdir()) == before  # in memory: nothing written
    return res


def test_calibrate_in_memory_recovers_the_hidden_truth(campaign, result):
    assert result.converged and result.status == "ok"
    assert result.holdout["after"]["rms"] < 0.05 < 0.5 < result.holdout["before"]["rms"]
    # gauge-free: the calibrated model predicts the true reflector positions at random poses
    nominal = robocal.load_robot("ur10")
    truth = campaign["truth"]
    true = nominal.with_params(np.array([truth["true_parameters"][n] for n in nominal.params.names])).replace(
        T_world_base=np.array(truth["T_tracker_base"]))
    q = np.random.default_rng(0).uniform(-2.5, 2.5, (50, 6))
    T_cal, T_true = result.robot.fk(q), true.fk(q)
    p_cal = T_cal[:, :3, :3] @ result.targets_mm[0] + T_cal[:, :3, 3]
    p_true = T_true[:, :3, :3] @ np.array(truth["reflectors_mm"][0]) + T_true[:, :3, 3]
    assert np.sqrt(np.mean(np.sum((p_cal - p_true) ** 2, axis=1))) < 0.05
    assert set(result.sigma) == set(result.parameters) and all(result.units[n] in ("mm", "rad") for n in result.sigma)
    assert result.identifiability["identifiable"]


def test_save_writes_what_the_command_writes(tmp_path, campaign, result):
    files = result.save(tmp_path / "api")
    assert sorted(p.name for p in files.values()) == ["accuracy_map.csv", "calibrated_robot.toml",
                                                      "calibrated_robot.urdf", "report.html", "residuals.csv",
                                                      "result.json"]
    r = CliRunner().invoke(robocal.cli.main, ["calibrate", "ur10", str(campaign["csv"]), "--out",
                                              str(tmp_path / "cli"), "--holdout", "0.25", "--seed", "3"])
    assert r.exit_code == 0, r.output
    assert sorted(p.name for p in (tmp_path / "cli").iterdir()) == sorted(p.name for p in (tmp_path / "api").iterdir())
    a, c = (json.loads((tmp_path / k / "result.json").read_text()) for k in ("api", "cli"))
    assert a.keys() == c.keys()
    a["metadata"].pop("written"), c["metadata"].pop("written")
    assert a["metadata"] == c["metadata"]
    va = np.array([p["value"] for p in a["parameters"]])
    vc = np.array([p["value"] for p in c["parameters"]])
    assert np.allclose(va, vc, rtol=0, atol=1e-9)
    with pytest.raises(robocal.OutputExistsError):
        result.save(tmp_path / "api")


def test_a_bad_file_is_a_robocal_error(tmp_path):
    bad = tmp_path / "bad.csv"
    bad.write_text("# format: robocal-measurements/1\nx,y,z\n1,2\n")
    with pytest.raises(robocal.RobocalError):
        robocal.calibrate("ur10", bad)
    with pytest.raises(robocal.InputFileError):
        robocal.read_measurements(tmp_path / "missing.csv")


def test_correct_targets_puts_the_calibrated_robot_on_its_targets(result):
    q = np.random.default_rng(2).uniform(-1.5, 1.5, (5, 6))
    targets = result.robot.fk(q)
    corr = robocal.correct_targets(result.robot, targets, q_seed=q)
    assert corr.converged.all()
    assert np.abs(result.robot.fk(corr.q)[:, :3, 3] - targets[:, :3, 3]).max() < 1e-4


def _frames(rng, n):
    from scipy.spatial.transform import Rotation

    T = np.tile(np.eye(4), (n, 1, 1))
    T[:, :3, :3] = Rotation.from_rotvec(rng.normal(0, 0.6, (n, 3))).as_matrix()
    T[:, :3, 3] = rng.normal(0, 300, (n, 3))
    return T


def test_calibrate_hand_eye_recovers_a_known_transform():
    rng = np.random.default_rng(4)
    X = _frames(rng, 1)[0]            # true T_flange_camera
    T_base_target = _frames(rng, 1)[0]
    F = _frames(rng, 8)               # T_base_flange
    C = np.linalg.inv(F @ X) @ T_base_target  # T_camera_target
    r = robocal.calibrate_hand_eye(F, C)
    assert np.abs(r.T_hand_eye - X).max() < 1e-6 and r.rotation_residual_deg < 1e-6 and r.n_poses == 8
    with pytest.raises(robocal.InputError):
        robocal.calibrate_hand_eye(F[:2], C[:2])


def test_calibrate_tool_recovers_a_known_tcp():
    rng = np.random.default_rng(6)
    tcp, ref = np.array([12.0, -3.0, 180.0]), np.array([900.0, 100.0, 400.0])
    F = _frames(rng, 6)
    F[:, :3, 3] = ref - np.einsum("nij,j->ni", F[:, :3, :3], tcp)  # R t + p = P_ref
    r = robocal.calibrate_tool(F)
    assert np.abs(r.tcp_mm - tcp).max() < 1e-6
    with pytest.raises(robocal.NotIdentifiableError):
        robocal.calibrate_tool(np.tile(F[:1], (5, 1, 1)))
