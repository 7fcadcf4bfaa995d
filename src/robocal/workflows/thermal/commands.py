"""The ``robocal thermal`` commands as workflows (thesis ch. 3 and 5.1; docs/thermal.md).

One function per command: :func:`simulate_thermal_cell` (``simulate``), :func:`calibrate_sensor`
(``calibrate-sensor``), :func:`screen_run` (``screen``) and :func:`compensate_program_files`
(``compensate``). Each takes plain arguments (file paths, names, numbers), reads and writes the
files, and returns the dict the command prints with ``--json``; keys starting with ``_`` carry
what only the console text needs (they are not part of the JSON). User errors (bad files, values,
names) raise ``ValueError``, ``KeyError`` or ``OSError`` with a one-line message; progress and
notes go to the optional ``progress(i, n, text)`` and ``note(text)`` callbacks. Inside, lengths
are mm and angles rad.
"""

from __future__ import annotations

import math
import time
from pathlib import Path

import numpy as np

from ...io.output_paths import check_outputs
from ...io.programs.joint_table import JointProgram, read_joint_program, write_joint_program
from ...io.thermal_files import read_sensor_json, read_sphere_file, read_truth_json, write_sensor_json, write_setup_json
from ...robots import load_robot
from ...sim.robot import as_rng
from ...sim.thermal.simulator import SPHERE_DIAMETER_MM, ThermalCell, standard_schedules, write_run
from .inputs import load_run_dir, match_cold_reference, select_poses

__all__ = ["RUN_FILES", "format_delta", "simulate_thermal_cell", "calibrate_sensor", "screen_run",
           "compensate_program_files"]

#: The files ``simulate`` writes into every run folder.
RUN_FILES = ("sphere_cold.csv", "sphere.csv", "monitor_cold.csv", "monitor.csv", "cycles.csv", "truth.json",
             "setup.json")


def _silent(*_args) -> None:
    """The default ``progress`` / ``note`` callback: report nothing."""


def _num(x):
    """A float, or None when it is NaN / inf (JSON null)."""
    x = float(x)
    return x if math.isfinite(x) else None


def _list(a) -> list:
    """The values of ``a`` (any shape) as a flat list of floats / None."""
    return [_num(v) for v in np.ravel(a)]


def _check_new(paths, overwrite: bool) -> None:
    """``FileExistsError`` for the first of ``paths`` that exists, unless ``overwrite``."""
    if overwrite:
        return
    for p in paths:
        if Path(p).exists():
            raise FileExistsError(f"{p}: file exists; pass --overwrite to replace it")


def _check_sigma(sigma_mm) -> None:
    """``ValueError`` unless ``sigma_mm`` [mm] is None or a positive finite number."""
    if sigma_mm is not None and not (sigma_mm > 0 and math.isfinite(sigma_mm)):
        raise ValueError(f"--noise must be a positive number of mm, got {sigma_mm}")


def format_delta(unit: str, value: float) -> str:
    """A parameter delta for printing: mm as is, rad in deg."""
    if unit == "rad":
        return f"{math.degrees(value):+.6f} deg"
    return f"{value:+.5f} {unit}"


# ---------------------------------------------------------------------------------------------- simulate
def _check_simulate_args(out: Path, n_cycles: int, n_sphere: int, overwrite: bool) -> None:
    if n_cycles < 2:
        raise ValueError(f"--cycles must be at least 2, got {n_cycles}")
    if n_sphere < 6:
        raise ValueError(f"--sphere-poses must be at least 6, got {n_sphere}")
    if out.exists() and not out.is_dir():
        raise NotADirectoryError(f"{out}: not a directory (--out is the folder for run1/, run2/, run3/)")
    _check_new([out / f"run{i}" / f for i in (1, 2, 3) for f in RUN_FILES] + [out / "program.csv"], overwrite)


def _simulate_run(cell, schedule, seed: int, i: int, d: Path, overwrite: bool) -> dict:
    """Simulate run ``i`` (0-based) into folder ``d``; its row of the summary (drifts [mm])."""
    run = cell.simulate(schedule, seed)
    write_run(d, cell, run, overwrite=overwrite)
    write_setup_json(d / "setup.json", cell.model.name, cell.T_flange_sensor, SPHERE_DIAMETER_MM, overwrite=overwrite)
    hours = schedule.duration_s / 3600.0
    return {"run": i + 1, "role": "screening" if i == 0 else "evaluation", "cycles": run.n_cycles, "hours": hours,
            "tcp_drift_3h_mm": float(np.interp(3 * 3600.0, run.timeline_s, run.tcp_drift_mm)) if hours >= 3.0 else None,
            "tcp_drift_end_mm": float(run.tcp_drift_mm[-1]),
            "tcp_drift_max_mm": float(run.tcp_drift_mm.max()), "dir": str(d)}


def _write_taught_program(path: Path, cell, overwrite: bool) -> None:
    """The cell's monitored poses (34 x n joints) as a taught program (robocal-program/1)."""
    prog = JointProgram(cell.q_monitor, tuple(f"P{k + 1:02d}" for k in range(len(cell.q_monitor))),
                        cell.model.controller_joints,
                        {"robot": cell.model.name, "angle_unit": "deg", "program": "car_body",
                         "note": "taught on the cold robot: the 34 monitored car-body poses of the simulated cell"})
    write_joint_program(path, prog, cell.model, overwrite=overwrite)


def simulate_thermal_cell(out_dir, *, seed: int = 2024, schedule_seed: int = 7, n_cycles: int = 90,
                          n_sphere: int = 20, preset: str = "realistic", overwrite: bool = False,
                          progress=_silent) -> dict:
    """Simulate the thermal cell heating in three runs of ``n_cycles`` cycles and write them as
    measurement files (``out_dir/run1..run3/``, :data:`RUN_FILES`) with ``out_dir/program.csv``.

    Returns the settings, ``runs`` (one row per run: role, cycles, hours, TCP drift after 3 h, at
    the end and max [mm], folder) and ``program``; ``_sphere_noise_mm`` is the sensor noise [mm].
    """
    out = Path(out_dir)
    _check_simulate_args(out, n_cycles, n_sphere, overwrite)
    out.mkdir(parents=True, exist_ok=True)
    progress(1, 4, f"building the cell (seed {seed}, {n_sphere} sphere poses)")
    cell = ThermalCell.standard(seed, n_sphere_poses=n_sphere, preset=preset)
    run_seeds = as_rng(seed).integers(0, 2**31, 4)                     # as run_thermal_experiment
    rows = []
    for i, sch in enumerate(standard_schedules(schedule_seed, n_cycles)):
        progress(2 + i, 4, f"simulating run {i + 1} ({n_cycles} cycles) and writing {out / f'run{i + 1}'}")
        rows.append(_simulate_run(cell, sch, int(run_seeds[1 + i]), i, out / f"run{i + 1}", overwrite))
    _write_taught_program(out / "program.csv", cell, overwrite)
    return {"seed": seed, "schedule_seed": schedule_seed, "preset": preset, "robot": cell.model.name,
            "cycles": n_cycles, "sphere_poses": n_sphere, "monitored_points": len(cell.q_monitor), "runs": rows,
            "program": str(out / "program.csv"), "_sphere_noise_mm": cell.sphere_noise_mm}


# ---------------------------------------------------------------------------------------------- calibrate-sensor
def _cal_dict(cal) -> dict:
    """A :class:`~robocal.thermal.system_calibration.SystemCalibration` as JSON-ready data."""
    return {"method": cal.method, "n_poses": cal.n_poses, "T_sensor_base": cal.T_sensor_base.tolist(),
            "T_base_sensor": cal.T_base_sensor.tolist(), "P_e_mm": cal.P_e.tolist(),
            "std": {"rotation_deg": _list(np.degrees(cal.std_rotation_rad)),
                    "translation_mm": _list(cal.std_translation_mm), "P_e_mm": _list(cal.std_P_e_mm)},
            "residual_rms_mm": cal.rms_mm,
            "residual_max_mm": float(np.linalg.norm(cal.residuals_mm, axis=1).max()),
            "residuals_mm": cal.residuals_mm.tolist(), "converged": bool(cal.converged),
            "orthonormality_error": float(cal.orthonormality_error)}


def _system_calibrations(model, q, P, method: str, sigma_mm, truth):
    """The calibrations of ``method`` (least squares first with ``"both"``) and the comparison.

    q (N, n) joints [rad | mm]; P (N, 3) sphere centres in the sensor frame [mm]; truth None or
    ``{"T": (4, 4), "P_e": (3,)}``. Returns (list of calibrations, comparison or None)."""
    from ...thermal import calibrate_system, calibrate_system_thesis, compare_system_calibrations

    if method == "both":
        comp = compare_system_calibrations(model, q, P, point_sigma_mm=sigma_mm,
                                           T_sensor_base_true=None if truth is None else truth["T"],
                                           P_e_true=None if truth is None else truth["P_e"])
        return [comp.least_squares, comp.thesis], comp
    if method == "thesis":
        return [calibrate_system_thesis(model, q, P)], None
    return [calibrate_system(model, q, P, point_sigma_mm=sigma_mm)], None


def _truth_errors(model, q, cals, truth) -> dict:
    """Per method the frame errors against ``truth`` (empty without), evaluated at the centre of
    the true sphere positions of joints ``q`` (N, n) in the base frame."""
    if truth is None:
        return {}
    from ...thermal import frame_errors
    from ...thermal.system_calibration import _base_flange

    T = _base_flange(model, q)
    centre = (T[:, :3, :3] @ truth["P_e"] + T[:, :3, 3]).mean(axis=0)
    return {c.method: frame_errors(c.T_sensor_base, truth["T"], c.P_e, truth["P_e"], at_base=centre) for c in cals}


def _rms_note(rms_mm: float):
    """A note when the residual RMS [mm] is far above a sphere sensor's noise (else None)."""
    if not rms_mm > 0.1:
        return None
    return (f"residual RMS {rms_mm:.3f} mm is well above a sphere sensor's noise (~0.02 mm): "
            "the robot model's geometry errors are absorbed into T_sensor_base and P_e (harmless for drift "
            "compensation, which uses differences; use a calibrated robot file for an accurate frame)")


def _read_truth(truth_file):
    if not truth_file:
        return None
    t = read_truth_json(truth_file)
    return {"T": t["T_sensor_base"], "P_e": t["P_e"]}


def calibrate_sensor(robot, sphere_file, *, method: str = "lsq", sigma_mm=None, poses=(), truth_file=None,
                     out_file=None, overwrite: bool = False, allow_unconverged: bool = False) -> dict:
    """System calibration (thesis 3.3): ``T_sensor_base`` and ``P_e`` from the sphere file.

    method: ``"lsq"``, ``"thesis"`` or ``"both"``; sigma_mm: sensor noise per coordinate [mm] or
    None; poses: id patterns (all without). ``out_file`` is written (least squares first) only
    when the sanity gates pass. Returns ``results`` (one per method), ``errors`` against
    ``truth_file``, ``comparison``, ``out``, ``note``, ``status``, ``reasons``; ``_calibrations``
    holds the result objects. ``convergence``: of every method's fit; one that did not converge
    writes no ``out_file`` unless ``allow_unconverged``.
    """
    from ...calib.sanity import touchup_verdict
    from ..convergence import Convergence

    model = load_robot(robot)
    _check_sigma(sigma_mm)
    if out_file:
        check_outputs(out_file, {"the sphere file": sphere_file, "--truth": truth_file, "the robot file": robot},
                      overwrite=overwrite)
    meas = select_poses(read_sphere_file(sphere_file, model), poses, sphere_file)
    q, P = meas.joints, meas.points[:, 0]
    truth = _read_truth(truth_file)
    cals, comp = _system_calibrations(model, q, P, method, sigma_mm, truth)
    errors = _truth_errors(model, q, cals, truth)
    verdict = touchup_verdict(cals[0].rms_mm, cals[0].P_e, sigma_mm, what="system calibration")
    conv = Convergence.of([(c.method, c.converged, c.message) for c in cals],
                          "more sphere poses spread over the workspace and joint ranges, or --method lsq")
    write = bool(out_file) and verdict.ok and conv.may_write_model(allow_unconverged)
    if write:  # a failed or unconverged calibration writes no sensor file (exit code 3 or 4)
        write_sensor_json(out_file, cals[0], model, sphere_file, overwrite=overwrite)
    return {"robot": model.name, "file": sphere_file, "pose_ids": list(meas.pose_ids),
            "results": [_cal_dict(c) for c in cals], "errors": errors or None,
            "comparison": None if comp is None else {"difference": comp.difference, "table": comp.table()},
            "out": out_file if write else None, "note": _rms_note(cals[0].rms_mm), "status": verdict.status,
            "reasons": list(verdict.reasons), "convergence": conv.as_dict(), "_calibrations": cals}


# ---------------------------------------------------------------------------------------------- screen
def _sensor_frame(run: dict, model, sensor_file):
    """(T_sensor_base (4, 4), P_e (3,) [mm], description): from ``sensor_file`` or calibrated on
    the run's cold sphere poses."""
    from ...thermal import calibrate_system

    if sensor_file:
        s = read_sensor_json(sensor_file, model)
        return s["T_sensor_base"], s["P_e"], sensor_file
    cal = calibrate_system(model, run["q_sphere"], run["sphere_cold"])
    return (cal.T_sensor_base, cal.P_e,
            f"calibrated from sphere_cold.csv ({cal.n_poses} poses, residual RMS {cal.rms_mm:.3f} mm"
            + (")" if cal.converged else f"; NOT converged: {cal.message})"))


def _check_given_set(given, prob, model) -> None:
    """``KeyError`` / ``ValueError`` unless every name of ``given`` is a screening candidate, once."""
    for n in given:
        model.params.index(n)                                   # unknown names: suggestions
        if n not in prob.names:
            raise ValueError(f"parameter {n!r} is fixed in {model.name!r} (not a screening candidate); "
                             f"candidates: {', '.join(prob.names)}")
    if len(set(given)) != len(given):
        raise ValueError(f"--params names a parameter twice: {', '.join(given)}")


def _chosen_set(prob, model, given, n_keep: int, threshold_mm: float, statistic: str, progress):
    """(screening result or None, chosen names): ``given`` checked, or screened to ``n_keep``."""
    from ...thermal.screening import screen_parameters

    if given:
        _check_given_set(given, prob, model)
        progress(2, 3, f"evaluating the given set of {len(given)} on {prob.n_cycles} cycles")
        return None, tuple(given)
    if not 1 <= n_keep <= len(prob.names):
        raise ValueError(f"--keep must be in [1, {len(prob.names)}] (the free parameters), got {n_keep}")
    progress(2, 3, f"screening {len(prob.names)} -> {n_keep} parameters on {prob.n_cycles} cycles x "
                   f"{prob.n_poses} sphere poses")
    res = screen_parameters(prob, n_keep, threshold_mm=threshold_mm, statistic=statistic)
    return res, res.selected


def _online_lambda(prob, sets: dict, n_online: int, threshold_mm: float, statistic: str):
    """({set: online pose indices}, {column: lambda [%]}) for the parameter ``sets``."""
    from ...thermal.screening import select_online_poses

    online = {}
    for k, names in sets.items():
        if 3 * n_online < len(names):
            raise ValueError(f"--online-poses {n_online} gives {3 * n_online} equations, fewer than the "
                             f"{len(names)} {k} parameters")
        online[k] = select_online_poses(prob, names, n_online)
    lam = {"before": prob.evaluate((), threshold_mm, statistic).lam}
    for k, names in sets.items():
        lam[k] = prob.with_poses(online[k]).evaluate(names, threshold_mm, statistic).lam
    lam["screened_all_poses"] = prob.evaluate(sets["screened"], threshold_mm, statistic).lam
    return online, lam


def _load_screening_problem(run_dir, robot, sensor_file, setup_file, progress):
    """(run dict, problem, sensor description) of a run directory; robot None: the one it names."""
    from ...thermal.screening import ScreeningProblem

    model = None if robot is None else load_robot(robot)
    progress(1, 3, f"reading {run_dir}")
    run = load_run_dir(run_dir, model, setup=setup_file)
    T_sb, P_e, sensor_src = _sensor_frame(run, run["model"], sensor_file)
    prob = ScreeningProblem.from_measurements(run["model"], T_sb, P_e, run["q_sphere"], run["sphere_cold"],
                                              run["sphere"], run["q_monitor"], run["monitor_cold"], run["monitor"],
                                              run["T_flange_sensor"], times_s=run["times_s"])
    return run, prob, sensor_src


def screen_run(run_dir, *, n_keep: int = 8, threshold_mm: float = 0.1, statistic: str = "rms", n_online: int = 6,
               params=(), sensor_file=None, setup_file=None, robot=None, progress=_silent) -> dict:
    """Parameter screening (thesis 3.2, table 5-1) on a run directory, or with ``params`` (names)
    the evaluation of that set; then the best ``n_online`` sphere poses of the traditional and
    the chosen set and lambda [%] (share of monitored directions with ``statistic`` residual
    below ``threshold_mm`` [mm]) before / traditional / screened / screened on all poses.
    """
    from ...thermal.screening import traditional_parameters

    if not (threshold_mm > 0 and math.isfinite(threshold_mm)):
        raise ValueError(f"--threshold must be a positive number [mm], got {threshold_mm}")
    given = list(params)
    run, prob, sensor_src = _load_screening_problem(run_dir, robot, sensor_file, setup_file, progress)
    model = run["model"]
    if not 1 <= n_online <= prob.n_poses:
        raise ValueError(f"--online-poses must be in [1, {prob.n_poses}] (the run's sphere poses), got {n_online}")
    res, chosen = _chosen_set(prob, model, given, n_keep, threshold_mm, statistic, progress)
    progress(3, 3, f"choosing {n_online} online sphere poses and evaluating")
    trad = traditional_parameters(model)
    online, lam = _online_lambda(prob, {"traditional": trad, "screened": chosen}, n_online, threshold_mm, statistic)
    ids = run["sphere_ids"]
    return {"run_dir": run_dir, "robot": model.name, "mode": "evaluate" if res is None else "screen",
            "cycles": prob.n_cycles, "sphere_poses": prob.n_poses, "monitored_directions": prob.n_directions,
            "threshold_mm": threshold_mm, "statistic": statistic, "sensor": sensor_src,
            "steps": [] if res is None else res.table(), "selected": list(chosen), "traditional": list(trad),
            "online_poses": {k: [ids[i] for i in v] for k, v in online.items()},
            "lambda_percent": lam}


# ---------------------------------------------------------------------------------------------- compensate
def _point_rows(model, program, comp) -> list[dict]:
    """One dict per program point: drift before, residuals, largest joint correction [deg], ..."""
    corr_deg = np.degrees(np.abs(np.where(model.prismatic_joints, 0.0, comp.correction)).max(axis=1))
    return [{"point": n, "drift_before_mm": float(b), "residual_mm": float(r), "rotation_residual_rad": float(rr),
             "max_joint_correction_deg": float(c), "correction": comp.correction[i].tolist(),
             "iterations": int(it), "converged": bool(ok), "within_limits": bool(wl)}
            for i, (n, b, r, rr, c, it, ok, wl) in enumerate(zip(
                program.names, comp.drift_before_mm, comp.position_error_mm, comp.rotation_error_rad, corr_deg,
                comp.iterations, comp.converged, comp.within_limits))]


def _write_corrected(out_file, program_file, program, comp, drift, model, overwrite: bool) -> None:
    """The corrected program, its note naming the source and the identified deltas."""
    md = dict(program.metadata)
    md["note"] = ((md.get("note", "") + "\n") if md.get("note") else "") + (
        f"corrected for thermal drift by robocal thermal compensate from {Path(program_file).name}: "
        f"{', '.join(f'{n} {format_delta(u, d)}' for n, u, d in zip(drift.names, drift.units, drift.delta))}")
    write_joint_program(out_file, JointProgram(comp.q, program.names, program.joint_names, md), model,
                        overwrite=overwrite)


def _record_cycle(store, rid, model, meta, q_s, P_w, drift, comp, program, program_file, elapsed: float) -> int:
    """A ``thermal_compensation`` cycle in ``store``: the sphere measurements q_s (m, n), P_w
    (m, 3) [mm], the identified deltas, the metrics and the corrections; returns its id."""
    joint_units = ["mm" if p else "rad" for p in model.prismatic_joints]
    std = [None if not np.isfinite(s) else float(s) for s in drift.std]
    with store.cycle(rid, "thermal_compensation", robot_model=model.name, notes="robocal thermal compensate",
                     meta=meta) as c:
        c.add_measurements(q_s, P_w, target="sphere", sensor="fixed sensor", joint_units=joint_units)
        c.add_parameters(list(drift.names), drift.delta, units=list(drift.units),
                         values=(model.params.values[[model.params.index(n) for n in drift.names]]
                                 + drift.delta).tolist(), std=std)
        c.add_metrics({"residual_rms_before": (drift.rms_before_mm, "mm"),
                       "residual_rms_after": (drift.rms_after_mm, "mm"),
                       "condition_number": (float(drift.condition_number), "1"),
                       "rank": (float(drift.rank), "1"), "n_poses": (float(drift.n_poses), "1"),
                       "drift_before_max": (float(comp.drift_before_mm.max()), "mm"),
                       "compensated_error_max": (float(comp.position_error_mm.max()), "mm"),
                       "cycle_time": (float(elapsed), "s")})
        c.add_corrections(comp.q_taught, comp.q, program=Path(program_file).stem, point_names=list(program.names),
                          joint_units=joint_units)
    return c.id


def _check_history(history) -> None:
    """``ValueError`` naming the history database when it cannot be opened (nothing written yet)."""
    from ...store import HistoryError, HistoryStore, default_history_target

    db = history or default_history_target()
    try:
        with HistoryStore.open(db):
            pass
    except (HistoryError, ValueError, OSError) as exc:
        from ...store import redact_url

        raise ValueError(f"--history {redact_url(db)}: {exc}; nothing written") from None


def _record_history(history, robot_id, model, meta, out_file, *args):
    """(database, cycle id) after :func:`_record_cycle` in ``history`` ("": the default target);
    ``ValueError`` naming ``out_file`` (already written) when that fails."""
    from ...store import HistoryError, HistoryStore, default_history_target

    db = history or default_history_target()
    try:
        with HistoryStore.open(db) as store:
            cycle_id = _record_cycle(store, robot_id or model.name, model, meta, *args)
    except (HistoryError, ValueError, OSError) as exc:
        raise ValueError(f"{out_file} was written, but the history was not recorded: {exc}") from None
    return db, cycle_id


def _sphere_now(model, sphere_file, poses, cold_file, note):
    """(measurements, cold centres (m, 3) [mm] or None): the selected sphere poses and their cold
    reference matched by joints (None: predicted later by the model; ``note`` says so)."""
    meas = select_poses(read_sphere_file(sphere_file, model), poses, sphere_file)
    if not cold_file:
        note("note: no --cold reference: the cold sphere positions are predicted by the model and the sensor "
             "calibration (their errors enter the identified deltas)")
        return meas, None
    cold = read_sphere_file(cold_file, model, what="cold sphere")
    return meas, match_cold_reference(meas.joints, cold, cold_file, meas.pose_ids)


def _drift_json(drift) -> dict:
    """The identification part of the ``compensate`` JSON (std NaN -> None)."""
    return {"n_poses": drift.n_poses, "equations": 3 * drift.n_poses,
            "parameters": [{**row, "std": _num(row["std"])} for row in drift.table()],
            "rank": drift.rank, "condition_number": float(drift.condition_number),
            "singular_values": drift.singular_values.tolist(),
            "residual_rms_before_mm": drift.rms_before_mm, "residual_rms_after_mm": drift.rms_after_mm,
            "residuals_after_mm": drift.residuals_after_mm.tolist()}


def compensate_program_files(robot, *, sensor_file, sphere_file, params, program_file, out_file, poses=(),
                             cold_file=None, overwrite: bool = False, position_only: bool = False, sigma_mm=None,
                             history=None, robot_id=None, note=_silent, force: bool = False) -> dict:
    """Online compensation (thesis (3-8)-(3-10)): identify the deltas ``params`` (names) from the
    current sphere centres and write the corrected taught program to ``out_file``.

    history: None (no record), "" (the default database) or a path / URL: a
    ``thermal_compensation`` cycle is recorded there. Returns the identification (deltas [mm |
    rad], rank, residuals [mm]), ``points`` (per program point), ``elapsed_s`` and ``history``;
    ``_summary`` is the compensation's one-line summary. The identification passes the sanity
    gates (:func:`robocal.calib.sanity.drift_verdict`: residual vs noise, deltas within what heat
    does) or gets ``status`` "failed" with ``reasons``, and then no corrected program is written
    (no history record either) unless ``force``.
    """
    from ...calib.sanity import drift_verdict
    from ...thermal import compensate_program, identify_drift

    t_start = time.perf_counter()
    model = load_robot(robot)
    _check_sigma(sigma_mm)
    check_outputs(out_file, {"--program": program_file, "--sensor": sensor_file, "the sphere file": sphere_file,
                             "--cold": cold_file, "the robot file": robot,
                             "--history": history if history and "://" not in str(history) else None},
                  overwrite=overwrite)
    sensor = read_sensor_json(sensor_file, model)
    meas, P_c = _sphere_now(model, sphere_file, poses, cold_file, note)
    q_s, P_w = meas.joints, meas.points[:, 0]
    program = read_joint_program(program_file, model)
    drift = identify_drift(model, sensor["T_sensor_base"], sensor["P_e"], q_s, P_w, P_c, list(params),
                           point_sigma_mm=sigma_mm)
    comp = compensate_program(model, drift, program.joints, position_only=position_only)
    elapsed = time.perf_counter() - t_start
    verdict = drift_verdict(drift.names, drift.units, drift.delta, drift.rms_after_mm, sigma_mm)
    write = verdict.ok or force
    if write and history is not None:
        _check_history(history)  # a damaged database is named before the program is written
    if write:
        _write_corrected(out_file, program_file, program, comp, drift, model, overwrite)
    meta = {"sensor": sensor_file, "sphere": sphere_file, "cold": cold_file, "program": program_file, "out": out_file,
            "position_only": position_only, "pose_ids": list(meas.pose_ids)}
    db = cycle_id = None
    if history is not None and write:
        db, cycle_id = _record_history(history, robot_id, model, meta, out_file, q_s, P_w, drift, comp, program,
                                       program_file, elapsed)
    return {"robot": model.name, "sensor": sensor_file, "sphere": sphere_file, "cold": cold_file,
            "pose_ids": list(meas.pose_ids), **_drift_json(drift),
            "program": program_file, "out": out_file if write else None, "position_only": position_only,
            "status": verdict.status, "reasons": list(verdict.reasons),
            "angle_unit_of_corrections": "rad", "points": _point_rows(model, program, comp),
            "all_converged": comp.all_converged, "all_within_limits": bool(comp.within_limits.all()),
            "elapsed_s": elapsed, "history": None if db is None else {"db": str(db), "cycle_id": cycle_id},
            "_summary": comp.summary()}
