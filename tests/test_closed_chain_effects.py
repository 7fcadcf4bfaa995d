"""The closed-chain calibration judged at the hidden true robot of a cell with effects the model
lacks (issue 25, item 4; ``robocal closed-chain simulate --effects realistic``).

The ideal cell's acceptance test (``test_closed_chain.py::test_irb140_acceptance_against_a_tracker_calibration``)
passes "within 3 sigma" by construction: its only unmodelled effect is a 0.0005 deg cyclic joint
error. Here the true arm also has a reducer transmission error (0.005 / 0.003 deg once / twice per
revolution), J2/J3 gravity sag (3 mrad/kNm) and a 20 ppm warm-up over the session
(:class:`robocal.sim.closed_chain_effects.CellEffects`). The claim tested is the one a user
relies on: where the calibrated model puts a tool point, against where the true robot (with its
effects) puts it, over held-out configurations, after the best base frame and tool point (the
closed chain cannot see either). The tolerance comes from the effects' stated sizes, to first order
(the judging code and its first-order derivation: :mod:`robocal.sim.closed_chain_judge`, shared with
the documented figures of docs/closed-chain.md).

Asserted: RMS over the held-out poses of ``|error - predicted miss| <= 3 sigma_rms``, and the
effects are visible: the at-robot RMS exceeds the ideal cell's (same seed) and 3 sigma_rms.
Measured (seed 0): see :func:`test_realistic_cell_lands_at_truth_plus_its_first_order_miss`.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from click.testing import CliRunner

from robocal.cli.main import main
from robocal.io.spots import read_spots
from robocal.robots import load_robot
from robocal.sim.closed_chain_judge import judge

SEED = 0


def _run(args):
    r = CliRunner().invoke(main, [str(a) for a in args])
    assert r.exit_code == 0, r.output
    return r


def _cell(tmp_path_factory, effects):
    d = tmp_path_factory.mktemp(f"cc_{effects}")
    _run(["closed-chain", "simulate", "abb_irb140", "--seed", SEED, "--effects", effects, "--out", d / "cell.csv"])
    _run(["closed-chain", "calibrate", "abb_irb140", d / "cell.csv", "--target-spacing", "50", "--holdout", "0",
          "--no-report", "--out", d / "cal"])
    return d


@pytest.fixture(scope="module")
def realistic(tmp_path_factory):
    return _cell(tmp_path_factory, "realistic")


@pytest.fixture(scope="module")
def ideal(tmp_path_factory):
    return _cell(tmp_path_factory, "ideal")


def test_realistic_cell_lands_at_truth_plus_its_first_order_miss(realistic, ideal):
    """Seed 0, 80 held spots, 200 held-out configurations, a tool point 150 mm from the flange.
    Measured: realistic cell at-robot RMS 0.174 mm (max 0.353), first-order miss 0.152 mm RMS,
    error minus miss 0.041 mm RMS, noise sigma_rms 0.069 mm (99.9 % quantile of its RMS 0.156 mm);
    chi-square of the error in the 18 noise modes 20610 plain, 6.2 after the miss (99.9 % quantile
    42.3); ideal cell (same seed and noise): RMS 0.039 mm, chi-square 6.4; E_OP 0.0624 mm against
    0.0569 mm. Seeds 1-3 (not run here): error minus miss chi-square 19.3 / 36.7 / 22.1, plain
    1111 / 1.4e7 / 1.1e5; at-robot RMS 0.206 / 0.245 / 0.178 mm against the ideal's 0.049 / 0.107 /
    0.094 mm."""
    from scipy.stats import chi2

    r, i = judge(realistic, SEED), judge(ideal, SEED)
    bound = chi2.ppf(0.999, r["n_noise_modes"])
    # the tolerance: the first-order miss from the effects' sizes plus the noise at 99.9 %
    assert r["chi2_residual"] <= bound, r
    assert r["residual_rms_mm"] <= r["noise_rms_999_mm"], r
    assert i["chi2_error"] <= bound and i["rms_mm"] <= i["noise_rms_999_mm"], i  # the ideal cell: noise only
    # the effects are visible: noise alone is rejected, and the robot misses by more than the ideal cell's
    assert r["chi2_error"] > 10 * bound and r["rms_mm"] > r["noise_rms_999_mm"], r
    assert r["rms_mm"] > 3 * i["rms_mm"] and r["e_op_mm"] > i["e_op_mm"], (r, i)
    assert r["miss_rms_mm"] > 2 * r["sigma_rms_mm"], r  # the predicted bias is above the noise
    # docs/closed-chain.md's table is checked by robocal.docs.figures (closed-chain:effects ...)


def test_realistic_effects_are_written_to_the_truth_and_ideal_is_the_cell_as_before(realistic, ideal):
    """The truth file records the effects (what :func:`judge` rebuilds the true robot from); the
    ideal preset writes no entry and its held spots differ from the realistic ones by the effects
    only (same random streams: the same spots held, joints apart by < 0.05 deg)."""
    t = json.loads((realistic / "cell.truth.json").read_text())
    e = t["cell_effects"]
    assert e["preset"] == "realistic" and e["transmission_deg"] == [0.005, 0.003] and e["growth_ppm"] == 20.0
    assert e["compliance_mrad_per_knm"] == [3.0, 3.0] and np.shape(e["transmission_phases_rad"]) == (2, 6)
    ti = json.loads((ideal / "cell.truth.json").read_text())
    assert "cell_effects" not in ti and ti["simulation"]["effects"] == "ideal"
    nominal = load_robot("abb_irb140")
    a, b = read_spots(realistic / "cell.csv", robot=nominal), read_spots(ideal / "cell.csv", robot=nominal)
    assert a.target == b.target and a.plate == b.plate
    dq = np.degrees(np.abs(a.joints - b.joints)).max()
    assert 0.002 < dq < 0.05, dq
