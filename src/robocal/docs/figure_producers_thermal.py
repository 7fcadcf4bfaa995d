"""Producers of docs/thermal.md's documented figures that no other producer computes
(:mod:`robocal.docs.figures`): the effect-by-effect table and the three-hour drift; and the ratios
that docs/tcp.md's prose reads off the collision study. Each returns a flat ``{field: value}``
dict and is cached."""

from __future__ import annotations

import functools

__all__ = ["THERMAL_PRODUCERS", "tcp_collision_ratios", "thermal_drift_three_hours", "thermal_effect_alone"]

#: the effects of the realistic preset, each switchable alone (``robocal.sim.thermal.effects``)
EFFECTS = ("heat", "hall", "deformation", "joints", "noise", "outliers")


@functools.lru_cache(maxsize=None)
def thermal_effect_alone(effect: str) -> dict:
    """docs/thermal.md "Each effect alone": ``run_thermal_seeds`` on the realistic preset with only
    ``effect`` on (``ThermalEffects.realistic().only(effect)``), seeds 1-10, 90 cycles per run, no
    resamples. Fields: lambda [%] as ``{rms|max}.{screening|evaluation}.{column}.{median|q25|q75|min|max}``
    (``max`` is the strict statistic), ``n_not_converged``. ~6-10 s of CPU each."""
    from ..sim.thermal.effects import ThermalEffects
    from ..workflows.thermal.seeds import run_thermal_seeds
    from .figure_producers import _flat

    r = run_thermal_seeds(preset=ThermalEffects.realistic().only(effect), seeds=10, first_seed=1, n_cycles=90)
    return {**_flat(r["tables"]), "n_not_converged": float(r["fits"]["not_converged"])}


@functools.lru_cache(maxsize=None)
def thermal_drift_three_hours(preset: str) -> dict:
    """docs/thermal.md "Drift" (the set-up of ``tests/test_thermal_realism.py``'s
    ``test_realistic_drift_after_three_hours_is_in_the_thesis_range``): cells 1-8 (cell seed = run
    seed), 60 cycles of 140 s at full load without pause (3 h), the TCP drift at 3 h [mm] on the
    ``preset`` cell (``"realistic"`` or ``"ideal"``; ~3 s of CPU each).

    Fields ``min``, ``median``, ``max``."""
    import numpy as np

    from ..sim.thermal.simulator import ProductionSchedule, ThermalCell

    schedule = ProductionSchedule(np.full(60, 140.0), np.full(60, 1.0), np.zeros(60))
    tcp = []
    for seed in range(1, 9):
        run = ThermalCell.standard(seed, preset=preset).simulate(schedule, seed)
        tcp.append(float(np.interp(3 * 3600.0, run.timeline_s, run.tcp_drift_mm)))
    return {"min": min(tcp), "median": float(np.median(tcp)), "max": max(tcp)}


@functools.lru_cache(maxsize=None)
def tcp_collision_ratios() -> dict:
    """docs/tcp.md, the prose under the collision study (``robocal tcp simulate --collisions 10
    --seed 0``, producer ``tcp/collisions``): how much the tool-axis RMS error grows without the beta
    correction (``axis``), and the TCP RMS error with the thesis's step 3 (``tcp_thesis_step3``)."""
    from .figure_producers import PRODUCERS

    c = PRODUCERS["tcp/collisions"]()
    return {"axis": c["no_beta_correction.axis_rms_deg"] / c["beta_corrected.axis_rms_deg"],
            "tcp_thesis_step3": c["thesis_step3_no_beta.tcp_rms_mm"] / c["thesis_step3.tcp_rms_mm"]}


THERMAL_PRODUCERS = {"tcp/collision_ratios": tcp_collision_ratios,
                     **{f"thermal_drift/{p}": functools.partial(thermal_drift_three_hours, p)
                        for p in ("realistic", "ideal")},
                     **{f"thermal_alone/{e}": functools.partial(thermal_effect_alone, e) for e in EFFECTS}}
