"""Issue 31, item 1: Hayati's beta exists wherever two consecutive DH/MDH joint axes are (nearly)
parallel, whether or not the robot file writes it.

The robot is a Rokae-style 6-axis arm in Craig's modified DH as its vendor tables write it: no
``beta`` lines, J2 and J3 parallel (dimensions illustrative, typical of a 7 kg arm). The virtual
robot's J3 axis is really tilted (beta3 = 0.05 deg); a file written without ``beta`` lines must
reach the same held-out error as the same file with ``beta = 0.0`` lines on every joint.
"""

import json
import math

import numpy as np
import pytest
from click.testing import CliRunner

from robocal.cli import main
from robocal.io.measurements import Measurements, write_measurements
from robocal.kinematics.parallel_axes import parallel_axis_pairs
from robocal.robots import load_robot
from robocal.sim import VirtualRobot

# name, alpha [deg], a [mm], theta [deg], d [mm], limits [deg]
_MDH = [("J1", 0.0, 0.0, 0.0, 380.0, 170), ("J2", -90.0, 30.0, -90.0, 0.0, 130),
        ("J3", 0.0, 340.0, 0.0, 0.0, 150), ("J4", -90.0, 35.0, 0.0, 345.0, 170),
        ("J5", 90.0, 0.0, 0.0, 0.0, 115), ("J6", -90.0, 0.0, 0.0, 80.0, 350)]


def _robot_file(path, with_beta: bool):
    lines = ['format = "robocal-robot/1"', 'name = "rokae_style"', 'model = "mdh"', 'length_unit = "mm"',
             'angle_unit = "deg"', 'source = "test: Rokae-style MDH table, illustrative dimensions"']
    for name, alpha, a, theta, d, lim in _MDH:
        lines += ["", "[[joints]]", f'name = "{name}"', f"alpha = {alpha}", f"a = {a}"]
        lines += ["beta = 0.0"] if with_beta else []
        lines += [f"theta = {theta}", f"d = {d}", f"limits = [{-lim}.0, {lim}.0]"]
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path


def run(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


def test_a_file_without_beta_lines_has_beta_where_the_axes_are_parallel(tmp_path):
    model = load_robot(_robot_file(tmp_path / "r.toml", with_beta=False))
    assert [n for n in model.params.names if n.startswith("beta")] == ["beta3"]
    assert model.params.free[model.params.index("beta3")]
    assert [(model.links[p.first].name, model.links[p.second].name) for p in parallel_axis_pairs(model.links)] \
        == [("J2", "J3")]
    ur10 = load_robot("ur10")  # standard DH: J2 || J3 || J4 (alpha2 = alpha3 = 0) -> beta2, beta3
    assert [n for n in ur10.params.names if n.startswith("beta")] == ["beta2", "beta3"]
    np.testing.assert_allclose(ur10.fk(np.full(6, 0.3)), load_robot("ur10").fk(np.full(6, 0.3)))


@pytest.fixture(scope="module")
def campaign(tmp_path_factory):
    d = tmp_path_factory.mktemp("beta")
    plain = _robot_file(d / "rokae_plain.toml", with_beta=False)
    declared = _robot_file(d / "rokae_beta.toml", with_beta=True)
    nominal = load_robot(declared)
    rng = np.random.default_rng(7)
    virtual = VirtualRobot.perturbed(nominal, rng, angle_sigma_deg=0.0, length_sigma_mm=0.2,
                                     offset_sigma_deg=0.03, joint_noise_deg=0.0)
    true = virtual.true_model.with_params(beta3=math.radians(0.05))
    virtual = VirtualRobot(nominal, true)
    q = virtual.random_configurations(80, rng)
    p = virtual.true_poses(q)[:, :3, 3] + rng.normal(0, 0.01, (80, 3))
    data = write_measurements(d / "m.csv", Measurements(q, p, joint_names=nominal.controller_joints,
                                                        metadata={"robot": "rokae_style"}),
                              length_unit="mm", angle_unit="deg")
    out = {}
    # the target sits at the flange origin: the last link's a6, theta6, d6 trade off with it
    for key, robot, fix in (("plain", plain, "a6,theta6,d6"), ("declared", declared, "a6,theta6,d6"),
                            ("no_beta", plain, "a6,theta6,d6,beta3")):
        r = run("calibrate", robot, data, "--out", d / key, "--sigma", 0.01, "--no-report", "--fix", fix)
        assert r.exit_code in ((0,) if key != "no_beta" else (0, 3, 4)), r.output
        out[key] = (r.output, json.loads((d / key / "result.json").read_text()))
    return out


def test_same_held_out_error_with_and_without_beta_lines(campaign):
    plain = campaign["plain"][1]["validation"]["after"]["rms"]
    declared = campaign["declared"][1]["validation"]["after"]["rms"]
    without = campaign["no_beta"][1]["validation"]["after"]["rms"]
    assert plain == pytest.approx(declared, rel=0.05)
    assert plain < 0.03  # ~ the 0.01 mm per coordinate noise
    assert without > 2 * plain  # the tilt the model could not express before


def test_the_report_names_the_parallel_pair(campaign):
    output, res = campaign["plain"]
    assert "parallel axes: J2 || J3 (beta3 free" in output
    assert res["identifiability"]["parallel_axes"] == [{"joints": ["J2", "J3"], "beta": "beta3", "beta_free": True}]
    assert "beta3" in res["metadata"]["free"]


def test_free_beta3_and_free_all_on_a_file_without_beta_lines(tmp_path):
    from robocal.workflows.calibration.calibrate import select_free

    model = load_robot(_robot_file(tmp_path / "r.toml", with_beta=False))
    assert select_free(model, ["beta3"]) == ["beta3"]
    assert "beta3" in select_free(model, free_all=True)
