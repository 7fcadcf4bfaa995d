"""Producers of documented figures that run the page's own commands through the command line
(:mod:`robocal.docs.figures`): the coverage gates of docs/calibration.md and the corrected robot
programs at the simulated true robot of docs/robot-programs.md. Each returns a flat
``{field: value}`` dict and is cached."""

from __future__ import annotations

import functools
import json
import re
import shutil
import tempfile
from pathlib import Path

__all__ = ["CLI_PRODUCERS", "run_cli"]


def run_cli(*args, ok=(0,)) -> str:
    """``robocal ARGS`` in this process; its stdout. Raises RuntimeError on an exit code not in ``ok``."""
    from click.testing import CliRunner

    from ..cli import main as cli

    r = CliRunner().invoke(cli, [str(a) for a in args], catch_exceptions=False)
    if r.exit_code not in ok:
        raise RuntimeError(f"robocal {' '.join(map(str, args))}: exit {r.exit_code}: {r.output[-800:]}")
    return r.stdout


# ------------------------------------------------------------------------------- coverage gates
#: docs/calibration.md "Coverage gates": the joints each degenerate campaign holds fixed [deg]
#: (controller joint index -> angle), as in ``tests/test_coverage_gates.py``
COVERAGE_CAMPAIGNS = {"full": {}, "a4_fixed": {3: 0.0}, "a2_a3_fixed": {1: -60.0, 2: 60.0},
                      "only_a1": {1: -60.0, 2: 60.0, 3: 0.0, 4: 40.0, 5: 0.0}}


@functools.lru_cache(maxsize=None)
def coverage_gates() -> dict:
    """docs/calibration.md's coverage-gate table: KR 150, 40 feasible poses of the default cell
    with the campaign's joints held fixed (seed 3), hidden truth ``VirtualRobot.perturbed(seed 4)``
    without encoder noise, one reflector at (15, -10, 60) mm measured with 0.02 mm (tracker seed 5,
    noise seed 6); ``robocal calibrate --force`` on each campaign, and the calibrated model compared
    with the hidden truth at 300 feasible poses of the full cell (seed 0).

    Fields per campaign ``{name}.``: ``holdout_rms_mm`` (result.json, held-out RMS after),
    ``n_identified`` (variables identified, with base and target), ``n_missing`` (robot
    parameters a full campaign identifies that were not), ``true_rms_mm`` (RMS of the calibrated
    model's reflector position against the true one over the 300 poses), ``failed`` (1 when the
    gate failed, exit 3), ``n_joints_named`` (joints the reasons name)."""
    from dataclasses import replace

    import numpy as np

    from ..calib.cell import default_cell, sample_feasible
    from ..io.measurements import write_measurements
    from ..robots import load_robot
    from ..sim import LaserTracker, VirtualRobot

    robot = "kuka_kr150_r3100"
    point = (15.0, -10.0, 60.0)
    model = load_robot(robot)
    virtual = VirtualRobot.perturbed(model, 4, joint_noise_deg=0.0)
    tracker = LaserTracker.placed(5, np.array([point]), sigma_mm=0.02)
    q_check, _ = sample_feasible(default_cell(point), model, 300, np.random.default_rng(0), margin=0.05)
    true_points = tracker.true_points(virtual, q_check)[:, 0]
    out = {}
    with tempfile.TemporaryDirectory() as tmp:
        for name, fixed in COVERAGE_CAMPAIGNS.items():
            ranges = np.array(model.limits, dtype=float)
            for k, deg in fixed.items():
                ranges[k] = np.radians([deg, deg])
            cell = replace(default_cell(point), joint_ranges=ranges)
            q, _ = sample_feasible(cell, model, 40, np.random.default_rng(3), margin=0.05)
            csv = Path(tmp) / f"{name}.csv"
            write_measurements(csv, tracker.measure(virtual, q, np.random.default_rng(6)))
            cal = Path(tmp) / name
            run_cli("calibrate", robot, csv, "--out", cal, "--no-report", "--force", ok=(0, 3))
            res = json.loads((cal / "result.json").read_text())
            fitted = load_robot(str(cal / "calibrated_robot.toml"))
            p = np.asarray(res["targets"][0]["point_mm"], float)
            T = fitted.fk(q_check)
            err = np.linalg.norm(T[:, :3, :3] @ p + T[:, :3, 3] - true_points, axis=-1)
            reasons = " ".join(res["reasons"])
            m = re.search(r"only (\d+) of the (\d+) parameters a full campaign identifies", reasons)
            out.update({f"{name}.holdout_rms_mm": float(res["validation"]["after"]["rms"]),
                        f"{name}.n_identified": float(len(res["identifiability"]["identifiable"])),
                        f"{name}.n_missing": float(int(m.group(2)) - int(m.group(1))) if m else 0.0,
                        f"{name}.true_rms_mm": float(np.sqrt(np.mean(err ** 2))),
                        f"{name}.failed": float(res["status"] == "failed"),
                        f"{name}.n_joints_named": float(len(set(re.findall(r"joint (A\d) moved only", reasons))))})
    return out


# ------------------------------------------------------------------- robot programs at the robot
def _execute(truth, program, cal, *extra) -> dict:
    """``robocal simulate execute --json``: ``{target: row}``."""
    doc = json.loads(run_cli("simulate", "execute", truth, program, "--cell-base", cal, "--json", *extra))
    return {r["target"]: r for r in doc["targets"]}


def _sigmas(report: Path) -> list:
    """The corrected Cartesian targets' printed sigma [mm] of a ``correct`` report (CSV)."""
    import csv

    with open(report, newline="") as f:
        rows = csv.DictReader(line for line in f if not line.startswith("#"))
        return [float(r["sigma_mm"]) for r in rows if r["status"] == "corrected"]


def _summary(prefix: str, before: dict, after: dict, sigma: list) -> dict:
    """Per-target before/after errors [mm] (``{prefix}.{before|after}.{target}``), their mean and
    max, the largest orientation error after [deg], and the sigma range [mm]."""
    import numpy as np

    out = {}
    names = [n for n, r in before.items() if r["kind"] == "cartesian"]
    for what, rows in (("before", before), ("after", after)):
        e = [rows[n]["error_mm"] for n in names]
        out.update({f"{prefix}.{what}.{n}": float(v) for n, v in zip(names, e)})
        out[f"{prefix}.{what}.mean"], out[f"{prefix}.{what}.max"] = float(np.mean(e)), float(np.max(e))
        out[f"{prefix}.{what}.min"] = float(np.min(e))
    out[f"{prefix}.after_deg.max"] = float(max(after[n]["error_deg"] for n in names))
    out[f"{prefix}.sigma.min"], out[f"{prefix}.sigma.max"] = float(min(sigma)), float(max(sigma))
    return out


def _with_krl_tool(config: Path, out: Path, r1) -> None:
    """``config.dat`` with ``TOOL_DATA[1]`` = the identified reflector ``r1`` [mm] (the page's ``sed``)."""
    tool = "TOOL_DATA[1]={X %.3f,Y %.3f,Z %.3f,A 0,B 0,C 0}" % tuple(r1)
    out.write_text(re.sub(r"TOOL_DATA\[1\]=\{[^}]*\}", tool, config.read_text()))


def _with_ur_tool(script: Path, out: Path, r1) -> None:
    """A UR script whose ``set_tcp`` is the identified reflector ``r1`` [mm] (the page's ``sed``)."""
    tcp = "set_tcp(p[%.6f, %.6f, %.6f, 0.0, 0.0, 0.0])" % tuple(v / 1000.0 for v in r1)
    out.write_text(re.sub(r"set_tcp\(p\[[^]]*\]\)", tcp, script.read_text()))


def _r1(cal: Path) -> list:
    """The identified reflector r1 [mm, flange frame] of a calibration's result.json."""
    res = json.loads((cal / "result.json").read_text())
    return [float(v) for v in next(t["point_mm"] for t in res["targets"] if t["name"] == "r1")]


@functools.lru_cache(maxsize=None)
def programs_at_robot() -> dict:
    """docs/robot-programs.md "Measured: KRL on a KR 150 and a UR10": the page's commands on
    ``docs/examples/programs/`` in a temporary copy (KR 150 seed 1, UR10 seed 3, 60 poses, 3
    reflectors), the TCP position errors of the true robot per Cartesian target before and after
    correction [mm], with the program's tool (``kr.tool``, ``ur.tool``) and with the identified
    reflector r1 as the tool (``kr.r1``, ``ur.r1``; physical tool the true r1, (100, 0, 40) mm).

    Fields (:func:`_summary`) ``{kr|ur}.{tool|r1}.{before|after}.{target|mean|max}``,
    ``.after_deg.max``, ``.sigma.{min|max}``; ``{kr|ur}.r1_identified.{x|y|z}`` [mm];
    ``ur.true.{d6|a6}_error_mm`` (truth minus nominal); ``ur.after.{J5 of movel@7, J1 of movel@9}``
    as ``ur.joint.{movel@7.J5|movel@9.J1}`` [deg]."""
    src = repository_root_examples()
    out = {}
    with tempfile.TemporaryDirectory() as tmp:
        d = Path(tmp)
        for f in ("cell.dat", "config.dat", "pick.script"):
            shutil.copy(src / f, d / f)
        # KRL on a KR 150
        run_cli("simulate", "tracker", "kuka_kr150_r3100", "--poses", 60, "--reflectors", 3, "--seed", 1,
                "--out", d / "kr.csv")
        cal = d / "kr-cal"
        run_cli("calibrate", "kuka_kr150_r3100", d / "kr.csv", "--out", cal, "--no-report")
        model = cal / "calibrated_robot.toml"
        truth, cdat = d / "kr.truth.json", ("--config-dat", d / "config.dat")
        run_cli("correct", model, d / "cell.dat", *cdat, "--out", d / "cell_corrected.dat")
        out.update(_summary("kr.tool", _execute(truth, d / "cell.dat", model, *cdat),
                            _execute(truth, d / "cell_corrected.dat", model, "--intended", d / "cell.dat", *cdat),
                            _sigmas(d / "cell_corrected.dat.report.csv")))
        r1 = _r1(cal)
        out.update({f"kr.r1_identified.{c}": v for c, v in zip("xyz", r1)})
        _with_krl_tool(d / "config.dat", d / "config_smr.dat", r1)
        smr = ("--config-dat", d / "config_smr.dat", "--true-tool", "100,0,40")
        run_cli("correct", model, d / "cell.dat", "--config-dat", d / "config_smr.dat", "--out", d / "cell_smr_corrected.dat")
        out.update(_summary("kr.r1", _execute(truth, d / "cell.dat", model, *smr),
                            _execute(truth, d / "cell_smr_corrected.dat", model, "--intended", d / "cell.dat", *smr),
                            _sigmas(d / "cell_smr_corrected.dat.report.csv")))
        # UR script on a UR10
        run_cli("simulate", "tracker", "ur10", "--poses", 60, "--reflectors", 3, "--seed", 3, "--out", d / "ur.csv")
        cal = d / "ur-cal"
        run_cli("calibrate", "ur10", d / "ur.csv", "--out", cal, "--no-report")
        model, truth = cal / "calibrated_robot.toml", d / "ur.truth.json"
        run_cli("correct", model, d / "pick.script", "--out", d / "pick_corrected.script")
        after = _execute(truth, d / "pick_corrected.script", model, "--intended", d / "pick.script")
        out.update(_summary("ur.tool", _execute(truth, d / "pick.script", model), after,
                            _sigmas(d / "pick_corrected.script.report.csv")))
        r1 = _r1(cal)
        out.update({f"ur.r1_identified.{c}": v for c, v in zip("xyz", r1)})
        out.update({f"ur.r1_identified_m.{c}": v / 1000.0 for c, v in zip("xyz", r1)})
        _with_ur_tool(d / "pick.script", d / "pick_smr.script", r1)
        run_cli("correct", model, d / "pick_smr.script", "--out", d / "pick_smr_corrected.script")
        out.update(_summary("ur.r1", _execute(truth, d / "pick_smr.script", model, "--true-tool", "100,0,40"),
                            _execute(truth, d / "pick_smr_corrected.script", model, "--intended", d / "pick_smr.script",
                                     "--true-tool", "100,0,40"),
                            _sigmas(d / "pick_smr_corrected.script.report.csv")))
        for name, j in (("movel@7", 4), ("movel@9", 0)):
            out[f"ur.joint.{name}.J{j + 1}"] = float(after[name]["joints_deg"][j])
        t = json.loads(truth.read_text())
        for p in ("d6", "a6"):
            out[f"ur.true.{p}_error_mm"] = float(t["true_parameters"][p] - t["nominal_parameters"][p])
    return out


@functools.lru_cache(maxsize=None)
def program_with_effects(effects: str) -> dict:
    """docs/robot-programs.md "With effects the model lacks": the KRL case with the identified r1
    as the tool, KR 150 seed 1, 60 poses, 3 reflectors, ``--effects EFFECTS``, ``calibrate
    --noise 0.02``. Fields as :func:`programs_at_robot`'s ``kr.r1`` (prefix ``kr``) and
    ``holdout_rms_mm`` (result.json, held-out RMS after)."""
    src = repository_root_examples()
    with tempfile.TemporaryDirectory() as tmp:
        d = Path(tmp)
        for f in ("cell.dat", "config.dat"):
            shutil.copy(src / f, d / f)
        run_cli("simulate", "tracker", "kuka_kr150_r3100", "--poses", 60, "--reflectors", 3, "--seed", 1,
                "--effects", effects, "--out", d / "kr.csv")
        cal = d / "kr-cal"
        run_cli("calibrate", "kuka_kr150_r3100", d / "kr.csv", "--out", cal, "--no-report", "--noise", 0.02)
        model, truth = cal / "calibrated_robot.toml", d / "kr.truth.json"
        _with_krl_tool(d / "config.dat", d / "config_smr.dat", _r1(cal))
        smr = ("--config-dat", d / "config_smr.dat", "--true-tool", "100,0,40")
        run_cli("correct", model, d / "cell.dat", "--config-dat", d / "config_smr.dat", "--out", d / "cell_smr_corrected.dat")
        out = _summary("kr", _execute(truth, d / "cell.dat", model, *smr),
                       _execute(truth, d / "cell_smr_corrected.dat", model, "--intended", d / "cell.dat", *smr),
                       _sigmas(d / "cell_smr_corrected.dat.report.csv"))
        out["removed_percent"] = 100.0 * (1.0 - out["kr.after.mean"] / out["kr.before.mean"])
        out["holdout_rms_mm"] = float(json.loads((cal / "result.json").read_text())["validation"]["after"]["rms"])
    return out


@functools.lru_cache(maxsize=None)
def thermal_seed_2024(preset: str) -> dict:
    """docs/thermal.md "simulate" and "screen": ``robocal thermal simulate --seed 2024 --cycles 90
    --preset PRESET`` (per run ``run{k}.{hours|tcp_3h_mm|tcp_end_mm|tcp_max_mm}``), ``robocal thermal
    screen RUN1 --json`` and ``--params`` (the set screened on run 1) on runs 2 and 3: λ [%] as
    ``run{k}.lambda.{before|traditional|screened}``; ``robocal thermal calibrate-sensor`` with the
    nominal model on run 1's cold spheres, ``--truth``: ``sensor.residual_rms_mm`` and the errors
    ``sensor.{rotation_deg|at_point_mm|P_e_mm|...}``; with a robot file of the true parameters:
    ``sensor_true.{rotation_deg|at_point_mm|P_e_mm|...}``."""
    out = {}
    with tempfile.TemporaryDirectory() as tmp:
        d = Path(tmp) / "cell"
        text = run_cli("thermal", "simulate", "--out", d, "--seed", 2024, "--cycles", 90, "--preset", preset)
        for k, hours, t3, end, mx in re.findall(r"(?m)^\s+([123])\s+\w+\s+\d+\s+([0-9.]+)\s+([0-9.]+|-)\s+([0-9.]+)\s+"
                                                r"([0-9.]+)\s", text):
            out.update({f"run{k}.hours": float(hours), f"run{k}.tcp_end_mm": float(end), f"run{k}.tcp_max_mm": float(mx)})
            if t3 != "-":
                out[f"run{k}.tcp_3h_mm"] = float(t3)
        cal = json.loads(run_cli("thermal", "calibrate-sensor", "kuka_kr150_r3100", d / "run1" / "sphere_cold.csv",
                                 "--truth", d / "run1" / "truth.json", "--json"))
        out["sensor.residual_rms_mm"] = float(cal["results"][0]["residual_rms_mm"])
        out.update({f"sensor.{k}": float(v) for k, v in cal["errors"]["least-squares"].items()})
        # the same with the true geometry (a robot file of the truth's parameters, as a geometric calibration gives)
        from ..robots import load_robot
        from ..robots.writer import save_robot

        truth = json.loads((d / "run1" / "truth.json").read_text())
        m = load_robot(truth["robot"])
        save_robot(m.with_params([truth["true_parameters"][n] for n in m.params.names]), Path(tmp) / "true_robot.toml")
        cal = json.loads(run_cli("thermal", "calibrate-sensor", Path(tmp) / "true_robot.toml", d / "run1" / "sphere_cold.csv",
                                 "--truth", d / "run1" / "truth.json", "--json"))
        out.update({f"sensor_true.{k}": float(v) for k, v in cal["errors"]["least-squares"].items()})
        first = json.loads(run_cli("thermal", "screen", d / "run1", "--json"))
        runs = {1: first}
        for k in (2, 3):
            runs[k] = json.loads(run_cli("thermal", "screen", d / f"run{k}", "--params", ",".join(first["selected"]),
                                         "--json"))
    for k, r in runs.items():
        out.update({f"run{k}.lambda.{m}": float(v) for m, v in r["lambda_percent"].items() if v is not None})
    return out


@functools.lru_cache(maxsize=None)
def thermal_compensate() -> dict:
    """docs/thermal.md "compensate" (the set-up of ``tests/test_thermal_cli.py``): ``robocal thermal
    simulate --seed 2024 --cycles 20 --preset ideal``, ``screen`` run 1, ``calibrate-sensor`` on run
    1's cold spheres, ``compensate`` run 2 after cycle 20 with the screened set from its 6 online
    poses and their cold reference, the 34-point program. Fields ``residual_rms_{before|after}_mm``,
    ``condition_number`` and, on the true simulated robot (warm at cycle 20 against cold at the
    taught joints), ``true.{before_max|after_max|after_mean}_mm``."""
    import numpy as np

    from ..io.programs.joint_table import read_joint_program
    from ..robots import load_robot

    robot, cycles = "kuka_kr150_r3100", 20
    with tempfile.TemporaryDirectory() as tmp:
        d = Path(tmp) / "cell"
        run_cli("thermal", "simulate", "--seed", 2024, "--cycles", cycles, "--preset", "ideal", "--out", d)
        screen = json.loads(run_cli("thermal", "screen", d / "run1", "--json"))
        sensor = Path(tmp) / "sensor.json"
        run_cli("thermal", "calibrate-sensor", robot, d / "run1" / "sphere_cold.csv", "--out", sensor)
        run2 = d / "run2"
        poses = ",".join(f"c{cycles:03d}-{p}" for p in screen["online_poses"]["screened"])
        out = Path(tmp) / "corrected.csv"
        r = json.loads(run_cli("thermal", "compensate", robot, "--sensor", sensor, "--sphere", run2 / "sphere.csv",
                               "--poses", poses, "--cold", run2 / "sphere_cold.csv", "--params",
                               ",".join(screen["selected"]), "--program", d / "program.csv", "--out", out, "--json"))
        truth = json.loads((run2 / "truth.json").read_text())
        model = load_robot(robot)
        taught, corrected = read_joint_program(d / "program.csv", model), read_joint_program(out, model)
    true = model.with_params([truth["true_parameters"][n] for n in model.params.names])
    warm = true.with_params(true.params.values + np.array(truth["delta_true"][cycles - 1]))
    cold = true.fk(taught.joints)[:, :3, 3]
    before = np.linalg.norm(warm.fk(taught.joints)[:, :3, 3] - cold, axis=1)
    after = np.linalg.norm(warm.fk(corrected.joints)[:, :3, 3] - cold, axis=1)
    return {"residual_rms_before_mm": float(r["residual_rms_before_mm"]),
            "residual_rms_after_mm": float(r["residual_rms_after_mm"]), "condition_number": float(r["condition_number"]),
            "true.before_max_mm": float(before.max()), "true.after_max_mm": float(after.max()),
            "true.after_mean_mm": float(after.mean())}


@functools.lru_cache(maxsize=None)
def ik_train_example() -> dict:
    """docs/kinematics.md "Command line": ``robocal ik-train abb_irb140 --samples 20000 --seed 0``
    and ``robocal ik abb_irb140 513.1 119.1 441.8 -166.5 5.4 154.6 --deg --seed-net ... --json``:
    ``centres``, ``validation.{joint_deg|position_mm}`` (medians), ``seed.position_error_mm``,
    ``seed.ok`` (1 when the seed's status is ok), ``solution.max_joint_error_deg`` (against
    J = (10, 20, 10, 30, 60, -20) deg)."""
    with tempfile.TemporaryDirectory() as tmp:
        net = Path(tmp) / "irb140.iknet.npz"
        text = run_cli("ik-train", "abb_irb140", "--samples", 20000, "--seed", 0, "--out", net)
        doc = json.loads(run_cli("ik", "abb_irb140", 513.1, 119.1, 441.8, -166.5, 5.4, 154.6, "--deg", "--seed-net", net,
                                 "--json"))
    out = {"centres": float(re.search(r"(\d+) centres, trained", text).group(1)),
           "validation.joint_deg": float(re.search(r"joint error \[deg\]\s+([0-9.]+)", text).group(1)),
           "validation.position_mm": float(re.search(r"position error \[mm\]\s+([0-9.]+)", text).group(1)),
           "seed.position_error_mm": float(doc["seed"]["position_error_mm"]),
           "seed.ok": float(doc["seed"]["status"] == "ok")}
    target = (10.0, 20.0, 10.0, 30.0, 60.0, -20.0)
    out["solution.max_joint_error_deg"] = min(max(abs(a - b) for a, b in zip(s["joints"], target))
                                              for s in doc["solutions"])
    return out


@functools.lru_cache(maxsize=None)
def tutorial() -> dict:
    """docs/tutorial.md: ``robocal simulate tracker ur10 --poses 80 --noise 0.02 --seed 5``, then
    ``robocal.calibrate`` with ``CalibrationOptions(holdout=0.25, seed=3, noise_mm=0.02)``: the
    held-out RMS ``holdout.{before|after}`` [mm]."""
    import robocal

    with tempfile.TemporaryDirectory() as tmp:
        csv = Path(tmp) / "campaign.csv"
        run_cli("simulate", "tracker", "ur10", "--poses", 80, "--noise", 0.02, "--seed", 5, "--out", csv)
        robot = robocal.load_robot("ur10")
        result = robocal.calibrate(robot, robocal.read_measurements(str(csv), robot),
                                   options=robocal.CalibrationOptions(holdout=0.25, seed=3, noise_mm=0.02))
    return {"holdout.before": float(result.holdout["before"]["rms"]), "holdout.after": float(result.holdout["after"]["rms"])}


@functools.lru_cache(maxsize=None)
def ros_handeye(test_set: str) -> dict:
    """docs/datasets.md "ros_industrial_handeye": ``robocal handeye solve
    <datasets>/ros_industrial_handeye/raw/TEST_SET/cal_data.yaml --exact-poses --json``: ``rms_px``,
    ``n_images_used``, ``n_corners``, the camera pose ``position_mm.{0,1,2}``, ``sigma_position_mm.{0,1,2}``,
    ``rotation_vector_deg.{0,1,2}``, ``sigma_rotation_deg.max``, ``rms_mm`` (on the target plane), the linear
    starts ``linear.{method}.difference_position_mm`` / ``.rms_px`` (and ``linear.rms_px.min`` / ``.max``) and
    ``images.{name}.rms_px`` per image, ``images.n_points.{min|max}`` (corners detected per used image)."""
    from ..io.datasets import datasets_root

    src = datasets_root() / "ros_industrial_handeye" / "raw" / test_set / "cal_data.yaml"
    with tempfile.TemporaryDirectory() as tmp:
        d = json.loads(run_cli("handeye", "solve", src, "--exact-poses", "--out", Path(tmp) / "out", "--json"))
    pose = d["camera_pose"]
    out = {"rms_px": float(d["reprojection_rms_px"]), "n_images_used": float(d["n_images_used"]),
           "n_corners": float(d["n_corners"]), "sigma_rotation_deg.max": float(max(pose["sigma_rotation_deg"]))}
    for key in ("position_mm", "sigma_position_mm", "rotation_vector_deg"):
        out.update({f"{key}.{k}": float(v) for k, v in enumerate(pose[key])})
    out["rms_mm"] = float(d["reprojection_rms_mm"])
    for m, lin in d["linear"].items():  # the linear starts: distance from the refined position, their RMS
        out[f"linear.{m}.difference_position_mm"] = float(lin["difference_position_mm"])
        out[f"linear.{m}.rms_px"] = float(lin["reprojection_rms_px"])
    rms = [out[f"linear.{m}.rms_px"] for m in d["linear"]]
    out["linear.rms_px.min"], out["linear.rms_px.max"] = min(rms), max(rms)
    out.update({f"images.{im['name']}.rms_px": float(im["rms_px"]) for im in d["images"] if im.get("rms_px") is not None})
    points = [im["n_points"] for im in d["images"] if im.get("used") and im.get("n_points") is not None]
    if points:  # corners detected per used image
        out["images.n_points.min"], out["images.n_points.max"] = float(min(points)), float(max(points))
    return out


def repository_root_examples() -> Path:
    """``docs/examples/programs`` of the repository."""
    from .figure_producers import repository_root

    return repository_root() / "docs" / "examples" / "programs"


CLI_PRODUCERS = {
    "calibration/coverage_gates": coverage_gates,
    "programs/at_robot": programs_at_robot,
    "programs/effects_ideal": lambda: program_with_effects("ideal"),
    "programs/effects_realistic": lambda: program_with_effects("realistic"),
    "ik_net/cli_example": ik_train_example,
    "tutorial/calibrate": tutorial,
    "thermal_cli/compensate": thermal_compensate,
    **{f"ros_handeye/{t}": functools.partial(ros_handeye, t) for t in ("test_set_charuco", "test_set_10x10")},
    **{f"thermal_cli/{p}": functools.partial(thermal_seed_2024, p) for p in ("realistic", "ideal")},
}
