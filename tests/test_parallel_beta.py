"""Issue 31, item 1: Hayati's beta exists wherever two consecutive DH/MDH joint axes are (nearly)
parallel, whether or not the robot file writes it.

The robot is a Rokae-style 6-axis arm in Craig's modified DH as its vendor tables write it: no
``beta`` lines, J2 and J3 parallel (dimensions illustrative, typical of a 7 kg arm). The virtual
robot's J3 axis is really tilted (beta3 = 0.05 deg); a file written without ``beta`` lines must
reach the same held-out error as the same file with ``beta = 0.0`` lines on every joint.
"""


import numpy as np
import pytest
from click.testing import CliRunner

from robocal.cli import main
from robocal.docs.figure_producers_pages import parallel_beta_campaign, rokae_style_robot_file
from robocal.kinematics.parallel_axes import parallel_axis_pairs
from robocal.robots import load_robot

_robot_file = rokae_style_robot_file  # written once in robocal.docs.figure_producers_pages (docs/robot-files.md)


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
    """The three calibrations of robocal.docs.figure_producers_pages.parallel_beta_campaign (exit 0
    with beta3 free; the one with beta3 held may fail its gates)."""
    return parallel_beta_campaign(tmp_path_factory.mktemp("beta"))


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
