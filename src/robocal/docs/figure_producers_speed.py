"""Producers of the machine-independent figures of docs/calibration.md and docs/kinematics.md next to
their speed sections (:mod:`robocal.docs.figures`): agreement between two code paths, standard
deviations, rates and iteration counts -- never a time (timings live in benchmarks/README.md with the
command that measures them). Each returns a flat ``{field: value}`` dict and is cached."""

from __future__ import annotations

import functools
import os

__all__ = ["SLOW_SPEED_PRODUCERS", "SPEED_PRODUCERS", "compiled_lm_agreement", "demo_kernel_shift", "ik_seed_ranges",
           "kernel_backend_agreement", "normal_equations_agreement", "plan_verdict"]


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


@functools.lru_cache(maxsize=None)
def normal_equations_agreement() -> dict:
    """docs/calibration.md "Point-only problems ... normal equations": the normal-equations path
    (``robocal.calib._normal``) against the general path (the full Jacobian; ``_normal.supports``
    patched to refuse) on the campaigns of tests/test_normal_equations.py
    (:func:`robocal.sim.tracker_campaigns.reflector_campaign`: UR10, 60 poses, seed 5; one
    reflector, and three reflectors with two missing points).

    Fields ``max_sigma`` (the largest estimate difference in sigma over both campaigns) and
    ``same_iterations`` (1 when both took the same iterations and stop reason on each)."""
    import warnings
    from unittest import mock

    from ..calib import _normal, solve
    from ..sim.tracker_campaigns import reflector_campaign

    gaps, same = [], True
    for three, missing in ((False, False), (True, True)):
        problem, _ = reflector_campaign("ur10", three_targets=three, missing=missing)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            fast = solve(problem)
            with mock.patch.object(_normal, "supports", lambda p: False):
                general = solve(problem)
        gaps.append(_sigma_gap(fast, general))
        same = same and fast.iterations == general.iterations and fast.reason == general.reason
    return {"max_sigma": max(gaps), "same_iterations": float(same)}


@functools.lru_cache(maxsize=None)
def kernel_backend_agreement() -> dict:
    """docs/calibration.md "Kernels: numpy first": every kinematics kernel's output computed by the
    numpy and by the compiled kernels on every shipped robot (tests/test_kernel_backends.py's
    comparison, :func:`robocal.kinematics._backend_agreement.backend_difference`, seed 3).

    Fields ``max_abs`` (the largest difference over every output of every robot: mm, rad and their
    derivatives) and ``max_relative`` (the largest difference of an output over its largest
    magnitude)."""
    from ..kinematics._backend_agreement import backend_difference
    from ..robots import list_robots, load_robot

    runs = [backend_difference(load_robot(name), seed=3) for name in list_robots()]
    return {"max_abs": max(r["max_abs"] for r in runs), "max_relative": max(r["max_relative"] for r in runs)}


@functools.lru_cache(maxsize=None)
def demo_kernel_shift() -> dict:
    """docs/calibration.md "Kernels: numpy first": ``robocal demo --poses 100`` (seed 7) run twice,
    with the numpy and with the compiled kernels (``ROBOCAL_KERNELS=numpy`` / ``compiled``; the mode
    restored afterwards).

    Fields ``max_shift_mm`` (the largest difference of an ISO 9283 characteristic in mm, before or
    after calibration) and ``at_circle_before_mm`` (the circle path's AT before, numpy kernels)."""
    import tempfile
    from pathlib import Path

    from ..kinematics import _backend
    from ..workflows.demo import run_demo

    old, runs = _backend._mode, {}
    try:
        for mode in ("numpy", "compiled"):
            _backend.set_kernels(mode)
            with tempfile.TemporaryDirectory() as tmp:
                r = run_demo(Path(tmp) / "demo", seed=7, n_poses=100, history=False)
            runs[mode] = {c["characteristic"]: (float(c["before"]), float(c["after"])) for c in r["iso9283"]["comparison"]}
    finally:
        _backend.set_kernels(old)
    shifts = [abs(a - b) for k, v in runs["numpy"].items() if k.endswith("_mm") for a, b in zip(v, runs["compiled"][k])]
    return {"max_shift_mm": max(shifts), "at_circle_before_mm": runs["numpy"]["AT_mm_circle"][0]}


SPEED_PRODUCERS = {"calibration/plan_verdict": plan_verdict, "calibration/compiled_lm_agreement": compiled_lm_agreement,
                   "ik_seed/ranges": ik_seed_ranges, "calibration/normal_equations_agreement": normal_equations_agreement,
                   "calibration/kernel_backend_agreement": kernel_backend_agreement,
                   "calibration/demo_kernel_shift": demo_kernel_shift}
#: compiling the LM loop takes ~10 s of CPU on a fresh cache; the IK seed runs train three networks; the
#: demo twice takes ~10-15 s
SLOW_SPEED_PRODUCERS = {"calibration/compiled_lm_agreement", "ik_seed/ranges", "calibration/demo_kernel_shift"}
