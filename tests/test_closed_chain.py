"""Virtual closed kinematic chain (issue 16): simulator, measurement model, identifiability,
acceptance against a tracker calibration, file format and command line."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from click.testing import CliRunner

from robocal.calib.closed_chain import ClosedChainError, ClosedChainProblem, length_scale_check
from robocal.calib.residuals import RESIDUAL_BLOCKS, PointSpacingResidual, RaySpotResidual, jacobian_errors
from robocal.calib.residuals.check import perturbed_values
from robocal.cli.main import main
from robocal.io.spots import HeldSpots, SpotFileError, read_spots, write_spots
from robocal.robots import load_robot
from robocal.transforms import transform_points
from robocal.workflows.calibration.closed_chain import make_cell, run_closed_chain_calibration
from robocal.workflows.calibration.closed_chain_study import run_seed


def run(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


@pytest.fixture(scope="module")
def irb140():
    return load_robot("abb_irb140")


@pytest.fixture(scope="module")
def one_plate(irb140):
    """One plate position, 5 targets x 8 configurations (seed 3)."""
    cell, rng = make_cell(irb140, 3, plates=1)
    spots, truth = cell.hold_spots(8, rng, tolerance_mm=0.1)
    return cell, spots, truth


@pytest.mark.parametrize("cls", [RaySpotResidual, PointSpacingResidual])
def test_new_residuals_are_registered_and_match_finite_differences(cls):
    assert f"{cls.__module__}.{cls.__qualname__}" in RESIDUAL_BLOCKS
    for seed in range(3):
        rng = np.random.default_rng(seed)
        block = cls.example(rng)
        errs = jacobian_errors(block, perturbed_values(block, rng))
        assert max(errs.values()) < 1e-6, errs


def test_simulated_spots_lie_on_their_marks_within_the_tolerance(one_plate):
    cell, spots, truth = one_plate
    laser = cell.laser.T_flange_laser
    T = cell.robot.true_model.fk(truth["q_link"]) @ laser  # the true beam at the true link angles
    origin, axis = T[:, :3, 3], T[:, :3, 2]
    plate = cell.plates[0]
    marks = dict(zip(plate.target_names, plate.targets_base()))
    P = np.array([marks[t] for t in spots.target])
    n = plate.T_base_plate[:3, 2]
    lam = ((P - origin) @ n) / (axis @ n)
    hit = origin + lam[:, None] * axis
    miss = np.linalg.norm(hit - P, axis=1)
    assert miss.max() <= 0.1 + 1e-6 and miss.mean() > 0.03  # within the tolerance, and not on the mark itself
    res = math.radians(0.001)
    assert np.allclose(spots.joints / res, np.round(spots.joints / res), atol=1e-6)  # quantised readings
    # the readings differ from the link angles by noise, resolution and the cyclic error the model lacks
    assert 1e-6 < np.abs(spots.joints - truth["q_link"]).max() < math.radians(0.01)


def test_no_chain_closes_when_no_target_repeats(irb140, tmp_path):
    q = np.tile(np.radians([10.0, 5.0, -20.0, 30.0, 40.0, 0.0]), (6, 1)) + np.radians(np.arange(6))[:, None]
    spots = HeldSpots(tuple(str(i) for i in range(6)), ("p1",) * 6, tuple(f"t{i}" for i in range(6)), q,
                      irb140.controller_joints, 0.1)
    path = write_spots(tmp_path / "spots.csv", spots, robot=irb140.name)
    with pytest.raises(ClosedChainError, match="no chain closes"):
        ClosedChainProblem(irb140, q, spots.plate, spots.target)
    r = run("closed-chain", "calibrate", "abb_irb140", path, "--out", tmp_path / "cal")
    assert r.exit_code == 1 and "Error:" in r.output and "no chain closes" in r.output
    assert "Traceback" not in r.output and not (tmp_path / "cal" / "result.json").exists()


def test_a_spot_held_once_is_named(irb140, one_plate):
    _, spots, _ = one_plate
    rows = list(range(8)) + [8]  # t1 eight times, t2 once
    s = spots.subset(rows)
    with pytest.raises(ClosedChainError, match=r"p1\.t2 held in only one configuration"):
        ClosedChainProblem(irb140, s.joints, s.plate, s.target)


def test_single_plate_without_spacing_reports_the_scale_unidentifiable(irb140, one_plate, tmp_path):
    _, spots, _ = one_plate
    path = write_spots(tmp_path / "one.csv", spots, robot=irb140.name)
    no = run_closed_chain_calibration("abb_irb140", path, tmp_path / "a", holdout=0.0, report=False)
    scale = next(f for f in no["result"]["closed_chain"]["findings"] if f["what"] == "length scale")
    assert scale["identifiable"] is False and scale["parameters_held"] == ["d4"]
    assert "--target-spacing" in scale["to_recover"]
    assert no["problem"].scale_held == "d4" and "d4" not in no["calibration_result"].names
    assert length_scale_check(no["problem"], no["calibration_result"].state)["mismatch"] < 1e-9
    yes = run_closed_chain_calibration("abb_irb140", path, tmp_path / "b", holdout=0.0, report=False,
                                       target_spacing_mm=50.0)
    scale = next(f for f in yes["result"]["closed_chain"]["findings"] if f["what"] == "length scale")
    assert scale["identifiable"] is True and yes["problem"].scale_held is None
    assert "d4" in yes["calibration_result"].identifiability.identifiable


def test_base_frame_and_beam_findings_name_the_parameters(irb140, one_plate, tmp_path):
    _, spots, _ = one_plate
    path = write_spots(tmp_path / "one.csv", spots, robot=irb140.name)
    out = run_closed_chain_calibration("abb_irb140", path, tmp_path / "c", holdout=0.0, report=False,
                                       target_spacing_mm=50.0)
    f = {x["what"]: x for x in out["result"]["closed_chain"]["findings"]}
    assert {"d1", "theta1"} <= set(f["base frame"]["parameters_held"])
    assert {"d6", "theta6"} <= set(f["along the beam"]["parameters_held"])
    held = {d["name"] for d in out["result"]["identifiability"]["dropped"]} | set(f["base frame"]["parameters_held"])
    assert not held & set(out["calibration_result"].identifiability.identifiable)


def test_irb140_acceptance_against_a_tracker_calibration():
    """5 targets x 8 configurations x 2 plates, 0.1 mm tolerance, joints read at 0.001 deg."""
    r = run_seed(0)
    assert r["n_held_spots"] == 80 and r["converged"]
    assert r["gauge_truth_rms_mm"] < 1e-5  # the model is exact on noise-free data
    assert r["n_checked"] >= 20 and r["max_abs_z"] < 3.0  # identified robot and mount parameters
    w = r["workspace_rms_mm"]
    assert w["closed_chain"] < w["nominal"] / 10.0
    assert w["tracker"] <= w["closed_chain"] < 2.5 * w["tracker"]
    assert 0.03 < r["E_OP_after_mm"] < 0.08  # ~ sigma sqrt(pi/2) for 0.05 mm per in-plate axis


def test_spot_file_errors_name_line_and_column(irb140, one_plate, tmp_path):
    _, spots, _ = one_plate
    good = write_spots(tmp_path / "good.csv", spots, robot=irb140.name)
    back = read_spots(good, robot=irb140)
    assert np.allclose(back.joints, spots.joints, atol=1e-8) and back.tolerance_mm == 0.1
    text = good.read_text()
    (tmp_path / "rad.csv").write_text(text.replace("# angle_unit: deg", "# angle_unit: rad").replace(
        "# robot", "# note: x\n# robot"))
    with pytest.raises(SpotFileError, match="outside the limits|beyond one turn|look like"):
        read_spots(tmp_path / "rad.csv", robot=irb140)
    (tmp_path / "nounit.csv").write_text(text.replace("# angle_unit: deg\n", ""))
    with pytest.raises(SpotFileError, match="angle_unit"):
        read_spots(tmp_path / "nounit.csv", robot=irb140)
    lines = text.splitlines()
    k = next(i for i, ln in enumerate(lines) if ln.startswith("3,"))
    lines[k] = lines[k].replace(lines[k].split(",")[5], "abc", 1)
    (tmp_path / "bad.csv").write_text("\n".join(lines) + "\n")
    with pytest.raises(SpotFileError, match=rf"line {k + 1}, column 'J3'"):
        read_spots(tmp_path / "bad.csv", robot=irb140)
    r = run("closed-chain", "calibrate", "abb_irb140", good, "--target-spacing", "0.05", "--out", tmp_path / "m")
    assert r.exit_code == 1 and "metres given as millimetres" in r.output


def test_cli_simulate_and_calibrate_write_the_outputs_of_calibrate(tmp_path):
    spots = tmp_path / "cell.csv"
    r = run("closed-chain", "simulate", "abb_irb140", "--plates", "2", "--configurations", "6", "--seed", "4",
            "--out", spots)
    assert r.exit_code == 0, r.output
    truth = json.loads((tmp_path / "cell.truth.json").read_text())
    assert truth["spacing_mm"] == 50.0 and len(truth["plates"]) == 2
    r = run("closed-chain", "calibrate", "abb_irb140", spots, "--target-spacing", "50", "--out", tmp_path / "cal")
    assert r.exit_code == 0, r.output
    assert "E_OP" in r.output and "length scale    identifiable" in r.output
    for name in ("result.json", "calibrated_robot.toml", "calibrated_robot.urdf", "report.html"):
        assert (tmp_path / "cal" / name).is_file()
    res = json.loads((tmp_path / "cal" / "result.json").read_text())
    cc = res["closed_chain"]
    assert res["status"] == "ok" and cc["E_OP_after_mm"] < cc["E_OP_before_mm"] / 5
    assert res["validation"]["after"]["rms"] < res["validation"]["before"]["rms"] / 3  # held-out spots
    cal = load_robot(tmp_path / "cal" / "calibrated_robot.toml")
    q = np.radians([[10.0, 20.0, -30.0, 40.0, 50.0, 60.0]])
    p_cal = transform_points(cal.fk(q), np.zeros(3))
    assert 0.05 < np.linalg.norm(p_cal - transform_points(load_robot("abb_irb140").fk(q), np.zeros(3))) < 20.0
    assert "E_OP" in (tmp_path / "cal" / "report.html").read_text()
    r = run("closed-chain", "calibrate", "abb_irb140", spots, "--out", tmp_path / "cal")
    assert r.exit_code == 1 and "--overwrite" in r.output


def test_a_length_fixed_by_the_user_anchors_the_scale_without_holding_another(irb140, one_plate, tmp_path):
    _, spots, _ = one_plate
    path = write_spots(tmp_path / "one.csv", spots, robot=irb140.name)
    out = run_closed_chain_calibration("abb_irb140", path, tmp_path / "d", holdout=0.0, report=False, fix=["d4"])
    assert out["problem"].scale_held == "d4"
    assert {"a2", "a1", "d5"} <= set(out["calibration_result"].identifiability.identifiable)


def test_the_same_held_spots_in_any_row_order_give_the_same_result(tmp_path):
    """Issue 29: a shuffled copy of the held-spot file failed the gates (d4 -227 mm); rows are put in
    one canonical order (plate, target, id) before the split and the solve."""
    spots = tmp_path / "cell.csv"
    r = run("closed-chain", "simulate", "abb_irb140", "--plates", "2", "--configurations", "6", "--seed", "4",
            "--out", spots)
    assert r.exit_code == 0, r.output
    lines = spots.read_text().splitlines()
    head = [i for i, line in enumerate(lines) if not line.startswith("#")][0] + 1
    body = lines[head:]
    order = np.random.default_rng(7).permutation(len(body))
    (tmp_path / "shuffled.csv").write_text("\n".join(lines[:head] + [body[i] for i in order]) + "\n")
    results = []
    for name in ("cell.csv", "shuffled.csv"):
        r = run("closed-chain", "calibrate", "abb_irb140", tmp_path / name, "--target-spacing", "50", "--out",
                tmp_path / name.replace(".csv", ""))
        assert r.exit_code == 0, r.output
        results.append(json.loads((tmp_path / name.replace(".csv", "") / "result.json").read_text()))
    a, b = ({p["name"]: p["value"] for p in res["parameters"] if p["block"] == "geometry"} for res in results)
    assert set(a) == set(b) and len(a) > 5
    assert all(abs(a[n] - b[n]) < 1e-6 for n in a), {n: (a[n], b[n]) for n in a}
    assert results[0]["validation"]["after"]["rms"] == pytest.approx(results[1]["validation"]["after"]["rms"], abs=1e-9)
