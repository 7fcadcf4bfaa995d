"""Producers of the documented figures of docs/testing.md, docs/closed-chain.md and docs/tcp.md measured
on the set-ups of tests (robocal.docs.figures): the closed-chain cell judged at the true robot, the
tracker campaign, the UR10 6-D campaign imported from vendor exports, the camera self-calibrations
and the hand-eye refinement on robots that differ from their models, the positioner's independent
reference fit, table 5-2 on six seeds, the tool-frame cells and the touch-up gate; closed-form
statistics quoted as expectations. The set-ups live in :mod:`robocal.sim` (and
:mod:`robocal.workflows.datasets.positioner_reference`) and are shared with the tests (same draws).
Each producer returns a flat ``{field: value}`` dict and is cached."""

from __future__ import annotations

import functools

__all__ = ["SLOW_TESTING_PRODUCERS", "TESTING_PRODUCERS", "closed_chain_effects", "closed_chain_effects_z",
           "closed_chain_held_sigma", "gaussian_formulas", "handeye_link_errors", "positioner_reference",
           "self_calibration_effects", "six_d_import", "tcp_realism_cells", "thermal_table_5_2", "touchup_gate",
           "tracker_effects"]


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


@functools.lru_cache(maxsize=None)
def six_d_import() -> dict:
    """docs/testing.md, the ``test_six_d_import.py`` rows (the set-up of its ``realistic`` fixture):
    the UR10 6-D campaign with the ``realistic`` effects (:func:`robocal.sim.six_d_exports.probe_campaign`,
    seed 11) written as a Leica T-Mac export and an RTDE log, ``robocal import ... --orientation rpy``,
    ``robocal calibrate ur10 --sigma 0.02 --holdout 0``, the first-order bias from the hidden truth
    (:func:`robocal.sim.first_order.six_d_fit_bias`); then ``robocal correct`` on 8 tool-pose targets
    (seed 99) and the true robot with the campaign's effects, as warm as at its end, at the
    corrected joints. ~3 s of CPU.

    Fields ``rot_z.after.{0|1|2|max}``, ``rot_z.plain.{0|1|2|max}`` (probe rotation |error / sigma|
    after / before the bias), ``residual_rms_mm``, ``residual_pred_mm`` (first-order misfit plus
    noise); at the robot ``pos.{landing|miss|diff|sigma}.{min|max}`` [mm] and
    ``rot.{landing|miss|diff|sigma}.{min|max}`` [deg] (landing error, first-order miss, their
    vector difference, the noise sigma)."""
    import json
    import tempfile
    from pathlib import Path

    import numpy as np

    from ..sim.first_order import poses_with_effects, six_d_fit_bias
    from ..sim.six_d_exports import (PROBE_ROBOT, PROBE_SIGMA_MM, PROBE_W_MM_PER_RAD, export_times, probe_campaign,
                                     probe_tool, read_corrected_joints, write_leica_tmac, write_pose_targets,
                                     write_rtde_log)
    from ..transforms import so3_log
    from .figure_producers_cli import run_cli

    sigma, w, seed = PROBE_SIGMA_MM, PROBE_W_MM_PER_RAD, 11
    c = probe_campaign(60, seed, effects=True)
    q, virtual, T_inst, T_free, tool = c["q"], c["virtual"], c["T_inst"], c["T_free"], probe_tool()
    joints = ("J1", "J2", "J3", "J4", "J5", "J6")
    with tempfile.TemporaryDirectory() as tmp:
        d = Path(tmp)
        leica = write_leica_tmac(d / "tmac.csv", c["T"], export_times(len(q)))
        rtde = write_rtde_log(d / "rtde.csv", q)
        run_cli("import", leica, "--joints", rtde, "--robot", PROBE_ROBOT, "--orientation", "rpy", "--out", d / "m.csv")
        run_cli("calibrate", PROBE_ROBOT, d / "m.csv", "--out", d / "cal", "--sigma", sigma, "--holdout", 0, "--no-report")
        res = json.loads((d / "cal" / "result.json").read_text())
        q_t = virtual.random_configurations(8, np.random.default_rng(99), margin=0.2)
        targets = T_inst @ virtual.true_poses(q_t) @ tool
        write_pose_targets(d / "t.csv", targets, q_t, joints)
        run_cli("correct", d / "cal" / "calibrated_robot.toml", d / "t.csv", "--out", d / "c.csv")
        q_c = read_corrected_joints(d / "c.csv", joints)
    estimated = [p["name"] for p in res["model_parameters"] if p["estimated"]]
    fit = (virtual.true_model, estimated, q, T_inst, tool, T_free, w)
    bias = six_d_fit_bias(*fit)
    tf = res["tool_frame"]
    T_fit = np.array(tf["T_flange_measured"])
    err, std = so3_log(T_fit[:3, :3] @ tool[:3, :3].T), np.array(tf["std_rotvec_rad"])
    after, plain = np.abs(err - bias["tool_rotvec"]) / std, np.abs(err) / std
    n_var = len(estimated) + 12
    out = {**{f"rot_z.after.{k}": float(after[k]) for k in range(3)}, "rot_z.after.max": float(after.max()),
           **{f"rot_z.plain.{k}": float(plain[k]) for k in range(3)}, "rot_z.plain.max": float(plain.max()),
           "residual_rms_mm": float(res["residuals"]["after"]["rms"]),
           "residual_pred_mm": float(np.hypot(bias["residual_rms_mm"], sigma * np.sqrt(3 * (1 - n_var / (6 * len(q))))))}
    reached = poses_with_effects(virtual.true_model, q_c, T_inst, tool, c["phases"], after_campaign=True)[1]
    first = six_d_fit_bias(*fit, q_at=q_c, T_at=reached, noise_mm=sigma)
    d_pos = reached[:, :3, 3] - targets[:, :3, 3]
    d_rot = so3_log(reached[:, :3, :3] @ np.swapaxes(targets[:, :3, :3], 1, 2))
    miss_pos, miss_rot = first["miss_at"][:, :3], first["miss_at"][:, 3:]
    vals = {"pos.landing": np.linalg.norm(d_pos, axis=1), "pos.miss": np.linalg.norm(miss_pos, axis=1),
            "pos.diff": np.linalg.norm(d_pos - miss_pos, axis=1), "pos.sigma": np.asarray(first["sigma_at_mm"]),
            "rot.landing": np.degrees(np.linalg.norm(d_rot, axis=1)), "rot.miss": np.degrees(np.linalg.norm(miss_rot, axis=1)),
            "rot.diff": np.degrees(np.linalg.norm(d_rot - miss_rot, axis=1)),
            "rot.sigma": np.degrees(np.asarray(first["sigma_at_rad"]))}
    out.update({f"{k}.{s}": float(getattr(np, s)(v)) for k, v in vals.items() for s in ("min", "max")})
    return out


@functools.lru_cache(maxsize=None)
def self_calibration_effects(robot: str) -> dict:
    """docs/testing.md, camera self-calibration with link-length errors (0.2 mm) and a bent board
    (0.4 mm): the set-ups of ``tests/test_self_calibration_nao.py`` (``nao``: seed 5, 40 views per
    arm) and ``tests/test_self_calibration.py`` (``justin``: seed 16, 25 views per hand), 0.3 px
    corner noise (:mod:`robocal.sim.cameras.self_calibration_effects`). <1 s of CPU each.

    Fields ``effect_rms_px`` (the effects' corner displacement), ``variance_factor``,
    ``naive_max_abs_z`` (error / reported sigma), ``corrected_max_abs_z`` ((error - first-order
    bias) / corner-noise sigma), ``bias_max_deg``, ``n_offsets``."""
    import numpy as np

    from ..sim.cameras.self_calibration_effects import justin_effects_case, nao_effects_case

    c = nao_effects_case() if robot == "nao" else justin_effects_case()
    return {"effect_rms_px": c["effect_rms_px"], "variance_factor": float(c["result"].variance_factor),
            "naive_max_abs_z": float(np.abs(c["z_naive"]).max()), "corrected_max_abs_z": float(np.abs(c["z_noise"]).max()),
            "bias_max_deg": float(np.degrees(max(abs(v) for v in c["delta"].values()))), "n_offsets": float(len(c["names"]))}


@functools.lru_cache(maxsize=None)
def handeye_link_errors() -> dict:
    """docs/testing.md, the hand-eye refinement with joint offsets on a robot whose links are 0.1 mm /
    0.01 deg off (the set-up of ``tests/test_handeye_refine.py``,
    :func:`robocal.sim.cameras.handeye_effects.handeye_link_error_case`). <1 s of CPU.

    Fields ``z_plain.max`` (max |error / sigma|), ``z_after.max`` (after the first-order bias)."""
    import numpy as np

    from ..sim.cameras.handeye_effects import handeye_link_error_case

    c = handeye_link_error_case()
    return {"z_plain.max": float(np.abs(c["z_plain"]).max()), "z_after.max": float(np.abs(c["z_after"]).max())}


@functools.lru_cache(maxsize=None)
def tracker_effects() -> dict:
    """docs/testing.md "The effects the model lacks": the set-up of ``tests/test_calibration.py``'s
    realistic case (:func:`robocal.sim.campaign_effects_fit.effects_campaign_fit`, seeds 0-1, 100
    training and 200 held-out poses, 0.02 mm) on the KR 150 and the UR10. <1 s of CPU.

    Fields per robot ``{kr150|ur10}.``: ``holdout_rms_mm.{0|1}`` (per seed), ``holdout_rms_mm``
    (pooled over the seeds), ``ratio`` (pooled hold-out RMS / first-order prediction),
    ``floor_rms_mm`` (pooled noise floor), ``naive_max_abs_z``, ``bias_max_abs_z``; over both robots
    ``naive_max_abs_z.{min|max}`` (over the four campaigns' maxima), ``floor_rms_mm.{min|max}``, ``ratio_deviation_percent``
    (largest |ratio - 1| [%])."""
    import numpy as np

    from ..sim.campaign_effects_fit import effects_campaign_fit

    out = {}
    for key, name in (("kr150", "kuka_kr150_r3100"), ("ur10", "ur10")):
        runs = [effects_campaign_fit(name, seed, tool_mm=(30.0, 40.0, 100.0), sigma_mm=0.02) for seed in range(2)]
        for s, c in enumerate(runs):
            out[f"{key}.holdout_rms_mm.{s}"] = float(np.sqrt(c["holdout_mse"]))
        ho, pred, floor = (np.mean([c[k] for c in runs]) for k in ("holdout_mse", "predicted_mse", "floor_mse"))
        out.update({f"{key}.holdout_rms_mm": float(np.sqrt(ho)), f"{key}.ratio": float(np.sqrt(ho / pred)),
                    f"{key}.floor_rms_mm": float(np.sqrt(floor)),
                    f"{key}.naive_max_abs_z": float(max(np.abs(c["z_naive"]).max() for c in runs)),
                    f"{key}.bias_max_abs_z": float(max(np.abs(c["z_bias"]).max() for c in runs))})
        out.update({f"{key}.naive_max_abs_z.{s}": float(np.abs(c["z_naive"]).max()) for s, c in enumerate(runs)})
    per_campaign = [out[f"{k}.naive_max_abs_z.{s}"] for k in ("kr150", "ur10") for s in range(2)]
    out["naive_max_abs_z.min"], out["naive_max_abs_z.max"] = min(per_campaign), max(per_campaign)
    out["floor_rms_mm.min"] = min(out["kr150.floor_rms_mm"], out["ur10.floor_rms_mm"])
    out["floor_rms_mm.max"] = max(out["kr150.floor_rms_mm"], out["ur10.floor_rms_mm"])
    out["ratio_deviation_percent"] = 100.0 * max(abs(out["kr150.ratio"] - 1.0), abs(out["ur10.ratio"] - 1.0))
    return out


@functools.lru_cache(maxsize=None)
def thermal_table_5_2() -> dict:
    """docs/testing.md "Table 5-2": the set-up of ``tests/test_thermal_screening.py``
    (``run_thermal_seeds(preset="realistic", seeds=6, first_seed=1, n_cycles=90)``); lambda [%] as
    ``{rms|max}.{screening|evaluation}.{column}.{median|q25|q75|min|max}``. ~15 s of CPU."""
    from ..workflows.thermal.seeds import run_thermal_seeds
    from .figure_producers import _flat

    r = run_thermal_seeds(preset="realistic", seeds=6, first_seed=1, n_cycles=90)
    return {**_flat(r["tables"]), "n_not_converged": float(r["fits"]["not_converged"])}


@functools.lru_cache(maxsize=None)
def tcp_realism_cells(preset: str) -> dict:
    """docs/testing.md, ``test_tcp_realism.py``: the set-up of its ``cells`` fixture,
    ``tcp_accuracy_study(preset=PRESET, seeds=20, first_seed=1, repeats=3)`` (the ideal preset with
    the cross-laser only). ~10 s of CPU (realistic).

    Fields ``check.{q25|median|q75}`` (cross-laser arm check [mm]); realistic also
    ``pb_minus_off_axis.{max|median}`` (parallel barriers: |TCP error - the bent tool's off-axis
    distance| [mm]) and ``beyond_tcp_mm`` = sqrt(median(check^2 - accuracy^2))."""
    import math

    import numpy as np

    from ..workflows.tool.accuracy import tcp_accuracy_study

    methods = ("cross_laser", "parallel_barriers") if preset == "realistic" else ("cross_laser",)
    r = tcp_accuracy_study(preset=preset, seeds=20, first_seed=1, repeats=3, methods=methods)
    chk = r["summary"]["cross_laser"]["check_mm"]
    out = {f"check.{k}": float(chk[k]) for k in ("q25", "median", "q75")}
    if preset == "realistic":
        d = np.array([abs(c["parallel_barriers"]["accuracy_mm"] - c["tcp_off_axis_mm"]) for c in r["per_seed"]])
        acc = np.array([c["cross_laser"]["accuracy_mm"] for c in r["per_seed"]])
        chk_all = np.array([c["cross_laser"]["check_mm"] for c in r["per_seed"]])
        out.update({"pb_minus_off_axis.max": float(d.max()), "pb_minus_off_axis.median": float(np.median(d)),
                    "beyond_tcp_mm": math.sqrt(max(float(np.median(chk_all**2 - acc**2)), 0.0))})
    return out


@functools.lru_cache(maxsize=None)
def positioner_reference() -> dict:
    """docs/testing.md, ``test_positioner_real_data.py``: robocal's positioner calibration (seed 0,
    150 training records) against the independent screw-axis fit of
    :mod:`robocal.workflows.datasets.positioner_reference` on the same records, with the same three
    target points and with the target origin alone. ~2 s of CPU.

    Fields ``robocal.{angle_deg|normal_mm|sigma_angle_deg|sigma_normal_mm}``,
    ``reference3.{...}`` and ``reference1.{...}`` (three points / origin alone),
    ``difference.{angle_deg|normal_mm}`` (|robocal - reference3|) and ``sigma_ratio_deviation``
    (largest |robocal sigma / reference sigma - 1|)."""
    import numpy as np

    from ..workflows.datasets.positioner_reference import reference_axes
    from ..workflows.datasets.ros_industrial_positioner import axes_on_training_records

    rec = axes_on_training_records(seed=0, n_train=150)
    T, q, got, sig = rec["T_camera_target"], rec["joints"], rec["axes"], rec["sigma"]
    out = {"robocal.angle_deg": float(got[0]), "robocal.normal_mm": float(got[1]),
           "robocal.sigma_angle_deg": float(sig[0]), "robocal.sigma_normal_mm": float(sig[1])}
    for n in (3, 1):
        ref, sigma, _ = reference_axes(T, q, n_points=n)
        out.update({f"reference{n}.angle_deg": float(ref[0]), f"reference{n}.normal_mm": float(ref[1]),
                    f"reference{n}.sigma_angle_deg": float(sigma[0]), f"reference{n}.sigma_normal_mm": float(sigma[1])})
        if n == 3:
            out["difference.angle_deg"], out["difference.normal_mm"] = (float(v) for v in np.abs(got - ref))
            out["sigma_ratio_deviation"] = float(np.max(np.abs(sig / sigma - 1.0)))
    return out


@functools.lru_cache(maxsize=None)
def touchup_gate() -> dict:
    """docs/tcp.md's touch-up gates: the set-up of ``tests/test_tool_gates.py`` (seven touch poses,
    0.05 mm noise, seed 3, :func:`robocal.sim.tool.touch_poses.touch_poses`; pose 5 moved 5 mm), the
    four-point fit. Fields ``rms_mm`` (the fit's RMS, what the RMS gate alone saw) and
    ``tcp_error_mm`` (its TCP against the true one)."""
    import numpy as np

    from ..sim.tool.touch_poses import TCP_TRUE_MM, touch_poses
    from ..tcp.touchup import four_point_tcp

    T = touch_poses(7, np.random.default_rng(3), noise=0.05)
    T[4, :3, 3] += np.array([3.0, -4.0, 0.0])  # 5 mm off
    fit = four_point_tcp(T)
    return {"rms_mm": float(fit.rms_mm), "tcp_error_mm": float(np.linalg.norm(fit.tcp_mm - TCP_TRUE_MM))}


TESTING_PRODUCERS = {"closed_chain/held_sigma": closed_chain_held_sigma, "formulas/gaussian": gaussian_formulas,
                     **{f"closed_chain_effects/seed{s}": functools.partial(closed_chain_effects, s) for s in range(4)},
                     "closed_chain_effects/z": closed_chain_effects_z, "six_d/import_realistic": six_d_import,
                     **{f"self_calibration_effects/{r}": functools.partial(self_calibration_effects, r) for r in ("nao", "justin")},
                     "handeye/link_errors": handeye_link_errors, "calibration/tracker_effects": tracker_effects,
                     "thermal/table_5_2_seeds_1_6": thermal_table_5_2,
                     "ros_industrial_positioner/reference": positioner_reference, "tcp/touchup_gate": touchup_gate,
                     **{f"tcp/realism_cells_{p}": functools.partial(tcp_realism_cells, p) for p in ("realistic", "ideal")}}

#: run with ``--all``: longer than ~5 s of CPU (table 5-2, the tool-frame cells, the study's z), reading the
#: 10-seed closed-chain study (theta1's sigma), or ~1.5 s each for the seeds 1-3 quoted in prose
SLOW_TESTING_PRODUCERS = {"closed_chain/held_sigma", "closed_chain_effects/seed1", "closed_chain_effects/seed2",
                          "closed_chain_effects/seed3", "closed_chain_effects/z", "thermal/table_5_2_seeds_1_6",
                          "tcp/realism_cells_realistic", "tcp/realism_cells_ideal"}
