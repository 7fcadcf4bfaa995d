"""Table 5-2 over many seeds: the thesis-like thermal experiment as a distribution (issue 11).

:func:`run_thermal_seeds` runs :func:`robocal.workflows.thermal.runs.run_thermal_experiment` for
``seeds`` consecutive seeds (cell, system calibration, the three schedules -- schedule seed =
cell seed -- and every noise stream differ per seed) and summarises, for both lambda statistics
(``"rms"``: the thesis's share of monitored directions whose rms residual over the cycles is
below 0.1 mm; ``"max"``: the strict share that never left the band), per run role
(``screening``: run 1, in-sample; ``evaluation``: runs 2 and 3 pooled) and column (``before``,
``traditional``, ``screened``, and ``stable`` with bootstrap resamples), the median and the
spread (quartiles, extremes) of lambda [%]; the share of runs ordered screened > traditional >
before; and how often each parameter was screened (over the seeds; with resamples also the
mean bootstrap frequency).

:func:`format_seeds_table` renders it as text.
"""

from __future__ import annotations

import time

import numpy as np

from ...thermal.stability import selection_frequency
from ..stats import summarise
from .runs import run_thermal_experiment

__all__ = ["STATISTICS", "run_thermal_seeds", "summarise", "format_seeds_table"]

STATISTICS = ("rms", "max")


def _tables(per_seed, columns) -> dict:
    """``{statistic: {role: {column: summary}}}`` over the runs of every seed."""
    out = {}
    for st in STATISTICS:
        out[st] = {}
        for role in ("screening", "evaluation"):
            rows = [r for s in per_seed for r in s["rows"] if r["role"] == role]
            out[st][role] = {c: summarise([r["lambda"][st][c] for r in rows]) for c in columns}
    return out


def _ordered(per_seed, statistic: str) -> dict:
    """Share of runs (per role) with screened > traditional > before, and with screened >= traditional."""
    out = {}
    for role in ("screening", "evaluation"):
        lam = [r["lambda"][statistic] for s in per_seed for r in s["rows"] if r["role"] == role]
        out[role] = {"strict_order": float(np.mean([x["screened"] > x["traditional"] > x["before"] for x in lam])),
                     "screened_not_worse": float(np.mean([x["screened"] >= x["traditional"] for x in lam]))}
    return out


def run_thermal_seeds(*, preset="realistic", seeds: int = 20, first_seed: int = 1, n_cycles: int = 90,
                      n_screen_poses: int = 20, n_online_poses: int = 6, n_keep: int = 8, resamples: int = 0,
                      system_calibration: bool = True, progress=None) -> dict:
    """Run the experiment for seeds ``first_seed .. first_seed + seeds - 1`` (module docstring).

    resamples: bootstrap resamples of run 1's cycles per seed (0: none); progress: optional
    callable ``(i, n, text)``. Returns ``settings``, ``tables`` (``{statistic: {role: {column:
    {median, q25, q75, min, max, n}}}}``), ``ordering`` (per statistic and role), ``selection``
    (``{name: share of seeds}``), ``bootstrap_frequency`` (``{name: mean frequency}`` or None),
    ``per_seed`` (seed, screened set, stable set, the rows), ``elapsed_s``.
    """
    if seeds < 1:
        raise ValueError(f"seeds must be >= 1, got {seeds}")
    t0 = time.perf_counter()
    per_seed = []
    for i in range(int(seeds)):
        seed = int(first_seed) + i
        if progress is not None:
            progress(i + 1, int(seeds), f"seed {seed}")
        r = run_thermal_experiment(seed=seed, schedule_seed=seed, n_cycles=n_cycles, n_screen_poses=n_screen_poses,
                                   n_online_poses=n_online_poses, n_keep=n_keep, preset=preset,
                                   system_calibration=system_calibration, stability=resamples)
        rep = r["stability"]
        cal = r.get("system_calibration")
        per_seed.append({"seed": seed, "screened": list(r["screened"]),
                         "system_calibration_converged": None if cal is None else bool(cal.converged),
                         "stable": None if rep is None else list(rep.selected),
                         "bootstrap_frequency": None if rep is None else rep.frequency,
                         "rows": [{k: v for k, v in row.items()} for row in r["rows"]],
                         "preset": r["settings"]["preset"]})
    columns = ["before", "traditional", "screened"] + (["stable"] if resamples > 0 else [])
    boot = None
    if resamples > 0:
        names = list(per_seed[0]["bootstrap_frequency"])
        boot = {n: float(np.mean([s["bootstrap_frequency"][n] for s in per_seed])) for n in names}
        boot = dict(sorted(boot.items(), key=lambda kv: -kv[1]))
    return {
        "settings": {"preset": per_seed[0]["preset"], "seeds": int(seeds), "first_seed": int(first_seed),
                     "n_cycles": n_cycles, "n_screen_poses": n_screen_poses, "n_online_poses": n_online_poses,
                     "n_keep": n_keep, "resamples": resamples, "threshold_mm": 0.1,
                     "roles": {"screening": "run 1 (in-sample)", "evaluation": "runs 2 and 3"}},
        "tables": _tables(per_seed, columns),
        "ordering": {st: _ordered(per_seed, st) for st in STATISTICS},
        "selection": selection_frequency([s["screened"] for s in per_seed]),
        "bootstrap_frequency": boot,
        "per_seed": per_seed,
        # the fits behind the figures (one system calibration per seed): how many did not converge
        "fits": {"n": sum(s["system_calibration_converged"] is not None for s in per_seed),
                 "not_converged": sum(s["system_calibration_converged"] is False for s in per_seed)},
        "elapsed_s": time.perf_counter() - t0,
    }


def format_seeds_table(res: dict) -> str:
    """Median [q25, q75] of lambda per role and column, both statistics, and the frequencies."""
    s = res["settings"]
    lines = [f"table 5-2 over {s['seeds']} seeds (preset {s['preset']}, {s['n_cycles']} cycles per run, "
             f"{s['n_online_poses']} online sphere poses): lambda [%], median [q25, q75]"]
    for st, label in (("rms", "rms residual < 0.1 mm (thesis)"), ("max", "every cycle < 0.1 mm (strict)")):
        tab = res["tables"][st]
        cols = list(tab["screening"])
        lines += ["", f"{label}", f"{'role':<11}" + "".join(f"{c:>22}" for c in cols)]
        for role, row in tab.items():
            lines.append(f"{role:<11}" + "".join(f"{row[c]['median']:>8.1f} [{row[c]['q25']:5.1f}, {row[c]['q75']:5.1f}]"
                                                 for c in cols))
        o = res["ordering"][st]["evaluation"]
        lines.append(f"evaluation runs ordered screened > traditional > before: {100 * o['strict_order']:.0f} %; "
                     f"screened >= traditional: {100 * o['screened_not_worse']:.0f} %")
    fits = res.get("fits")
    if fits and fits["n"]:
        lines += ["", f"system calibrations (least squares, one per seed): {fits['not_converged']} of {fits['n']} "
                      "did not converge"]
    lines += ["", "selection frequency over seeds: " +
              ", ".join(f"{n} {100 * f:.0f} %" for n, f in res["selection"].items())]
    if res.get("bootstrap_frequency"):
        lines.append("mean bootstrap frequency: " +
                     ", ".join(f"{n} {100 * f:.0f} %" for n, f in res["bootstrap_frequency"].items() if f > 0))
    return "\n".join(lines)
