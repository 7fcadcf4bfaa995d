"""Elastic calibration on the real data (issue 18): same protocols and splits as
docs/datasets.md, geometric vs elastic-joint. Skips with the reason when the data are absent."""

from __future__ import annotations

import json

import pytest
from click.testing import CliRunner

from robocal.cli.main import main
from robocal.io.datasets import HILTI_SETS, datasets_root
from robocal.workflows.datasets import calibrate_boby, calibrate_justin

ROOT = datasets_root()
# the independent reference fit's calibrated (geometric) RMS per set [mm], printed to 0.1 mm
# (../shared/datasets/hilti_trailblazer/README.md, "Reference calibration"; as tests/test_real_data.py)
HILTI_REFERENCE = {"flat": 4.1, "pallet": 4.7, "orthogonal_wood": 3.7, "wood_left_track": 6.2, "seesaw": 6.1,
                   "diagonal_wood": 4.9, "outdoor": 4.7}


def _need(folder):
    p = ROOT / folder
    return pytest.mark.skipif(not p.is_dir(), reason=f"real data folder {p} absent (see docs/datasets.md)")


@_need("dlr_justin")
def test_dlr_justin_joint_compliance_reaches_the_source_figure():
    """Acceptance <= 6.0 mm mean TCP error (source 5.64); measured 4.28 mm mean, 4.72 mm RMS."""
    r = calibrate_justin(0, model="elastic-joint")
    assert r["all"]["mean"] > 10.0  # the geometric level, unchanged
    assert r["elastic"]["mean"] < 4.5 and r["elastic"]["rms"] < 5.0, r["elastic"]
    ident = r["results"]["elastic"].identifiability.by_block()["compliance"]
    # torso_0 turns about the vertical: no gravity torque varies, reported by name
    assert [d["name"] for d in ident["dropped"]] == ["compliance.torso_0"]


@_need("dlr_justin")
def test_dlr_justin_full_model_converges_in_hundreds_not_thousands_of_iterations():
    """Issue 34 item 3: elastic-full on the protocol's split converges in every round, its full
    level in 143 iterations here (1324 with the start's column scaling, the first round at the cap
    of 1000: robocal.calib._iterate, "Growing column scales"), holdout mean 3.29 mm (source 3.12;
    3.27 at the old stopping point of the same nearly flat cost). Bounds: 2x the iterations,
    +0.06 mm."""
    r = calibrate_justin(0, model="elastic-full")
    full = r["results"]["full"]
    assert full.converged and all(res.converged for res in r["results"].values())
    assert full.iterations <= 300, full.iterations
    assert r["full"]["mean"] < 3.35 and r["full"]["max"] < 9.0, r["full"]


@_need("boby_fanuc")
def test_boby_fanuc_joint_compliance_below_0_40_mm():
    """Seeds 0 and 3 (the best and the worst geometric split), every fit converged (issue 25: the
    LM needs 103-1292 iterations here since the chi-square stop bounds the remaining decrease, 98-558
    before; the earlier 200-iteration cap stopped three of five seeds and
    gave lower figures): elastic-joint holdout RMS 0.271 and 0.309 mm against 0.348 and 0.536 mm
    geometric (all five seeds: 0.276 mm mean, docs/datasets.md); the target is < 0.40 mm."""
    for seed in (0, 3):
        r = calibrate_boby(seed, model="elastic-joint")
        assert r["result"].converged and r["nominal_result"].converged
        assert r["calibrated"]["rms"] < 0.40, (seed, r["calibrated"])
        assert r["calibrated"]["rms"] < 0.85 * r["geometric"]["rms"]


@_need("hilti_trailblazer")
def test_hilti_elastic_joint_beats_every_set_from_the_command_line():
    """elastic-joint on every set: at least 0.5 mm below the geometric fit of the same run, and
    below the independent reference fit (a geometric one) by as much; the geometric fit itself at
    or below the reference, as docs/datasets.md accepts. Measured 2.68-5.49 mm RMS against
    3.63-6.15 geometric and 3.7-6.2 reference (elastic-full, ~20x slower here: 2.36-5.40,
    docs/elastic.md)."""
    pytest.importorskip("yaml", reason="the Hilti files need PyYAML (extra 'yaml')")
    out = CliRunner().invoke(main, ["datasets", "run", "hilti_trailblazer", "--model", "elastic-joint", "--json"])
    assert out.exit_code == 0, out.output
    rec = json.loads(out.stdout)
    assert rec["convergence"]["converged"] and rec["convergence"]["n_fits"] == 2  # every fit converged
    assert rec["model"] == "elastic-joint" and [s["set"] for s in rec["sets"]] == list(HILTI_SETS)
    for s in rec["sets"]:
        ref = HILTI_REFERENCE[s["set"]]
        assert s["geometric"]["rms"] <= ref + 0.05, s  # + half the printed resolution
        assert s["holdout_rms_mm"] < s["geometric"]["rms"] - 0.5, s  # measured 0.58-1.06 mm lower
        assert s["holdout_rms_mm"] < ref - 0.5, s
        assert s["holdout_mean_mm"] < s["holdout_rms_mm"] < s["holdout_max_mm"]


def test_datasets_cli_names_what_is_not_there(tmp_path):
    r = CliRunner().invoke(main, ["datasets", "run", "nope"])
    assert r.exit_code == 1 and "unknown data set 'nope'" in r.output
    r = CliRunner().invoke(main, ["datasets", "run", "boby_fanuc", "--root", str(tmp_path)])
    assert r.exit_code == 1 and "not found" in r.output
    r = CliRunner().invoke(main, ["datasets", "list", "--root", str(tmp_path), "--json"])
    assert r.exit_code == 0 and not any(d["present"] for d in json.loads(r.output))


def test_datasets_cli_refuses_an_unknown_model():
    r = CliRunner().invoke(main, ["datasets", "run", "boby_fanuc", "--model", "elastic-lateral"])
    assert r.exit_code == 2 and "elastic-full" in r.output
