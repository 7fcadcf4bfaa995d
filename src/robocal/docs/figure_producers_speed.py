"""Producers of the machine-independent figures of docs/calibration.md and docs/kinematics.md next to
their speed sections (:mod:`robocal.docs.figures`): agreement between two code paths, standard
deviations, rates and iteration counts -- never a time (timings live in benchmarks/README.md with the
command that measures them). Each returns a flat ``{field: value}`` dict and is cached."""

from __future__ import annotations

import functools
import os

__all__ = ["SLOW_SPEED_PRODUCERS", "SPEED_PRODUCERS", "compiled_lm_agreement", "ik_seed_ranges", "plan_verdict"]


@functools.lru_cache(maxsize=None)
def plan_verdict() -> dict:
    """docs/calibration.md "One identifiability verdict" (the set-up of tests/test_plan_verdict.py,
    :func:`robocal.workflows.calibration.plan_verdict.plan_and_calibrations`): sigma(a5) [mm] as the
    plan predicts it and as the calibrations of three simulated robots report it.

    Fields ``plan_a5_std_mm``, ``calibration_a5_std_mm.min``, ``calibration_a5_std_mm.max``."""
    from ..workflows.calibration.plan_verdict import plan_and_calibrations

    plan, results = plan_and_calibrations()
    cal = [float(r.std[r.names.index("a5")]) for r in results]
    return {"plan_a5_std_mm": float(plan["std"][plan["names"].index("a5")]),
            "calibration_a5_std_mm.min": min(cal), "calibration_a5_std_mm.max": max(cal)}


def _both_loops(problem, **kw) -> tuple:
    """The problem solved by the compiled LM loop and by the Python loop (``ROBOCAL_COMPILED_LM``
    ``always`` / ``never``, restored afterwards; warnings silenced)."""
    import warnings

    from ..calib import _lm_compiled, solve

    old = os.environ.get(_lm_compiled.ENV)
    out = []
    try:
        for loop in ("always", "never"):
            os.environ[_lm_compiled.ENV] = loop
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                out.append(solve(problem, **kw))
    finally:
        if old is None:
            os.environ.pop(_lm_compiled.ENV, None)
        else:
            os.environ[_lm_compiled.ENV] = old
    return tuple(out)


def _sigma_gap(a, b) -> float:
    """The largest |estimate difference| / sigma between two results of one problem."""
    import numpy as np

    ok = np.isfinite(b.std) & (b.std > 0)
    return float(np.max(np.abs(a.values - b.values)[ok] / b.std[ok]))


@functools.lru_cache(maxsize=None)
def compiled_lm_agreement() -> dict:
    """docs/calibration.md "The compiled LM loop": the compiled loop against the Python loop on the
    campaigns of tests/test_compiled_lm.py (:mod:`robocal.sim.tracker_campaigns`).

    Fields ``max_sigma`` (the largest estimate difference in sigma over the three campaigns of
    ``test_compiled_loop_equals_python_loop``: IRB140 identifiable geometry, IRB140 with the
    identifiability analysis, UR10 with three reflectors and missing points), ``same_iterations``
    (1 when every campaign took the same iterations and stop reason in both loops), and on the hard
    start of the Hilti URDF arm ``hilti.max_sigma``, ``hilti.iterations`` (the compiled loop's)."""
    from ..sim.tracker_campaigns import effects_tracker_campaign, plain_tracker_campaign

    gaps, same = [], True
    for robot, n_targets, missing, auto in (("abb_irb140", 1, False, False), ("abb_irb140", 1, False, True),
                                            ("ur10", 3, True, True)):
        problem = effects_tracker_campaign(robot, n_targets=n_targets, missing=missing, identifiable_only=not auto)[0]
        a, b = _both_loops(problem, auto_identifiable=auto)
        gaps.append(_sigma_gap(a, b))
        same = same and a.iterations == b.iterations and a.reason == b.reason
    a, b = _both_loops(plain_tracker_campaign("hilti_trailblazer"))
    return {"max_sigma": max(gaps), "same_iterations": float(same), "hilti.max_sigma": _sigma_gap(a, b),
            "hilti.iterations": float(a.iterations)}


@functools.lru_cache(maxsize=None)
def ik_seed_ranges() -> dict:
    """docs/kinematics.md "Where the learned seed pays off": the ranges over the three robots of
    ``python benchmarks/bench_ik_seed.py`` (:func:`robocal.docs.figure_producers_bench.ik_seed`:
    IRB140, beta-tilted IRB140, UR10).

    Fields ``{min|max}.ik.{start}.{converged|on_branch|median_it}`` [%, iterations] and
    ``mean.ga.gain_percent`` (the GA's gain in validation RMS joint error over the untuned default,
    generation 0 -> last, in % of generation 0, averaged), ``mean.ga.evaluations``."""
    from .figure_producers_bench import ik_seed

    runs = [ik_seed(r) for r in ("irb140", "tilted", "ur10")]
    out = {}
    for key in ("ik.network.converged", "ik.network.on_branch", "ik.network.median_it", "ik.middle.converged",
                "ik.middle.on_branch", "ik.middle.median_it"):
        vals = [r[key] for r in runs]
        out[f"min.{key}"], out[f"max.{key}"] = min(vals), max(vals)
    gains = [100.0 * (r["ga.first"] - r["ga.last"]) / r["ga.first"] for r in runs]
    out["mean.ga.gain_percent"] = sum(gains) / len(gains)
    out["mean.ga.evaluations"] = sum(r["ga.evaluations"] for r in runs) / len(runs)
    return out


SPEED_PRODUCERS = {"calibration/plan_verdict": plan_verdict, "calibration/compiled_lm_agreement": compiled_lm_agreement,
                   "ik_seed/ranges": ik_seed_ranges}
#: compiling the LM loop takes ~10 s of CPU on a fresh cache; the IK seed runs train three networks
SLOW_SPEED_PRODUCERS = {"calibration/compiled_lm_agreement", "ik_seed/ranges"}
