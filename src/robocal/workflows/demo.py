"""`robocal demo`: the accuracy-maintenance cycle on a simulated robot.

A virtual KUKA KR150 R3100 whose true kinematic parameters differ from the nominal ones by
realistic manufacturing tolerances (lengths ~0.5 mm, angles ~0.05 deg, joint offsets ~0.05 deg):

1. **the problem**: it repeats a pose to a few hundredths of a millimetre but reaches computed
   poses only to millimetres;
2. **geometric calibration**: a laser-tracker campaign written to a measurement file, calibrated
   with ``robocal calibrate`` (held-out poses), and the accuracy reached over the workspace;
3. **thermal compensation**: production with heating; the parameters heat really moves are
   screened on one run and re-identified online from 6 sphere poses on others;
4. **a collision**: the tool is bent; the cross-laser cell recalibrates it.

Every step is recorded in a history database; the numbers go to ``demo_result.json``, the plots
to ``report.html``.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from ..io.atomic import atomic_write_text
from .outputs import check_outputs_free, ensure_writable_dir, staged_outputs
from ..metrics import error_statistics
from ..robots import load_robot
from ..sim import LaserTracker, VirtualRobot

__all__ = ["run_demo", "write_json"]

REFLECTOR_MM = (30.0, 40.0, 100.0)


def write_json(path, data, overwrite: bool = True) -> Path:
    """Write JSON atomically (temporary file, then rename)."""
    return atomic_write_text(path, json.dumps(data, indent=2) + "\n", overwrite=overwrite)


def _problem(nominal, virtual, rng, n_poses, n_repeats):
    q = virtual.feasible_configurations(n_poses, rng, margin=0.1)
    T_true = virtual.reach(q, rng)
    T_nominal = nominal.fk(q)
    err = np.linalg.norm(T_true[:, :3, 3] - T_nominal[:, :3, 3], axis=1)
    reach = np.linalg.norm(T_nominal[:, :2, 3], axis=1)
    p_rep = virtual.reach(np.repeat(q[:1], n_repeats, axis=0), rng)[:, :3, 3]
    repeat = np.linalg.norm(p_rep - p_rep.mean(axis=0), axis=1)
    bins = np.quantile(reach, [0.0, 1 / 3, 2 / 3, 1.0])
    by_reach = []
    for lo, hi in zip(bins[:-1], bins[1:]):
        sel = (reach >= lo) & (reach <= hi)
        by_reach.append({"reach_mm": [float(lo), float(hi)], **error_statistics(err[sel])})
    return q, T_nominal, err, {
        "accuracy_mm": error_statistics(err),
        "accuracy_by_reach_mm": by_reach,
        "repeatability_mm": {"max_deviation": float(repeat.max()), "rms_deviation": float(np.sqrt(np.mean(repeat**2)))},
    }


def _geometric_calibration(nominal, virtual, q_work, out, seed):
    from .calibration.calibrate import run_calibration

    tracker = LaserTracker.placed(seed + 1, reflectors=np.atleast_2d(REFLECTOR_MM), sigma_mm=0.02)
    meas_path, truth_path = out / "tracker_campaign.csv", out / "tracker_campaign.truth.json"
    tracker.campaign(virtual, 100, seed + 2, measurements_path=meas_path, truth_path=truth_path, overwrite=True,
                     margin=0.1)
    run = run_calibration(nominal.name, meas_path, out / "calibration", holdout=0.2, seed=seed, sigma_mm=0.02,
                          overwrite=True)
    run["T_tracker_world"] = tracker.T_tracker_world
    res, prob = run["calibration_result"], run["problem"]
    # accuracy over the whole workspace: the calibrated model against the true robot, at the
    # reflector, in the tracker frame (what the instrument sees)
    p_true = tracker.true_points(virtual, q_work).reshape(len(q_work), -1, 3)
    p_cal = prob.predict_points(res.state, q=q_work)
    err_after = np.linalg.norm(p_cal - p_true, axis=-1).ravel()
    return run, {
        "poses_measured": 100,
        "tracker_noise_mm": 0.02,
        "held_out": run["result"].get("validation", {}),
        "workspace_accuracy_mm": {"after": error_statistics(err_after)},
        "identified": len(res.identifiability.identifiable),
        # the calibration's own numbers, for the history: its estimated parameters and its residuals
        "parameters": [p for p in run["result"]["model_parameters"] if p["estimated"]],
        "residuals_mm": {"before": run["result"]["residuals"]["before"]["rms"],
                         "after": run["result"]["residuals"]["after"]["rms"]},
        "not_identifiable": [d["name"] for d in res.identifiability.dropped],
        "files": {k: str(v) for k, v in run["files"].items() if v is not None},
    }, err_after


def _iso_before_after(stage, nominal, virtual, run, seed) -> dict:
    """The ISO 9283 test (10 pose cycles, 3 path cycles, no drift run: a demo's length) run by the
    true robot with the nominal program and with the program corrected by the calibration; a
    15 um + 6 um/m tracker 3 m in front of the cube. Writes ``iso9283/`` (plan, both runs, the
    evaluation) and returns the comparison per characteristic [mm | deg]."""
    from ..io.iso9283_files import read_iso_measurements, write_iso_measurements
    from ..performance.adequacy import parse_mpe
    from ..sim.iso9283 import simulate_iso_run
    from .performance.iso9283_evaluate import compare_runs, evaluate_iso_run
    from .performance.iso9283_plan import build_iso_plan, write_iso_plan
    from .performance.iso9283_report import write_iso_outputs
    from .performance.iso9283_simulate import corrected_plan

    T_tool = np.eye(4)
    T_tool[:3, 3] = REFLECTOR_MM
    plan = build_iso_plan(nominal, T_flange_tool=T_tool, cycles=10, path_cycles=3)
    folder = stage / "iso9283"
    write_iso_plan(folder, plan, nominal, overwrite=True)
    mpe = parse_mpe("15um+6um/m")
    station = np.asarray(plan["cube"]["centre_mm"]) + [3000.0, 0.0, 0.0]
    res = run["calibration_result"]
    # the plant registers its tracker to the calibrated base frame (the calibration's [base]): the
    # true robot's base placed in that frame; both programs are judged there (a base-frame offset
    # the calibration cannot tell from theta1 / d1 is the cell's registration, not the robot's)
    T_calbase_world = np.linalg.inv(res.model.T_world_base) @ run["T_tracker_world"]
    true = virtual.true_model.replace(T_world_base=T_calbase_world @ virtual.true_model.T_world_base)
    T_identified = np.eye(4)
    T_identified[:3, 3] = np.asarray(res.state.targets, float)[0]
    runs = []
    for name, protocol in (("before", plan), ("after", corrected_plan(plan, res.model, T_identified))):
        rows, _ = simulate_iso_run(true, protocol, seed=np.random.default_rng(seed + 11), mpe=mpe,
                                   instrument_at_mm=station, in_world=True)
        path = write_iso_measurements(folder / f"{name}.csv", rows, overwrite=True)
        runs.append(evaluate_iso_run(plan, read_iso_measurements(path), mpe=mpe, instrument_at_mm=station))
    comparison = compare_runs(runs[0], runs[1])
    write_iso_outputs(folder / "evaluation", {"format": "robocal-iso9283-result/1", "robot": nominal.name,
                                              "runs": runs, "comparison": comparison,
                                              "instrument": {"mpe": mpe.text, "instrument_at_mm": station.tolist()},
                                              "conditions": plan["conditions"]}, overwrite=True)
    return {"cube_edge_mm": plan["cube"]["edge_mm"], "cycles": 10, "path_cycles": 3, "comparison": comparison,
            "folder": str(folder)}


def _thermal(seed):
    """Production with heating: screening on run 1, online compensation on runs 2 and 3."""
    from .thermal.runs import run_thermal_experiment

    exp = run_thermal_experiment(seed=seed, preset="realistic")  # the figures a user will see (issue 11)
    names = list(exp["screened"])
    run2 = exp["problems"][1].with_poses(exp["online_poses"]["screened"])
    deltas = run2.identify(names)  # (cycles, k) identified from 6 sphere poses per cycle
    model = exp["cell"].model
    units = [model.params.units[model.params.index(n)] for n in names]
    ev = run2.evaluate(names)
    times = run2.times_s if run2.times_s is not None else np.arange(deltas.shape[0]) * 180.0
    cycles = []
    for c in range(0, deltas.shape[0], 10):  # every 10th production cycle goes to the history
        within = np.abs(ev.residuals[c]) < 0.1  # this cycle's monitored directions within 0.1 mm
        cycles.append({"cycle": c, "time_s": float(times[c]), "names": names, "deltas": deltas[c].tolist(),
                       "units": units, "lambda_percent": 100.0 * float(within.mean())})
    return {
        "rows": exp["rows"],
        "screened": names,
        "traditional": list(exp["traditional"]),
        "screening_table": [{"step": st.step, "removed": st.removed, "lambda_percent": st.lam}
                            for st in exp["screening"].steps],
        "cycles": cycles,
        "note": "thermal cell simulated on its own KR150 (seed-derived), realistic preset (effects outside the model, docs/thermal.md); 34 monitored points",
    }


def _tool_recalibration(seed):
    from .tool.recalibration import tcp_repeatability_study

    study = tcp_repeatability_study(collisions=1, seed=seed, robot=None, variants={"beta_corrected": {}})
    run = study["variants"]["beta_corrected"]["runs"][0]
    return {
        "collision": {k: v for k, v in study["collisions"][0].items() if k != "T_flange_tool_true"},
        "sensor": study["sensor"],
        "tcp_error_mm": run["tcp_error_mm"],
        "axis_error_deg": run["axis_error_deg"],
        "cycle_time_s": run["cycle_time_s"],
        "cell": "cross-laser light barriers, beta 88 deg, tilted 2 deg; I/O 1 kHz; repeatability 0.1 mm; "
                "flange motions generated in Cartesian space",
    }


def _record_history(store_path, robot_name, result, campaign_path):
    """Record the demo's cycles in a fresh history database at ``store_path``.

    The demo's production time is simulated: the clock is laid out so that the last cycle ends
    now (never in the future), and every cycle says so (notes and ``meta.clock = "simulated"``).
    The geometric calibration records the tracker campaign's poses as its measurements; the
    thermal cycles record the number of sphere poses they used in ``meta``.
    """
    from datetime import datetime, timedelta, timezone

    from ..io.measurements import read_measurements
    from ..store import HistoryStore

    Path(store_path).unlink(missing_ok=True)  # a fresh history (the demo writes into an empty staging folder)
    thermal = result.get("thermal", {}).get("cycles") or []
    production_s = (thermal[-1]["time_s"] if thermal else 0.0) + 600.0
    now = datetime.now(timezone.utc).replace(microsecond=0)
    t_cal = now - timedelta(seconds=production_s + 3600.0)  # the calibration an hour before production
    meta = {"clock": "simulated", "source": "robocal demo"}
    meas = read_measurements(campaign_path)
    with HistoryStore.open(store_path) as store:
        g = result["geometric_calibration"]
        with store.cycle(robot_name, "geometric_calibration", started_at=t_cal, finished_at=t_cal, meta=meta,
                         notes="robocal demo (simulated time): laser-tracker campaign") as c:
            c.add_measurements(meas.joints, meas.points[:, 0], sensor="laser tracker (simulated)")
            params = g.get("parameters") or []
            if params:  # the calibration's own estimates: change from nominal, value, std
                c.add_parameters([p["name"] for p in params], [p["change"] for p in params],
                                 units=[p["unit"] for p in params], values=[p["calibrated"] for p in params],
                                 std=[p["std"] for p in params])
            if g.get("residuals_mm"):  # its own residuals on the calibration poses
                c.add_metric("residual_rms_before", g["residuals_mm"]["before"], "mm")
                c.add_metric("residual_rms_after", g["residuals_mm"]["after"], "mm")
            # the simulator's truth: nominal and calibrated model against the true robot over the workspace
            c.add_metric("workspace_error_nominal_rms", result["accuracy_mm"]["rms"], "mm")
            c.add_metric("workspace_error_calibrated_rms", g["workspace_accuracy_mm"]["after"]["rms"], "mm")
        start = now - timedelta(seconds=production_s)
        for cyc in thermal:
            t = start + timedelta(seconds=cyc["time_s"])
            with store.cycle(robot_name, "thermal_compensation", started_at=t, finished_at=t,
                             meta={**meta, "sphere_poses": 6},
                             notes=f"robocal demo (simulated time): production cycle {cyc['cycle']}, "
                                   f"6 sphere poses") as c:
                c.add_parameters(cyc["names"], cyc["deltas"], units=cyc["units"])
                c.add_metric("lambda", cyc["lambda_percent"], "%")
        t = result["tool_recalibration"]
        with store.cycle(robot_name, "tool_recalibration", started_at=now, finished_at=now, meta=meta,
                         notes="robocal demo (simulated time): after a collision") as c:
            c.add_metric("tcp_error", t["tcp_error_mm"], "mm")
            c.add_metric("cycle_time", t["cycle_time_s"], "s")
    return str(store_path)


#: What the demo writes into its folder; none is replaced without ``overwrite``.
DEMO_OUTPUTS = ("report.html", "demo_result.json", "accuracy_map.png", "accuracy_map_calibrated.png", "history.png",
                "history.sqlite", "tracker_campaign.csv", "tracker_campaign.truth.json", "calibration", "iso9283")


def run_demo(out_dir, *, robot: str = "kuka_kr150_r3100", seed: int = 7, n_poses: int = 500,
             n_repeats: int = 30, progress=None, history: bool = True, overwrite: bool = False) -> dict:
    """Run the maintenance cycle on a simulated robot; write results into ``out_dir``.

    Returns a dict with every number (mm, deg, s) and the paths written. ``progress(step, total,
    text)`` is called between steps when given. An existing output (:data:`DEMO_OUTPUTS`) raises
    ``FileExistsError`` before any work unless ``overwrite``; an unwritable folder raises
    :class:`~robocal.workflows.outputs.OutputError` naming it.
    """
    out = Path(out_dir)
    check_outputs_free(out, DEMO_OUTPUTS, overwrite)
    ensure_writable_dir(out)
    step = progress or (lambda i, n, text: None)
    total = 6
    nominal = load_robot(robot)
    step(1, total, f"the problem: virtual {nominal.title or nominal.name} with hidden true parameters (seed {seed})")
    # encoder noise 0.0005 deg per joint: about the +-0.06 mm repeatability KUKA states for this arm
    virtual = VirtualRobot.perturbed(nominal, seed, joint_noise_deg=0.0005)
    rng = np.random.default_rng(seed)
    q_work, T_nominal, err, problem = _problem(nominal, virtual, rng, n_poses, n_repeats)
    result = {"robot": nominal.name, "seed": seed, "n_poses": n_poses, **problem,
              "parameter_errors": virtual.parameter_errors()}

    with staged_outputs(out, DEMO_OUTPUTS, overwrite=overwrite) as stage:  # all or nothing, like calibrate
        result = _run_in(stage, out, step, total, nominal, virtual, q_work, T_nominal, err, result, seed, n_poses,
                         history)
    return result


def _run_in(stage, out, step, total, nominal, virtual, q_work, T_nominal, err, result, seed, n_poses, history):
    """Steps 2-6 of :func:`run_demo`, writing into the staging folder ``stage``; the paths in the
    returned result name their final place in ``out``."""
    step(2, total, "geometric calibration: 100-pose laser-tracker campaign -> robocal calibrate (20 % held out)")
    run, result["geometric_calibration"], err_after = _geometric_calibration(nominal, virtual, q_work, stage, seed)

    step(3, total, "production with heating: parameter screening, online compensation from 6 sphere poses")
    result["thermal"] = _thermal(seed)

    step(4, total, "a collision bends the tool: cross-laser recalibration")
    result["tool_recalibration"] = _tool_recalibration(seed)

    step(5, total, "ISO 9283 pose and path test before and after the calibration (the true robot runs both)")
    result["iso9283"] = _iso_before_after(stage, nominal, virtual, run, seed)

    step(5, total, "recording the cycles in the history database")
    if history:
        result["history"] = _record_history(stage / "history.sqlite", nominal.name, result,
                                            stage / "tracker_campaign.csv")

    step(6, total, "writing the report")
    report, before_png, after_png = _write_report(stage, nominal.name, result, run, T_nominal, err, err_after,
                                                  n_poses, history)
    result["files"] = {"report": str(report), "accuracy_map": str(before_png),
                       "accuracy_map_calibrated": str(after_png), "result": str(stage / "demo_result.json"),
                       "calibration": result["geometric_calibration"]["files"]}
    result = _relocated(result, str(stage), str(out))
    write_json(stage / "demo_result.json", result)
    return result


def _relocated(value, old: str, new: str):
    """``value`` (nested dicts, lists, strings) with every path under ``old`` moved to ``new``."""
    if isinstance(value, dict):
        return {k: _relocated(v, old, new) for k, v in value.items()}
    if isinstance(value, list):
        return [_relocated(v, old, new) for v in value]
    if isinstance(value, str) and value.startswith(old):
        return new + value[len(old):]
    return value


def _history_plot(out, robot_name, store_path):
    """The drift-over-time plot of the demo's history database: ``{section title: PNG path}``."""
    from ..report.history_plot import plot_history
    from ..store import HistoryStore

    with HistoryStore.open(store_path, create=False) as store:
        cycles = store.cycles(robot_name)
        params = store.parameter_history(robot_name)
        metrics = {m: store.metric_history(robot_name, m) for m in store.metric_names(robot_name)}
    events = [(c.started_at, c.kind) for c in cycles if c.status == "committed"]
    return {"Maintenance history: thermal parameter drift and cycle metrics": plot_history(
        params, metrics, out / "history.png", f"{robot_name}: drift over time", events=events)}


def _summary_tables(result, n_poses):
    """The report's tables: the cycle in numbers, and the thermal lambda per run."""
    acc, rep = result["accuracy_mm"], result["repeatability_mm"]
    after = result["geometric_calibration"]["workspace_accuracy_mm"]["after"]
    tool = result["tool_recalibration"]
    return {
        "The maintenance cycle in numbers": (["step", "figure", "value"], [
            ["1 the problem", f"nominal model error over {n_poses} poses (RMS / max)",
             f"{acc['rms']:.3f} / {acc['max']:.3f} mm"],
            ["1 the problem", "repeatability at one pose (max deviation)", f"{rep['max_deviation']:.3f} mm"],
            ["2 geometric calibration", "calibrated model vs the true robot, same poses (RMS / max)",
             f"{after['rms']:.4f} / {after['max']:.4f} mm"],
            ["4 tool recalibration", "TCP error / axis error / cycle time",
             f"{tool['tcp_error_mm']:.3f} mm / {tool['axis_error_deg']:.3f} deg / {tool['cycle_time_s']:.1f} s"],
        ]),
        "3 Thermal compensation: monitored directions within 0.1 mm (lambda, %)": (
            ["run", "role", "TCP drift after 3 h [mm]", "before", "traditional set", "screened set"],
            [[r_["run"], r_["role"], f"{r_['tcp_drift_3h_mm']:.3f}", f"{r_['before']:.1f}", f"{r_['traditional']:.1f}",
              f"{r_['screened']:.1f}"] for r_ in result["thermal"]["rows"]]),
    }


def _write_report(out, robot_name, result, run, T_nominal, err, err_after, n_poses, history):
    """``report.html`` with the accuracy maps before/after calibration (and the history plot);
    returns the paths of the report and the two maps."""
    from ..report.html import write_report
    from ..report.plots import plot_accuracy_map

    extra = _history_plot(out, robot_name, result["history"]) if history else {}
    rep_max = result["repeatability_mm"]["max_deviation"]
    before_png = plot_accuracy_map(T_nominal[:, :3, 3], err, out / "accuracy_map.png",
                                   f"{robot_name}: nominal model error over {n_poses} poses", repeatability_mm=rep_max)
    after_png = plot_accuracy_map(T_nominal[:, :3, 3], err_after, out / "accuracy_map_calibrated.png",
                                  f"{robot_name}: calibrated model error over the same poses", repeatability_mm=rep_max)
    report = write_report(out / "report.html", run["result"], overwrite=True,
                          extra_tables=_summary_tables(result, n_poses),
                          title=f"robocal demo: keeping a simulated {robot_name} accurate",
                          extra_plots={"Workspace accuracy of the nominal model": before_png,
                                       "Workspace accuracy after calibration": after_png, **extra})
    return report, before_png, after_png
