"""Producers of docs/thermal.md's documented figures that no other producer computes
(:mod:`robocal.docs.figures`): the effect-by-effect table and the three-hour drift; the ratios that
docs/tcp.md's prose reads off the collision study; and docs/testing.md's at-the-robot tables (the
set-ups of ``tests/test_program_at_robot.py`` through the command line). Each returns a flat
``{field: value}`` dict and is cached."""

from __future__ import annotations

import functools

__all__ = ["PROGRAM_CASES", "THERMAL_PRODUCERS", "frames_only_line", "program_at_robot", "six_d_at_robot", "tcp_collision_ratios", "thermal_drift_three_hours",
           "thermal_effect_alone", "thermal_system_advantage",
           "thermal_system_first_order_bias", "thermal_system_seeds100"]

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


#: docs/testing.md's at-the-robot cases (``tests/test_program_at_robot.py``): robot, campaign seed,
#: language, taught joints [deg], home [deg], base / work object (X, Y, Z [mm], A, B, C [deg])
PROGRAM_CASES = {
    "krl": ("kuka_kr150_r3100", 1, "krl",
            [[10, -80, 100, 5, 40, 20], [-25, -60, 85, -30, -60, -10], [41, -83, -87, -271, 63, 231],
             [-59, -66, -90, -210, 34, 82]], [0, -90, 90, 0, 0, 0], [1500, -300, 400, 0, 0, 10]),
    "rapid": ("abb_irb140", 2, "rapid",
              [[10, 20, 10, 5, 40, 20], [-20, 30, -10, -30, -60, -10], [-73, -67, -124, 53, -50, 33],
               [100, -45, -110, 30, 60, -40]], [0, 0, 0, 0, 30, 0], [500, -100, 300, 0, 0, 20]),
    "fanuc": ("fanuc_r2000ic_165f", 2, "fanuc",
              [[10, 10, 10, 5, 40, 20], [-20, 20, -10, -30, -60, -10], [112, -20, 94, -284, 88, -71],
               [-70, 13, 117, 162, -60, 124]], [0, 0, 0, 0, -90, 0], [1200, -200, 300, 0, 0, 15]),
    "ur": ("ur10", 3, "ur",
           [("j", [-30, -100, 100, -90, -90, 0]), ("l", [-30, -104, 112, -98, -90, 10]),
            ("l", [-20, -90, 100, -100, -90, 20]), ("j", [-20, -90, 100, -100, 60, 20]),
            ("l", [-15, -95, 100, -95, 70, 10]), ("j", [150, -80, -100, -90, 90, 0]),
            ("l", [155, -85, -95, -85, 80, 10]), ("j", [-30, -100, 100, -90, -90, 0])], None, None),
}


@functools.lru_cache(maxsize=None)
def program_at_robot(case: str, effects: str = "realistic", tool: tuple | None = None) -> dict:
    """docs/testing.md "At the robot": the set-up of ``tests/test_program_at_robot.py``'s case
    ``case`` (:data:`PROGRAM_CASES`) through the command line: ``robocal simulate tracker ROBOT
    --poses 40 --reflectors 3 --seed SEED --effects EFFECTS``, ``robocal calibrate`` (realistic:
    ``--no-orientation --holdout 0 --noise 0.02``), the program taught offline with the
    identified reflector r1 as its tool (``tool``: a tool [X, Y, Z, A, B, C] the campaign never saw
    instead), ``robocal correct``, ``robocal simulate execute`` of the original and the corrected
    program on the true robot (``--true-tool`` the true r1), and the first-order miss from the
    hidden truth (:func:`robocal.sim.first_order.tracker_campaign_bias`).

    Fields per corrected Cartesian target k (0-based, program order): ``landing.k``, ``miss.k``,
    ``sigma.k``, ``before.k``, ``noise.k`` (``sqrt(sigma^2 - unknown^2)``) [mm]; and
    ``{landing|miss|sigma|noise}.{min|max}``. ~5-15 s of CPU each."""
    import csv
    import json
    import tempfile
    from pathlib import Path

    import numpy as np

    from ..io.measurements import read_measurements
    from ..io.programs import read_program
    from ..sim.first_order import tracker_campaign_bias
    from ..sim.taught_programs import fanuc_program, krl_program, rapid_program, ur_program
    from .figure_producers_cli import run_cli

    robot, seed, lang, q, home, base = PROGRAM_CASES[case]
    with tempfile.TemporaryDirectory() as tmp:
        d = Path(tmp)
        meas = d / "cell.csv"
        run_cli("simulate", "tracker", robot, "--poses", 40, "--reflectors", 3, "--seed", seed, "--out", meas,
                "--effects", effects)
        fit = [] if effects == "ideal" else ["--no-orientation", "--holdout", 0, "--noise", 0.02]
        run_cli("calibrate", robot, meas, "--out", d / "cal", "--no-report", *fit)
        truth_file, cal = d / "cell.truth.json", d / "cal" / "calibrated_robot.toml"
        result = json.loads((d / "cal" / "result.json").read_text())
        truth = json.loads(truth_file.read_text())
        r1 = next(t["point_mm"] for t in result["targets"] if t["name"] == "r1")
        r1_true = truth["reflectors_mm"][0]
        t_prog = [*r1, 0, 0, 0] if tool is None else list(tool)
        options, execute = [], ([] if tool is not None else ["--true-tool", ",".join(f"{v!r}" for v in r1_true)])
        if lang == "krl":
            text, config_dat = krl_program(robot, q, home, t_prog, base)
            src, cdat = d / "cell.dat", d / "cell_config.dat"
            src.write_bytes(text.encode("latin-1"))
            cdat.write_bytes(config_dat.encode("latin-1"))
            options = ["--config-dat", cdat]
            execute = [*options, *execute]
        elif lang == "rapid":
            src = d / "cell.mod"
            src.write_text(rapid_program(robot, q, home, t_prog, base))
        elif lang == "fanuc":
            src = d / "cell.ls"
            src.write_text(fanuc_program(robot, q, home, t_prog, base))
            options = ["--tool", ",".join(repr(v) for v in t_prog), "--base", ",".join(str(v) for v in base)]
            execute = [*options, *execute]
        else:
            src = d / "cell.script"
            src.write_text(ur_program(robot, q, t_prog))
        out = src.with_name("corrected" + src.suffix)
        run_cli("correct", cal, src, "--out", out, *options)

        def run(program, intended=None):
            extra = ["--intended", intended] if intended is not None else []
            r = json.loads(run_cli("simulate", "execute", truth_file, program, "--json", "--cell-base", cal,
                                   *execute, *extra))
            return {row["target"]: row for row in r["targets"]}

        before, after = run(src), run(out, src)
        with open(out.with_name(out.name + ".report.csv"), newline="") as f:
            report = {row["target"]: row for row in csv.DictReader(line for line in f if not line.startswith("#"))}
        names = [t.name for t in read_program(src).targets if t.kind != "joint"]
        q_train = read_measurements(d / truth["simulation"]["measurements_file"]).joints
    estimated = [p["name"] for p in result["model_parameters"] if p["estimated"]]
    q_exec = np.radians([after[n]["joints_deg"] for n in names])
    miss = np.linalg.norm(tracker_campaign_bias(truth, estimated, q_train, q_exec,
                                                point=None if tool is None else list(tool[:3])), axis=1)
    sigma = np.array([float(report[n]["sigma_mm"]) for n in names])
    unknown = np.array([float(report[n].get("unknown_mm") or 0.0) for n in names])
    rows = {"landing": np.array([after[n]["error_mm"] for n in names]), "miss": miss, "sigma": sigma,
            "before": np.array([before[n]["error_mm"] for n in names]), "noise": np.sqrt(sigma**2 - unknown**2)}
    out_d = {f"{k}.{i}": float(x) for k, v in rows.items() for i, x in enumerate(v)}
    out_d.update({f"{k}.{s}": float(getattr(np, s)(v)) for k, v in rows.items() for s in ("min", "max")})
    return out_d


@functools.lru_cache(maxsize=None)
def thermal_system_advantage() -> dict:
    """docs/thermal.md "Measured accuracy", the prose under the table (producer
    ``system_calibration/thermal``, seeds 0-19): how much larger the thesis penalty method's mean
    error is than least squares' [%], ``min`` and ``max`` over the five measures."""
    from .figure_producers import PRODUCERS

    r = PRODUCERS["system_calibration/thermal"]()
    keys = ("rotation_deg", "at_point_mm", "sensor_origin_mm", "translation_mm", "P_e_mm")
    larger = [100.0 * (r[f"thesis.seeds20_mean.{k}"] / r[f"ls.seeds20_mean.{k}"] - 1.0) for k in keys]
    return {"min": min(larger), "max": max(larger)}


@functools.lru_cache(maxsize=None)
def thermal_system_seeds100(off_model: bool) -> dict:
    """docs/thermal.md "Measured accuracy", seeds 0-99 (the set-up of ``tests/test_thermal_core.py``'s
    ``_system_errors``, as ``system_calibration/thermal`` but 100 seeds): both system calibrations
    per seed; ``off_model``: the true robot ``VirtualRobot.perturbed(kuka, 500 + seed, 0.1 mm, 0.01 deg,
    0.01 deg)`` (the test on a robot that differs from its model). ~5 s of CPU.

    Fields ``wins.{measure}`` (seeds where least squares is better), ``wins_all`` (all five),
    ``ratio.{min|max}`` (mean error penalty / least squares over the measures), ``z.{rms|max}``
    (least squares' ``|P_e error| / |std P_e|``)."""
    import numpy as np

    from ..robots import load_robot
    from ..sim import VirtualRobot
    from .figure_producers_setups import SYSTEM_MEASURES, system_calibration_seed

    kuka = load_robot("kuka_kr150_r3100")
    keys = SYSTEM_MEASURES
    ls, th, z = [], [], []
    for seed in range(100):
        true = None if not off_model else VirtualRobot.perturbed(
            kuka, 500 + seed, length_sigma_mm=0.1, angle_sigma_deg=0.01, offset_sigma_deg=0.01).true_model
        c = system_calibration_seed(seed, true)
        ls.append([c.errors["least-squares"][k] for k in keys])
        th.append([c.errors["thesis-penalty"][k] for k in keys])
        z.append(c.errors["least-squares"]["P_e_mm"] / np.linalg.norm(c.least_squares.std_P_e_mm))
    ls, th, z = np.array(ls), np.array(th), np.array(z)
    better = ls < th
    ratio = th.mean(axis=0) / ls.mean(axis=0)
    return {**{f"wins.{k}": float(w) for k, w in zip(keys, better.sum(axis=0))},
            "wins_all": float(better.all(axis=1).sum()), "ratio.min": float(ratio.min()),
            "ratio.max": float(ratio.max()), "z.rms": float(np.sqrt(np.mean(z**2))), "z.max": float(z.max())}


@functools.lru_cache(maxsize=None)
def thermal_system_first_order_bias() -> dict:
    """docs/testing.md, the thermal system calibration on a robot that differs from its model (the
    set-up of ``tests/test_thermal_core.py``'s ``test_system_calibration_on_a_robot_that_differs_from_its_model``):
    seeds 0-9, 9 poses, 0.02 mm noise, the true robot 0.1 mm / 0.01 deg per parameter off
    (``VirtualRobot.perturbed(kuka, 500 + seed)``); the first-order bias of ``P_e`` from the hidden
    truth (finite differences of ``predict_sphere``). ~1 s of CPU.

    Fields ``bias_mm.{min|max}`` (|bias of P_e|), ``naive_z.max``, ``corrected_z.{max|rms}`` (per
    axis, ``|error - bias| / std``), ``residual_rms_mm.{min|max}``."""
    import numpy as np

    from ..robots import load_robot
    from ..sim.thermal.drift_setup import P_E_MM as P_e
    from ..sim.thermal.drift_setup import off_model_system_calibration

    kuka = load_robot("kuka_kr150_r3100")
    naive, corrected, rms, size = [], [], [], []
    for seed in range(10):  # written once with tests/test_thermal_core.py
        r, bias = off_model_system_calibration(kuka, seed)
        size.append(float(np.linalg.norm(bias)))
        naive.append((r.P_e - P_e) / r.std_P_e_mm)
        corrected.append((r.P_e - P_e - bias) / r.std_P_e_mm)
        rms.append(float(np.sqrt(np.mean(r.residuals_mm ** 2))))
    naive, corrected = np.abs(naive), np.abs(corrected)
    return {"bias_mm.min": min(size), "bias_mm.max": max(size), "naive_z.max": float(naive.max()),
            "corrected_z.max": float(corrected.max()), "corrected_z.rms": float(np.sqrt(np.mean(corrected**2))),
            "residual_rms_mm.min": min(rms), "residual_rms_mm.max": max(rms)}


@functools.lru_cache(maxsize=None)
def six_d_at_robot() -> dict:
    """docs/testing.md, the 6-D rows (the set-up of ``tests/test_six_d_cli.py``'s realistic cases):
    a 6-D probe on a 35 / -20 / 180 mm tool, 60 poses of the KR 150 (seed 3, the last link's
    parameters true = nominal), the ``realistic`` campaign effects (transmission phases from seed
    1003), 0.02 mm / 0.02/100 rad noise; ``robocal calibrate --noise 0.02 --holdout 0``; the first-order
    bias from the hidden truth (:func:`robocal.sim.first_order.six_d_fit_bias`); then ``robocal
    correct`` on 8 tool-pose targets the true robot can take (seed 99) and the true robot with the
    campaign's effects at the corrected joints. ~3 s of CPU.

    Fields ``rot_z.{plain|after}.{0|1|2}`` (tool rotation |error / sigma|, before and after the
    bias), ``residual_rms_mm``, ``residual_pred_mm`` (first-order misfit plus noise);
    ``pos.{landing|diff|sigma}.{min|max}`` [mm] and ``rot.{landing|diff|sigma}.{min|max}`` [deg] at
    the robot (landing error, its difference to the first-order miss, the noise sigma)."""
    import json
    import tempfile
    from pathlib import Path

    import numpy as np

    from ..io.measurements import write_measurements
    from ..robots import load_robot
    from ..sim import VirtualRobot
    from ..sim.first_order import poses_with_effects, six_d_fit_bias
    from ..sim.six_d_campaign import SIX_D_ROBOT, SIX_D_SIGMA_MM, SIX_D_W_MM_PER_RAD, six_d_campaign
    from ..sim.six_d_exports import read_corrected_joints, write_pose_targets
    from ..transforms import so3_log
    from .figure_producers_cli import run_cli

    robot, sigma_mm, w, n = SIX_D_ROBOT, SIX_D_SIGMA_MM, SIX_D_W_MM_PER_RAD, 60
    meas, truth = six_d_campaign(n, 3, effects=True)
    nominal = load_robot(robot)
    model, q, T_tool, T_inst, T_free, phases = (truth["model"], truth["q"], truth["T_tool"], truth["T_inst"],
                                                truth["T_free"], truth["phases"])
    with tempfile.TemporaryDirectory() as tmp:
        d = Path(tmp)
        path = write_measurements(d / "probe.csv", meas, length_unit="mm", angle_unit="deg", orientation="kuka_abc")
        run_cli("calibrate", robot, path, "--out", d / "cal", "--noise", sigma_mm, "--holdout", 0, "--no-report")
        res = json.loads((d / "cal" / "result.json").read_text())
        q_t = VirtualRobot(nominal, model).random_configurations(8, np.random.default_rng(99), margin=0.2)
        targets = T_inst @ model.fk(q_t) @ T_tool
        joints = [f"A{j + 1}" for j in range(6)]
        write_pose_targets(d / "t.csv", targets, q_t, joints)
        run_cli("correct", d / "cal" / "calibrated_robot.toml", d / "t.csv", "--out", d / "c.csv")
        q_c = read_corrected_joints(d / "c.csv", joints)
    estimated = [p["name"] for p in res["model_parameters"] if p["estimated"]]
    bias = six_d_fit_bias(model, estimated, q, T_inst, T_tool, T_free, w)
    tf = res["tool_frame"]
    T = np.array(tf["T_flange_measured"])
    err, std = so3_log(T[:3, :3] @ T_tool[:3, :3].T), np.array(tf["std_rotvec_rad"])
    n_var = len(estimated) + 12
    out = {**{f"rot_z.plain.{k}": float(abs(err[k]) / std[k]) for k in range(3)},
           **{f"rot_z.after.{k}": float(abs(err[k] - bias["tool_rotvec"][k]) / std[k]) for k in range(3)},
           "residual_rms_mm": float(res["residuals"]["after"]["rms"]),
           "residual_pred_mm": float(np.hypot(bias["residual_rms_mm"], sigma_mm * np.sqrt(3 * (1 - n_var / (6 * n)))))}
    reached = poses_with_effects(model, q_c, T_inst, T_tool, phases, after_campaign=True)[1]
    first = six_d_fit_bias(model, estimated, q, T_inst, T_tool, T_free, w, q_at=q_c, T_at=reached, noise_mm=sigma_mm)
    d_pos = reached[:, :3, 3] - targets[:, :3, 3]
    d_rot = so3_log(reached[:, :3, :3] @ np.swapaxes(targets[:, :3, :3], 1, 2))
    miss_pos, miss_rot = first["miss_at"][:, :3], first["miss_at"][:, 3:]
    vals = {"pos.landing": np.linalg.norm(d_pos, axis=1), "pos.diff": np.linalg.norm(d_pos - miss_pos, axis=1),
            "pos.sigma": np.asarray(first["sigma_at_mm"]),
            "rot.landing": np.degrees(np.linalg.norm(d_rot, axis=1)),
            "rot.diff": np.degrees(np.linalg.norm(d_rot - miss_rot, axis=1)),
            "rot.sigma": np.degrees(np.asarray(first["sigma_at_rad"]))}
    out.update({f"{k}.{s}": float(getattr(np, s)(v)) for k, v in vals.items() for s in ("min", "max")})
    return out


@functools.lru_cache(maxsize=None)
def frames_only_line() -> dict:
    """docs/testing.md, the frames-only row (the set-up of ``tests/test_frames_only.py``'s realistic
    case): KR 150, 20 poses along an 800 mm line (seed 5), a ~170 deg tool, the ``realistic``
    campaign effects (phases from seed 1005), 0.02 mm / 0.0002 rad noise; ``robocal calibrate
    --frames-only --holdout 0 --noise 0.02``; the tool frame's first-order bias from the hidden truth
    (:func:`robocal.sim.first_order.six_d_fit_bias`, no geometric parameter free). ~1 s of CPU.

    Fields ``rot_z.{plain|after}.max`` (tool rotation |error / sigma| before / after the bias),
    ``residual_rms_mm``, ``residual_pred_mm``."""
    import json
    import tempfile
    from pathlib import Path

    import numpy as np

    from ..io.measurements import Measurements, write_measurements
    from ..sim.first_order import six_d_fit_bias
    from ..sim.line_campaign import LINE_ROBOT, line_campaign_poses
    from ..transforms import so3_log
    from .figure_producers_cli import run_cli

    n = 20
    c = line_campaign_poses(5, n, effects=True)
    m, q, tool, inst, Tm, p, R, robot = (c["model"], c["q"], c["tool"], c["instrument"], c["T_measured"], c["points"],
                                         c["rotations"], LINE_ROBOT)
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "line.csv"
        write_measurements(path, Measurements(q, p, joint_names=m.controller_joints, rotations=R,
                                              metadata={"robot": robot}), orientation="quaternion")
        run_cli("calibrate", robot, path, "--out", Path(tmp) / "cal", "--frames-only", "--holdout", 0, "--noise", 0.02,
                "--no-report")
        res = json.loads((Path(tmp) / "cal" / "result.json").read_text())
    bias = six_d_fit_bias(m, [], q, inst, tool, Tm, 100.0)
    tf = res["tool_frame"]
    err = so3_log(np.array(tf["T_flange_measured"])[:3, :3] @ tool[:3, :3].T)
    std = np.array(tf["std_rotvec_rad"])
    return {"rot_z.plain.max": float(np.max(np.abs(err) / std)),
            "rot_z.after.max": float(np.max(np.abs(err - bias["tool_rotvec"]) / std)),
            "residual_rms_mm": float(res["residuals"]["after"]["rms"]),
            "residual_pred_mm": float(np.hypot(bias["residual_rms_mm"], 0.02 * np.sqrt(3 * (1 - 12 / (6 * n)))))}


THERMAL_PRODUCERS = {"tcp/collision_ratios": tcp_collision_ratios,
                     "system_calibration/thermal_advantage": thermal_system_advantage,
                     "six_d/at_robot": six_d_at_robot,
                     "six_d/frames_only_line": frames_only_line,
                     "system_calibration/thermal_first_order_bias": thermal_system_first_order_bias,
                     **{f"system_calibration/thermal_100{'_off_model' if o else ''}":
                        functools.partial(thermal_system_seeds100, o) for o in (False, True)},
                     **{f"thermal_drift/{p}": functools.partial(thermal_drift_three_hours, p)
                        for p in ("realistic", "ideal")},
                     **{f"thermal_alone/{e}": functools.partial(thermal_effect_alone, e) for e in EFFECTS},
                     **{f"program_at_robot/{c}": functools.partial(program_at_robot, c) for c in PROGRAM_CASES},
                     "program_at_robot/krl_gripper": functools.partial(program_at_robot, "krl", tool=(0, 0, 250, 0, 0, 0)),
                     "program_at_robot/krl_gripper_ideal": functools.partial(program_at_robot, "krl", "ideal",
                                                                             tool=(0, 0, 250, 0, 0, 0))}
