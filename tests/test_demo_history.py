"""The demo's history: a rerun starts a fresh history, simulated time is labelled and never in the
future, and the calibration cycle records its measurements (issue 10, item 6)."""

from __future__ import annotations

from datetime import datetime, timezone

from click.testing import CliRunner

from robocal.cli import main
from robocal.store import HistoryStore
from robocal.workflows.demo import _record_history


def _result():
    cycles = [{"cycle": c, "time_s": 180.0 * c, "names": ["theta2", "a2"], "deltas": [1e-5 * c, 0.001 * c],
               "units": ["rad", "mm"], "lambda_percent": 90.0} for c in range(0, 90, 10)]
    params = [{"name": "a2", "unit": "mm", "change": 0.5, "calibrated": 1350.5, "std": 0.01},
              {"name": "theta3", "unit": "rad", "change": 1e-3, "calibrated": 1e-3, "std": 1e-5}]
    return {"accuracy_mm": {"rms": 1.5},
            "geometric_calibration": {"workspace_accuracy_mm": {"after": {"rms": 0.05}}, "parameters": params,
                                      "residuals_mm": {"before": 1.4, "after": 0.03}},
            "thermal": {"cycles": cycles}, "tool_recalibration": {"tcp_error_mm": 0.03, "cycle_time_s": 11.0}}


def test_demo_history_is_fresh_labelled_and_counts_measurements(tmp_path):
    campaign = tmp_path / "campaign.csv"
    r = CliRunner().invoke(main, ["simulate", "tracker", "kuka_kr150_r3100", "--poses", "25", "--out", str(campaign)])
    assert r.exit_code == 0, r.output
    db = tmp_path / "history.sqlite"
    for _ in range(2):  # the second run replaces the first history instead of interleaving with it
        before = datetime.now(timezone.utc)
        _record_history(db, "kuka_kr150_r3100", _result(), campaign)
    after = datetime.now(timezone.utc)
    with HistoryStore.open(db, create=False) as store:
        cycles = store.cycles("kuka_kr150_r3100")
    assert [c.kind for c in cycles].count("geometric_calibration") == 1
    assert len(cycles) == 1 + 9 + 1
    assert all(c.started_at <= after for c in cycles)            # never in the future
    assert max(c.started_at for c in cycles) >= before.replace(microsecond=0)  # the last cycle ends now
    assert all(c.meta.get("clock") == "simulated" and "simulated time" in c.notes for c in cycles)
    geo = next(c for c in cycles if c.kind == "geometric_calibration")
    assert geo.n_measurements == 25
    # issue 25: the calibration's own parameters and residuals; the simulator-truth errors named as such
    assert geo.n_parameters == 2
    assert geo.metrics["residual_rms_before"].value == 1.4 and geo.metrics["residual_rms_after"].value == 0.03
    assert geo.metrics["workspace_error_nominal_rms"].value == 1.5
    assert geo.metrics["workspace_error_calibrated_rms"].value == 0.05
    thermal = [c for c in cycles if c.kind == "thermal_compensation"]
    assert all(c.metrics["lambda"].unit == "%" and c.metrics["lambda"].value == 90.0 for c in thermal)
    assert all(c.meta.get("sphere_poses") == 6 for c in cycles if c.kind == "thermal_compensation")
