"""Tool-frame repeatability and accuracy over many cells (issue 11; thesis 5.2: 0.48 mm RMS).

:func:`tcp_accuracy_study`, per seed: one UR10 cell with its realism drawn
(:class:`~robocal.sim.tool.barrier_effects.BarrierEffects`: absolute error of the robot, I/O clock,
latency and jitter, dirty beams, tool runout, the measuring arm), the cross-laser sensor
calibrated by the pin procedure in that same cell, one tool bent by a collision, and
``repeats`` recalibrations of that same tool, each on its own noise stream, by every method:

* ``cross_laser`` -- :func:`robocal.tcp.cross_laser.recalibrate_tool` (thesis 4.2);
* ``parallel_barriers`` -- (4-6, 4-7) through the same simulator on a two-beam rig
  (:mod:`robocal.sim.tool.parallel_barrier_cell`), its beam heights measured with the flange face.

Per seed and method: **repeatability** = rms distance of the ``repeats`` TCPs from their mean
(the spread over repeated calibrations of the same tool); **accuracy** = rms distance from the
true TCP; **check** = rms distance from what a measuring arm registered to the robot base reads
when the robot holds the calibrated TCP at a check point (the thesis's kind of figure: it carries
the robot's absolute error at the check pose and the arm's own error); the same for the tool axis
[deg]. Over the seeds: median and quartiles of each. :func:`format_accuracy_table` renders it.
"""

from __future__ import annotations

import time
from dataclasses import replace

import numpy as np

from ...robots import load_robot
from ...sim.tool.barrier_effects import BarrierEffects, MeasuringArm, cell_realism
from ...sim.tool.light_barrier import CrossLaserSensor, LightBarrierCell, simulate_sensor_calibration_points
from ...sim.tool.parallel_barrier_cell import ParallelBarrierRig, measure_beam_heights, record_parallel_barriers, straight_tool
from ...tcp.cross_laser import CrossLaserSettings, recalibrate_tool
from ...transforms import so3_exp, transforms_from
from ..stats import summarise

__all__ = ["METHODS", "THESIS_RMS_MM", "tcp_accuracy_study", "format_accuracy_table", "budget_presets",
           "tcp_error_budget"]

METHODS = ("cross_laser", "parallel_barriers")
#: thesis 5.2.3: rms of 10 TCP positions checked with a measuring arm
THESIS_RMS_MM = 0.48
UR10_Q_SEED = np.array([0.0, -1.2, 1.6, -1.97, -1.57, 0.0])
SENSOR_ORIGIN_MM = (-850.0, -170.0, 200.0)
R_CHECK = np.diag([1.0, -1.0, -1.0])                     # tool pointing down at the check


def _rms(d) -> float:
    return float(np.sqrt(np.mean(np.sum(np.atleast_2d(d) ** 2, axis=-1))))


def _angle_deg(a, b) -> np.ndarray:
    return np.degrees(np.arccos(np.clip(np.einsum("ij,j->i", np.atleast_2d(a), b), -1.0, 1.0)))


def _check_tcp(T_true_tool, tcp_cal, accuracy, arm, repeatability_mm, rng) -> np.ndarray:
    """The TCP (3,) [mm, flange] a measuring arm finds when the robot holds ``tcp_cal`` at the
    check point: the controller reports the commanded flange; the arm reads the real tip."""
    p_chk = np.array(SENSOR_ORIGIN_MM) + [150.0, 0.0, 150.0]
    T_cmd = transforms_from(R_CHECK, p_chk - R_CHECK @ tcp_cal)
    R_act, p_act = T_cmd[:3, :3], T_cmd[:3, 3] + rng.normal(0.0, repeatability_mm / 3.6, 3)
    if accuracy is not None:
        w, d = accuracy.errors(T_cmd[None])
        R_act, p_act = so3_exp(w[0]) @ R_act, p_act + d[0]
    tip = R_act @ T_true_tool[:3, 3] + p_act
    return R_CHECK.T @ (arm.probe(tip) - T_cmd[:3, 3])


def _metrics(tcps, axes, checks, T_true) -> dict:
    """Repeatability, accuracy and check figures (module docstring) of one seed and method."""
    tcps, axes = np.asarray(tcps), np.asarray(axes)
    mean_axis = axes.mean(axis=0) / np.linalg.norm(axes.mean(axis=0))
    return {"repeatability_mm": _rms(tcps - tcps.mean(axis=0)),
            "accuracy_mm": _rms(tcps - T_true[:3, 3]),
            "bias_mm": float(np.linalg.norm(tcps.mean(axis=0) - T_true[:3, 3])),
            "check_mm": _rms(tcps - np.asarray(checks)),
            "axis_repeatability_deg": float(np.sqrt(np.mean(_angle_deg(axes, mean_axis) ** 2))),
            "axis_accuracy_deg": float(np.sqrt(np.mean(_angle_deg(axes, T_true[:3, 2]) ** 2)))}


def _one_seed(seed: int, effects: BarrierEffects, repeats: int, methods, model, settings) -> dict:
    """Every method on one cell (module docstring)."""
    s_cell, s_tool, s_cal, s_arm, s_pb, s_rep = np.random.SeedSequence([int(seed), 11]).spawn(6)
    T_nom = transforms_from(np.eye(3), np.asarray(SENSOR_ORIGIN_MM, float))
    sensor = CrossLaserSensor.build(T_nom, beta_deg=88.0, gap_mm=0.3, tilt_deg=2.0, tilt_axis_deg=30.0, yaw_deg=0.5)
    rng_cell = np.random.default_rng(s_cell)
    real = cell_realism(effects, sensor.beams, rng_cell, robot=model, q_seed=UR10_Q_SEED)
    kw = {**effects.cell_kwargs(), **real}
    tool0 = straight_tool()
    rng_tool = np.random.default_rng(s_tool)
    bent, _ = tool0.collided(rng_tool)
    t, a = bent.tcp_flange_mm, bent.axis_flange  # the collision's TCP off the tool axis (what (4-6, 4-7) miss) [mm]
    off_axis_mm = float(np.linalg.norm(t - (t @ a) * a))
    if effects.runout_mm > 0 or effects.runout_deg > 0:
        bent = bent.with_runout(effects.runout_mm, effects.runout_deg, rng_tool)
    arm = MeasuringArm(effects.arm_noise_mm, effects.arm_registration_mm, effects.arm_registration_deg,
                       np.random.default_rng(s_arm))
    rep_seeds = s_rep.spawn(int(repeats))
    out = {"seed": int(seed), "tcp_true_mm": bent.tcp_flange_mm.tolist(), "tcp_off_axis_mm": off_axis_mm}
    T_true = bent.T_flange_tool
    if "cross_laser" in methods:
        from ...tcp.sensor import calibrate_sensor

        pts, _ = simulate_sensor_calibration_points(sensor, T_nom, np.random.default_rng(s_cal), **kw)
        cal = calibrate_sensor(pts)
        tcps, axes, checks, cycle = [], [], [], []
        for k in range(int(repeats)):
            rng = np.random.default_rng(rep_seeds[k])
            res = recalibrate_tool(LightBarrierCell(sensor, bent, rng, **kw), cal, tool0.T_flange_tool, settings)
            tcps.append(res.tcp_flange_mm)
            axes.append(res.axis_flange)
            checks.append(_check_tcp(T_true, res.tcp_flange_mm, real.get("accuracy"), arm, effects.repeatability_mm,
                                     rng))
            cycle.append(res.cycle_time_s)
        out["cross_laser"] = {**_metrics(tcps, axes, checks, T_true), "cycle_s": float(np.mean(cycle))}
    if "parallel_barriers" in methods:
        out["parallel_barriers"] = _parallel(effects, bent, tool0, repeats, arm, T_true, s_pb, real)
    return out


def _parallel(effects, bent, tool0, repeats: int, arm, T_true, seed, real) -> dict:
    """The parallel-barrier method on its rig in the same cell (same robot, same I/O); ``seed``:
    a SeedSequence for its dirt, heights and repeats."""
    from ...tcp.parallel_barriers import parallel_barriers_tool

    rig = ParallelBarrierRig()
    s_dirt, s_h, s_rep = seed.spawn(3)
    dirt = cell_realism(BarrierEffects(dirt_fraction_max=effects.dirt_fraction_max, beam_width_mm=effects.beam_width_mm),
                        rig.beams(), np.random.default_rng(s_dirt)).get("dirt")
    kw = {**effects.cell_kwargs(), "accuracy": real.get("accuracy"), "dirt": dirt}
    h_up, h_down = measure_beam_heights(rig, np.random.default_rng(s_h), **kw)
    tcps, axes, checks, cycle = [], [], [], []
    for s in s_rep.spawn(int(repeats)):
        rng = np.random.default_rng(s)
        rec, t = record_parallel_barriers(LightBarrierCell(rig.beams(), bent, rng, **kw), rig, tool0.T_flange_tool,
                                          h_up, h_down)
        res = parallel_barriers_tool(**rec)
        tcps.append(res.tcp_mm)
        axes.append(res.axis)
        checks.append(_check_tcp(T_true, res.tcp_mm, real.get("accuracy"), arm, effects.repeatability_mm, rng))
        cycle.append(t)
    return {**_metrics(tcps, axes, checks, T_true), "cycle_s": float(np.mean(cycle))}


def tcp_accuracy_study(*, preset="realistic", seeds: int = 20, first_seed: int = 1, repeats: int = 10,
                       methods=METHODS, settings: CrossLaserSettings | None = None, progress=None) -> dict:
    """Run the study (module docstring) for seeds ``first_seed ..``; ``preset``: ``"ideal"``,
    ``"realistic"`` or a :class:`BarrierEffects`. Returns ``settings``, ``per_seed`` (every
    metric per method, the true TCP ``tcp_true_mm`` and its distance from the bent tool's axis
    ``tcp_off_axis_mm``), ``summary`` (``{method: {metric: {median, q25, q75, min, max, n}}}``),
    ``thesis_rms_mm`` and ``elapsed_s``."""
    if seeds < 1 or repeats < 2:
        raise ValueError(f"need seeds >= 1 and repeats >= 2, got {seeds}, {repeats}")
    bad = [m for m in methods if m not in METHODS]
    if bad:
        raise ValueError(f"unknown method(s) {bad}; choose from {', '.join(METHODS)}")
    effects = BarrierEffects.preset(preset)
    model = load_robot("ur10") if effects.robot_length_sigma_mm > 0 or effects.robot_angle_sigma_deg > 0 else None
    settings = settings or CrossLaserSettings()
    t0 = time.perf_counter()
    per_seed = []
    for i in range(int(seeds)):
        if progress is not None:
            progress(i + 1, int(seeds), f"seed {first_seed + i}")
        per_seed.append(_one_seed(first_seed + i, effects, repeats, methods, model, settings))
    keys = [k for k in per_seed[0][methods[0]]]
    summary = {m: {k: summarise([s[m][k] for s in per_seed]) for k in keys} for m in methods}
    return {"settings": {"preset": effects.name, "effects": {k: v for k, v in vars(effects).items()},
                         "seeds": int(seeds), "first_seed": int(first_seed), "repeats": int(repeats),
                         "methods": list(methods)},
            "per_seed": per_seed, "summary": summary, "thesis_rms_mm": THESIS_RMS_MM,
            "elapsed_s": time.perf_counter() - t0}


def format_accuracy_table(res: dict) -> str:
    """Median [q25, q75] over the seeds of every figure, per method, next to the thesis."""
    s = res["settings"]
    lines = [f"tool-frame recalibration over {s['seeds']} cells (preset {s['preset']}), {s['repeats']} repeats of "
             f"the same bent tool per cell: median [q25, q75] over the cells; thesis: {res['thesis_rms_mm']} mm rms",
             f"{'method':<18} {'repeatability mm':>22} {'accuracy mm':>22} {'arm check mm':>22} "
             f"{'axis accuracy deg':>22} {'cycle s':>8}"]
    for m, v in res["summary"].items():
        cells = [f"{v[k]['median']:>7.3f} [{v[k]['q25']:.3f}, {v[k]['q75']:.3f}]"
                 for k in ("repeatability_mm", "accuracy_mm", "check_mm", "axis_accuracy_deg")]
        lines.append(f"{m:<18} " + " ".join(f"{c:>22}" for c in cells) + f" {v['cycle_s']['median']:>8.1f}")
    lines.append("(repeatability: rms spread of the repeats about their mean; accuracy: rms distance from the true "
                 "TCP; arm check: from what a registered measuring arm reads at a check pose)")
    return "\n".join(lines)


def budget_presets() -> dict:
    """The error budget's cells: ``ideal``, ideal plus each realistic error source alone, and
    ``realistic`` (name -> :class:`BarrierEffects`)."""
    i, r = BarrierEffects.ideal(), BarrierEffects.realistic()
    one = {
        "I/O 125 Hz, late, jitter": dict(io_rate_hz=r.io_rate_hz, latency_s=r.latency_s,
                                         latency_jitter_s=r.latency_jitter_s),
        "absolute error": dict(robot_length_sigma_mm=r.robot_length_sigma_mm,
                               robot_angle_sigma_deg=r.robot_angle_sigma_deg),
        "dirty beams": dict(dirt_fraction_max=r.dirt_fraction_max, beam_width_mm=r.beam_width_mm),
        "tool runout": dict(runout_mm=r.runout_mm, runout_deg=r.runout_deg),
        "measuring arm": dict(arm_noise_mm=r.arm_noise_mm, arm_registration_mm=r.arm_registration_mm,
                              arm_registration_deg=r.arm_registration_deg),
    }
    return {"ideal": i, **{k: replace(i, name=f"ideal + {k}", **v) for k, v in one.items()}, "realistic": r}


def tcp_error_budget(*, seeds: int = 10, first_seed: int = 1, repeats: int = 5, methods=("cross_laser",),
                     progress=None) -> dict:
    """:func:`tcp_accuracy_study` for every cell of :func:`budget_presets`: ``{name: summary}``
    (``{method: {metric: {median, q25, q75, ...}}}``), the same seeds for each."""
    out = {}
    for k, (name, fx) in enumerate(budget_presets().items()):
        if progress is not None:
            progress(k + 1, len(budget_presets()), name)
        out[name] = tcp_accuracy_study(preset=fx, seeds=seeds, first_seed=first_seed, repeats=repeats,
                                       methods=methods)["summary"]
    return out
