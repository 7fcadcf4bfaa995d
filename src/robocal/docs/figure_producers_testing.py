"""Producers of docs/testing.md's and docs/closed-chain.md's documented figures that come from the
set-ups of the tests with effects the model lacks (:mod:`robocal.docs.figures`): the closed-chain
cell judged at the true robot, the UR10 6-D campaign imported from vendor exports, the camera
self-calibrations and the hand-eye refinement on robots that differ from their models. The set-ups
live in :mod:`robocal.sim` and are shared with the tests (same draws). Each producer returns a flat
``{field: value}`` dict and is cached."""

from __future__ import annotations

import functools

__all__ = ["TESTING_PRODUCERS", "closed_chain_effects", "closed_chain_effects_z"]


@functools.lru_cache(maxsize=None)
def closed_chain_effects(seed: int) -> dict:
    """docs/closed-chain.md "A cell with the effects the model lacks" (the set-up of
    ``tests/test_closed_chain_effects.py``): ``robocal closed-chain simulate abb_irb140 --seed SEED
    --effects ideal|realistic`` and ``robocal closed-chain calibrate ... --target-spacing 50
    --holdout 0``, judged at the true robot over 200 held-out configurations
    (:func:`robocal.sim.closed_chain_judge.judge`). ~1.5 s of CPU per seed.

    Fields ``{ideal|realistic}.{rms_mm|max_mm|miss_rms_mm|residual_rms_mm|sigma_rms_mm|noise_rms_999_mm|
    chi2_error|chi2_residual|e_op_mm}``, ``chi2_bound`` (the chi-square 99.9 % quantile of the
    realistic cell's noise modes), ``rms_ratio`` (realistic / ideal at-robot RMS)."""
    import tempfile
    from pathlib import Path

    from scipy.stats import chi2

    from ..sim.closed_chain_judge import judge
    from .figure_producers_cli import run_cli

    out = {}
    with tempfile.TemporaryDirectory() as tmp:
        for effects in ("ideal", "realistic"):
            d = Path(tmp) / effects
            d.mkdir()
            run_cli("closed-chain", "simulate", "abb_irb140", "--seed", seed, "--effects", effects, "--out", d / "cell.csv")
            run_cli("closed-chain", "calibrate", "abb_irb140", d / "cell.csv", "--target-spacing", "50", "--holdout", "0",
                    "--no-report", "--out", d / "cal")
            r = judge(d, seed)
            out.update({f"{effects}.{k}": float(v) for k, v in r.items()})
            if effects == "realistic":
                out["chi2_bound"] = float(chi2.ppf(0.999, r["n_noise_modes"]))
    out["rms_ratio"] = out["realistic.rms_mm"] / out["ideal.rms_mm"]
    return out


@functools.lru_cache(maxsize=None)
def closed_chain_effects_z() -> dict:
    """docs/closed-chain.md's last column on the realistic cell: ``run_seed(0, effects="realistic")``
    of :mod:`robocal.workflows.calibration.closed_chain_study` (the 22 identified parameters
    against the effect-free gauge truth, in reported sigmas). ~7 s of CPU. Fields ``max_abs_z``,
    ``n_not_converged``."""
    from ..workflows.calibration.closed_chain_study import run_seed

    r = run_seed(0, effects="realistic")
    return {"max_abs_z": float(r["max_abs_z"]), "n_not_converged": float(r["n_not_converged"])}


@functools.lru_cache(maxsize=None)
def closed_chain_held_sigma() -> dict:
    """docs/closed-chain.md's identifiability table: the standard deviation [rad] that ``theta1``
    would have on the study's cells (``closed_chain/study``: seeds 0-9, two plates), held as
    "barely observable". Fields ``theta1.min``, ``theta1.max``, ``n_held`` (cells that held it)."""
    from .figure_producers import PRODUCERS

    r = PRODUCERS["closed_chain/study"]()
    vals = [r[f"{s}.held_std.theta1"] for s in range(10) if f"{s}.held_std.theta1" in r]
    return {"theta1.min": min(vals), "theta1.max": max(vals), "n_held": float(len(vals))}


@functools.lru_cache(maxsize=None)
def gaussian_formulas() -> dict:
    """Closed-form statistics quoted as expectations (no simulation): for ``n`` = 22 independent
    standard normal estimates, ``p_any_beyond_3.22`` = P(max |z| > 3) [%] and
    ``median_max_abs_z.22`` (the median of max |z|: ``(2 Phi(x) - 1)^n = 1/2``); the binomial tail
    probabilities of the thermal sign test (docs/testing.md): ``binom_100_half_ge_65`` =
    P(Bin(100, 1/2) >= 65) and ``binom_100_0.9_le_80`` = P(Bin(100, 0.9) <= 80)."""
    from scipy.stats import binom, norm

    n = 22
    return {"p_any_beyond_3.22": 100.0 * (1.0 - (1.0 - 2.0 * norm.sf(3.0)) ** n),
            "median_max_abs_z.22": float(norm.ppf((1.0 + 0.5 ** (1.0 / n)) / 2.0)),
            "binom_100_half_ge_65": float(binom.sf(64, 100, 0.5)),
            "binom_100_0.9_le_80": float(binom.cdf(80, 100, 0.9))}


TESTING_PRODUCERS = {"closed_chain/held_sigma": closed_chain_held_sigma, "formulas/gaussian": gaussian_formulas,
                     **{f"closed_chain_effects/seed{s}": functools.partial(closed_chain_effects, s) for s in range(4)},
                     "closed_chain_effects/z": closed_chain_effects_z}

#: longer than ~5 s, or run only for history-like seed rows: with ``--all``
SLOW_TESTING_PRODUCERS = {"closed_chain/held_sigma", "closed_chain_effects/seed1", "closed_chain_effects/seed2",
                          "closed_chain_effects/seed3", "closed_chain_effects/z"}
