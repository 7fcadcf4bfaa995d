"""``robocal thermal experiment``: table 5-2 over many seeds (thin over
:func:`robocal.workflows.thermal.seeds.run_thermal_seeds`; registered by :mod:`robocal.cli.thermal`)."""

from __future__ import annotations

import json
import math

import click

from ._common import _step_printer, _user_error

__all__ = ["experiment_cmd", "experiment_json"]


def _clean(obj):
    """JSON-safe plain data (NaN -> null)."""
    if isinstance(obj, dict):
        return {str(k): _clean(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_clean(v) for v in obj]
    if isinstance(obj, float):
        return obj if math.isfinite(obj) else None
    if hasattr(obj, "item"):
        return _clean(obj.item())
    return obj


def experiment_json(res: dict) -> dict:
    """The printed JSON: settings, ``lambda`` (``{statistic: {role: {column: {median, q25, q75,
    min, max, n}}}}``), ordering, ``selection_frequency``, ``bootstrap_frequency`` and per seed
    the screened (and stable) set and lambda of every run for both statistics."""
    per_seed = [{"seed": s["seed"], "screened": s["screened"], "stable": s["stable"],
                 "runs": [{"run": r["run"], "role": r["role"], "tcp_drift_3h_mm": r["tcp_drift_3h_mm"],
                           "lambda": r["lambda"]} for r in s["rows"]]} for s in res["per_seed"]]
    return _clean({"settings": res["settings"], "lambda": res["tables"], "ordering": res["ordering"],
                   "selection_frequency": res["selection"], "bootstrap_frequency": res["bootstrap_frequency"],
                   "per_seed": per_seed, "fits": res.get("fits"), "elapsed_s": res["elapsed_s"]})


@click.command("experiment", short_help="Table 5-2 over N seeds: median and spread of lambda, selection frequency.")
@click.option("--preset", type=click.Choice(["ideal", "realistic"]), default="realistic", show_default=True,
              help="Effects outside the compensation model (docs/thermal.md 'Realism').")
@click.option("--seeds", "n_seeds", default=20, show_default=True, type=click.IntRange(1, 10000),
              help="Number of seeds (cells, schedules and noise all differ per seed).")
@click.option("--seed", "first_seed", default=1, show_default=True, type=int, help="The first seed; the others follow.")
@click.option("--cycles", "n_cycles", default=90, show_default=True, type=click.IntRange(8, 1000),
              help="Production cycles (~3 min) per run.")
@click.option("--resamples", default=0, show_default=True, type=click.IntRange(0, 1000),
              help="Bootstrap resamples of run 1's cycles per seed: selection frequency and a 'stable' column.")
@click.option("--json", "as_json", is_flag=True, help="Print JSON.")
def experiment_cmd(preset, n_seeds, first_seed, n_cycles, resamples, as_json):
    """The thesis-like thermal experiment (thesis 5.1, table 5-2) repeated over N seeds: per run
    role (screening = run 1, evaluation = runs 2 and 3) and column (before / traditional /
    screened) the median and spread of lambda, for the thesis's statistic (rms over the cycles
    < 0.1 mm) and the strict one (every cycle < 0.1 mm), and how often each parameter is screened.
    About 2 s per seed at 90 cycles.
    """
    from ..workflows.thermal.seeds import format_seeds_table, run_thermal_seeds

    try:
        res = run_thermal_seeds(preset=preset, seeds=n_seeds, first_seed=first_seed, n_cycles=n_cycles,
                                resamples=resamples, progress=_step_printer)
    except (ValueError, KeyError) as exc:
        raise _user_error(exc) from None
    if as_json:
        click.echo(json.dumps(experiment_json(res), indent=1))
        return
    click.echo(format_seeds_table(res))
    click.echo(f"({res['elapsed_s']:.0f} s)")
