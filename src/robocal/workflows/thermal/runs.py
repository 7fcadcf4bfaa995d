"""The thesis-like thermal compensation experiment (METHODS.md 4; thesis 5.1, tables 5-1 and 5-2).

:func:`run_thermal_experiment` on the simulated KR150 R3100 (DH + beta):

1. the cell (:meth:`robocal.sim.thermal.simulator.ThermalCell.standard`, ``preset`` ideal or realistic):
   20 sphere poses for screening, 34 monitored car-body points, fixed stereo sensor (0.02 mm),
   robot-held sensor (0.02 mm);
2. system calibration (thesis 3.3) from 9 cold sphere poses by nonlinear least squares
   (:func:`robocal.thermal.calibrate_system`); everything afterwards uses the *estimated*
   ``T_sensor_base`` and ``P_e`` (``system_calibration=False``: the true ones);
3. three runs of 90 ~3-min cycles with different production schedules
   (:func:`robocal.sim.thermal.simulator.standard_schedules`), each starting cold;
4. screening (:func:`robocal.thermal.screening.screen_parameters`) on run 1 with all 20 sphere
   poses per cycle, 24 -> 8 parameters;
5. for the traditional set (non-zero lengths) and the screened set, the 6 online sphere poses
   (of the 20) that minimise the predicted noise at the monitored points
   (:func:`~robocal.thermal.screening.select_online_poses`), and per run, per cycle, the
   identification from those 6 poses and the compensated residuals; lambda before / traditional /
   screened per run (table 5-2). Run 1 is in-sample for the screening; runs 2 and 3 are the
   evaluation.

:func:`format_thermal_table` renders the table; :func:`format_thermal_report` adds the screening
table (5-1) and the settings. One seed is one draw: :mod:`robocal.workflows.thermal.seeds` runs
the experiment over many.
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from ...sim.robot import as_rng
from ...sim.thermal.simulator import ThermalCell, standard_schedules, write_run
from ...thermal.screening import (
    LAMBDA_THRESHOLD_MM,
    ScreeningProblem,
    lambda_metric,
    screen_parameters,
    select_online_poses,
    traditional_parameters,
)

__all__ = ["run_thermal_experiment", "screening_problem", "format_thermal_table", "format_thermal_report"]


def screening_problem(cell: ThermalCell, run, *, T_sensor_base=None, P_e=None, model=None) -> ScreeningProblem:
    """The :class:`ScreeningProblem` of a simulated run, from its measurements (the model,
    ``T_sensor_base`` and ``P_e`` default to the cell's nominal model and true sensor set-up)."""
    model = cell.model if model is None else model
    return ScreeningProblem.from_measurements(
        model, cell.T_sensor_base if T_sensor_base is None else T_sensor_base, cell.P_e if P_e is None else P_e,
        run.q_sphere, run.sphere_cold, run.sphere, run.q_monitor, run.monitor_cold, run.monitor,
        cell.T_flange_sensor, times_s=run.times_s)


def run_thermal_experiment(*, seed: int = 2024, schedule_seed: int = 7, n_cycles: int = 90, n_screen_poses: int = 20,
                           n_online_poses: int = 6, n_keep: int = 8, threshold_mm: float = LAMBDA_THRESHOLD_MM,
                           statistic: str = "rms", system_calibration: bool = True, n_system_poses: int = 9,
                           out_dir=None, cell_options: dict | None = None,
                           screening_options: dict | None = None, preset="ideal", stability: int = 0) -> dict:
    """Run the experiment (module docstring); every draw from ``seed`` / ``schedule_seed``.

    preset: the cell's effects outside the model (``"ideal"``, ``"realistic"`` or a
    :class:`~robocal.sim.thermal.effects.ThermalEffects`; ``cell_options["preset"]`` wins).
    stability: if > 0, that many bootstrap resamples of run 1's cycles are screened
    (:func:`robocal.thermal.stability.screening_stability`); the report is ``stability`` and its
    selection by frequency is evaluated as a fourth column ``stable``.

    out_dir: if given, every run is also written as measurement files (``run1/``, ``run2/``,
    ``run3/``; :func:`robocal.sim.thermal.simulator.write_run`).
    Returns a dict: ``rows`` (one per run: run, role, cycles, hours, TCP drift after 3 h [mm],
    lambda before / traditional / screened [%]), ``screening`` (the
    :class:`~robocal.thermal.screening.ScreeningResult`), ``traditional`` and ``screened`` (names),
    ``online_poses`` ({"traditional": idx, "screened": idx} into the 20 sphere poses),
    ``lambda_screening_20`` (the screened set with all 20 poses on run 1), ``system_calibration``
    (the result or None) and its ``frame_errors``, ``cell``, ``runs``, ``problems``, ``settings``,
    ``timings_s``. Each row also has ``lambda``: ``{"rms": {column: %}, "max": {column: %}}``,
    both statistics side by side (``"max"``: a direction passes only if no cycle left the band).
    """
    t_start = time.perf_counter()
    timings = {}
    rng = as_rng(seed)
    run_seeds = rng.integers(0, 2**31, 4)
    cell = ThermalCell.standard(seed, n_sphere_poses=n_screen_poses, **{"preset": preset, **(cell_options or {})})
    model = cell.model
    timings["cell"] = time.perf_counter() - t_start

    T_sb, P_e, calib, ferr = cell.T_sensor_base, cell.P_e, None, None
    if system_calibration:
        t0 = time.perf_counter()
        calib, ferr = _system_calibration(cell, n_system_poses, int(run_seeds[0]))
        T_sb, P_e = calib.T_sensor_base, calib.P_e
        timings["system_calibration"] = time.perf_counter() - t0

    t0 = time.perf_counter()
    schedules = standard_schedules(schedule_seed, n_cycles)
    runs = [cell.simulate(s, int(run_seeds[1 + i])) for i, s in enumerate(schedules)]
    timings["simulate"] = time.perf_counter() - t0
    if out_dir is not None:
        for i, r in enumerate(runs):
            write_run(Path(out_dir) / f"run{i + 1}", cell, r, overwrite=True)

    t0 = time.perf_counter()
    problems = [screening_problem(cell, r, T_sensor_base=T_sb, P_e=P_e) for r in runs]
    timings["problems"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    screening = screen_parameters(problems[0], n_keep, threshold_mm=threshold_mm, statistic=statistic,
                                  **(screening_options or {}))
    timings["screening"] = time.perf_counter() - t0

    sets = {"traditional": traditional_parameters(model), "screened": screening.selected}
    report = None
    if stability > 0:
        from ...thermal.stability import screening_stability

        t0 = time.perf_counter()
        report = screening_stability(problems[0], stability, int(run_seeds[0]) + 1, n_keep=n_keep, full=screening,
                                     threshold_mm=threshold_mm, statistic=statistic, **(screening_options or {}))
        sets["stable"] = report.selected
        timings["stability"] = time.perf_counter() - t0
    online = {k: select_online_poses(problems[0], v, n_online_poses) for k, v in sets.items()}
    rows = [_row(i, r, p, sets, online, threshold_mm, statistic) for i, (r, p) in enumerate(zip(runs, problems))]
    timings["total"] = time.perf_counter() - t_start
    return {
        "rows": rows,
        "screening": screening,
        "traditional": sets["traditional"],
        "screened": sets["screened"],
        "online_poses": online,
        "lambda_screening_20": screening.lam,
        "stability": report,
        "system_calibration": calib,
        "frame_errors": ferr,
        "cell": cell,
        "runs": runs,
        "problems": problems,
        "settings": {"seed": seed, "schedule_seed": schedule_seed, "n_cycles": n_cycles,
                     "n_screen_poses": n_screen_poses, "n_online_poses": n_online_poses, "n_keep": n_keep,
                     "threshold_mm": threshold_mm, "statistic": statistic, "system_calibration": system_calibration,
                     "n_monitored_points": len(cell.q_monitor), "preset": cell.effects.name},
        "timings_s": timings,
    }


def _system_calibration(cell, n_poses: int, seed: int):
    """The sensor frame and sphere centre from the first ``n_poses`` cold sphere poses (least
    squares) and their errors against the cell's truth."""
    from ...thermal import calibrate_system, frame_errors

    q_sys = cell.q_sphere[:n_poses]
    P_s = cell.measure_sphere(q_sys, cell.robot.true_model.params.values, seed)
    calib = calibrate_system(cell.model, q_sys, P_s, point_sigma_mm=cell.sphere_noise_mm)
    ferr = frame_errors(calib.T_sensor_base, cell.T_sensor_base, calib.P_e, cell.P_e, at_base=cell.sphere_centre_base)
    return calib, ferr


def _row(i, run, problem, sets, online, threshold_mm, statistic) -> dict:
    """Table 5-2's row for run ``i``: lambda of no compensation and of every set (on its online
    poses), with ``statistic`` (the plain keys) and with both statistics (``lambda``)."""
    row = {"run": i + 1, "role": "screening" if i == 0 else "evaluation", "cycles": run.n_cycles,
           "hours": run.schedule.duration_s / 3600.0,
           "tcp_drift_3h_mm": float(np.interp(3 * 3600.0, run.timeline_s, run.tcp_drift_mm)),
           "tcp_drift_max_mm": float(run.tcp_drift_mm.max()), "lambda": {"rms": {}, "max": {}}}
    residuals = {"before": problem.residuals(())}
    for k, names in sets.items():
        residuals[k] = problem.with_poses(online[k]).residuals(names)
    for k, r in residuals.items():
        for st in ("rms", "max"):
            row["lambda"][st][k] = lambda_metric(r, threshold_mm, st)
        row[k] = lambda_metric(r, threshold_mm, statistic)
    return row


def format_thermal_table(result: dict) -> str:
    """Table 5-2: lambda [%] before / traditional / screened for every run."""
    s = result["settings"]
    lines = [f"share of monitored directions with {s['statistic']} residual < {s['threshold_mm']:g} mm (lambda, %); "
             f"{s['n_monitored_points']} points, {s['n_online_poses']} sphere poses online",
             f"{'run':>3}  {'role':<10} {'cycles':>6} {'hours':>5} {'TCP 3h mm':>9}  {'before':>7} {'traditional':>11} "
             f"{'screened':>8}"]
    for r in result["rows"]:
        lines.append(f"{r['run']:>3}  {r['role']:<10} {r['cycles']:>6} {r['hours']:>5.2f} "
                     f"{r['tcp_drift_3h_mm']:>9.3f}  "
                     f"{r['before']:>7.2f} {r['traditional']:>11.2f} {r['screened']:>8.2f}")
    lines.append(f"traditional: {', '.join(result['traditional'])}")
    lines.append(f"screened:    {', '.join(result['screened'])}")
    return "\n".join(lines)


def format_thermal_report(result: dict) -> str:
    """The screening table (5-1), the comparison table (5-2) and the system calibration."""
    parts = [result["screening"].format_table(), "", format_thermal_table(result)]
    fe = result.get("frame_errors")
    if fe:
        parts += ["", "system calibration (9 cold poses, least squares) against the truth: " +
                  ", ".join(f"{k} {v:.4g}" for k, v in fe.items() if isinstance(v, (int, float)))]
    t = result["timings_s"]
    parts += ["", "timings: " + ", ".join(f"{k} {v:.3f} s" for k, v in t.items())]
    return "\n".join(parts)
