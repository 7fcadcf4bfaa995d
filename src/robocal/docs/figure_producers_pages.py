"""Producers of the documented figures of docs/iso9283.md, docs/reliability.md, docs/robots.md,
docs/fleet.md, docs/thermal.md and the smaller pages that no other producer computes
(:mod:`robocal.docs.figures`). Each runs the page's commands or the test's own set-up (shared with
the test through ``robocal.sim``) and returns a flat ``{field: value}`` dict; cached."""

from __future__ import annotations

import functools
import json
import tempfile
from pathlib import Path

__all__ = ["PAGES_DATASETS_NEEDED", "PAGES_PRODUCERS", "SLOW_PAGES_PRODUCERS", "iso9283_simulated_run",
           "monte_carlo_test_plan", "parallel_beta_campaign", "justin_head_capture", "rendered_board_views",
           "rokae_style_robot_file"]


# ------------------------------------------------------------------------------------ iso9283.md
def iso9283_simulated_run(folder: Path) -> tuple:
    """The simulated ISO 9283 test of an IRB 140 through the command line (``tests/test_iso9283.py``'s
    fixture and docs/iso9283.md "Is the instrument good enough?"): ``iso9283 plan abb_irb140
    --drift-hours 1``, ``simulate iso9283 --seed 4 --instrument-at 3500,0,300``, and ``iso9283
    evaluate --mpe 15um+6um/m`` of the tracker file and of the truth file, in ``folder``.

    Returns
    -------
    (dict, dict)
        The plan's JSON and ``{"run.csv" | "run.truth.csv": evaluation JSON}``.
    """
    from .figure_producers_cli import run_cli as run

    d = Path(folder)
    plan = json.loads(run("iso9283", "plan", "abb_irb140", "--out", d / "plan", "--drift-hours", 1, "--json"))
    run("simulate", "iso9283", "abb_irb140", d / "plan", "--seed", 4, "--out", d / "run.csv", "--instrument-at",
        "3500,0,300")
    out = {name: json.loads(run("iso9283", "evaluate", d / "plan", d / name, "--out", d / ("ev-" + name), "--mpe",
                                "15um+6um/m", "--instrument-at", "3500,0,300", "--json"))
           for name in ("run.csv", "run.truth.csv")}
    return plan, out


@functools.lru_cache(maxsize=None)
def iso9283_adequacy() -> dict:
    """docs/iso9283.md "Is the instrument good enough?": the RP of P1-P5 measured by the tracker
    (``RP.min``, ``RP.max`` [mm]) and how many of them (``RP.inadequate``) and of the APs
    (``AP.adequate``) the adequacy judges so (:func:`iso9283_simulated_run`; ~2.5 s)."""
    with tempfile.TemporaryDirectory() as tmp:
        _, out = iso9283_simulated_run(Path(tmp))
    run = out["run.csv"]["runs"][0]
    rp = [p["RP_mm"] for p in run["pose"].values()]
    ade = run["adequacy"]
    return {"RP.min": min(rp), "RP.max": max(rp),
            "RP.inadequate": float(sum(not v["adequate"] for k, v in ade.items() if k.startswith("RP_mm."))),
            "AP.adequate": float(sum(v["adequate"] for k, v in ade.items() if k.startswith("AP_mm.")))}


@functools.lru_cache(maxsize=None)
def verify_backlash_trials() -> dict:
    """docs/iso9283.md "Backlash" (``tests/test_verify.py``'s set-up, :mod:`robocal.sim.verify_trials`):
    a 0.1 deg backlash of each of J1-J5, 100 checks each; the smallest and largest share [%] over the
    joints of checks ``detected``, ``named`` (as that joint's backlash) and ``offset_named`` (a
    0.05 deg offset jump on the same data named an offset). ~6 s of CPU."""
    from ..sim.verify_trials import backlash_trials

    rows = [backlash_trials(j) for j in range(5)]
    out = {}
    for k in ("detected", "named", "offset_named"):
        share = [100.0 * r[k] / r["trials"] for r in rows]
        out[f"{k}.min"], out[f"{k}.max"] = min(share), max(share)
    return out


@functools.lru_cache(maxsize=None)
def verify_backlash_command() -> dict:
    """docs/iso9283.md "Backlash", through the command line (the page's commands, as
    ``tests/test_verify.py::test_verify_command_names_a_backlash_from_approach_columns``):
    ``simulate tracker abb_irb140 --poses 60 --seed 3``, ``calibrate``, a 10-pose check (seed 3)
    whose J2 readings are moved by +-0.075 deg by approach side (:func:`robocal.sim.verify_trials.
    with_backlash_columns`, seed 7), ``verify --json`` (exit 6). Fields ``T``, ``threshold``,
    ``remaining_T``, ``remaining_threshold``, ``backlash_deg``, ``backlash_std_deg``. ~1.5 s of CPU."""
    import re

    from ..sim.verify_trials import with_backlash_columns
    from .figure_producers_cli import run_cli as run

    with tempfile.TemporaryDirectory() as tmp:
        d = Path(tmp)
        run("simulate", "tracker", "abb_irb140", "--poses", 60, "--seed", 3, "--out", d / "c.csv")
        run("calibrate", "abb_irb140", d / "c.csv", "--out", d / "cal")
        run("simulate", "tracker", "abb_irb140", "--poses", 10, "--seed", 3, "--out", d / "v.csv")
        (d / "b.csv").write_text(with_backlash_columns((d / "v.csv").read_text(), "J2", 0.15, seed=7))
        r = json.loads(run("verify", d / "cal", d / "b.csv", "--json", ok=(6,)))
    m = re.search(r"remaining T = ([0-9.]+) <= ([0-9.]+)", " ".join(r["reasons"]))
    return {"T": r["statistic"], "threshold": r["threshold"], "remaining_T": float(m.group(1)),
            "remaining_threshold": float(m.group(2)), "backlash_deg": r["suspect_offset"]["value"],
            "backlash_std_deg": r["suspect_offset"]["std"], "exit_code": 6.0}


@functools.lru_cache(maxsize=None)
def iso9283_wear_per_day() -> dict:
    """docs/iso9283.md "Over the robot's life": the worn robot's RP trend slope per day [mm]
    (``fleet status``'s, producer ``iso9283/wear``): how much the trend "now" grows a day."""
    from .figure_producers import PRODUCERS

    w = PRODUCERS["iso9283/wear"]()
    return {"worn.RP.slope_mm_per_day": w["status.worn.RP.slope_mm_per_30_days"] / 30.0}


# -------------------------------------------------------------------------------- reliability.md
@functools.lru_cache(maxsize=None)
def lm_stop_linear() -> dict:
    """docs/reliability.md "One convergence policy" (``tests/test_lm_stop_linear.py``'s problem,
    :mod:`robocal.sim.solver_problems`): the chi-square rule's stop on the slowly contracting problem,
    ``iterations`` and ``excess`` (cost above the minimum in residual variances). ~0.1 s."""
    import warnings

    from ..calib import solve
    from ..sim.solver_problems import excess_in_variances, large_residual_problem

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = solve(large_residual_problem(), max_iterations=1000, auto_identifiable=False)
    excess, _ = excess_in_variances(res)
    return {"iterations": float(res.iterations), "excess": excess, "converged": float(res.converged)}


@functools.lru_cache(maxsize=None)
def camera_gate_stretched() -> dict:
    """docs/reliability.md "Camera" (``tests/test_handeye_gate.py``'s set-up): ``simulate camera
    --images 8 --seed 4``; ``camera calibrate`` on the clean images (``clean_rms_px``) and on the
    set with every other image stretched 1.3 x sideways (:func:`robocal.sim.cameras.image_faults.
    stretch_every_other_image`; ``stretched_rms_px``, ``stretched_exit`` = 3)."""
    import shutil

    from ..sim.cameras.image_faults import stretch_every_other_image
    from .figure_producers_cli import run_cli as run

    board = "charuco:9x7:30mm:22mm:DICT_5X5_100"
    with tempfile.TemporaryDirectory() as tmp:
        d = Path(tmp)
        run("simulate", "camera", "--out", d / "cell", "--images", 8, "--seed", 4)
        shutil.copytree(d / "cell" / "images", d / "mixed")
        stretch_every_other_image(d / "mixed", 1.3)
        run("camera", "calibrate", d / "mixed", "--board", board, "--out", d / "c", ok=(3,))
        bad = json.loads((d / "c" / "camera_calibration.json").read_text())
        run("camera", "calibrate", d / "cell" / "images", "--board", board, "--out", d / "clean")
        good = json.loads((d / "clean" / "camera_calibration.json").read_text())
    return {"stretched_rms_px": float(bad["reprojection_rms_px"]), "clean_rms_px": float(good["reprojection_rms_px"]),
            "stretched_exit": 3.0}


@functools.lru_cache(maxsize=None)
def touchup_one_pose_off() -> dict:
    """docs/reliability.md's gate table (``tests/test_tool_gates.py``'s set-up): seven touch-up poses
    (:func:`robocal.sim.tool.touch_poses.touch_poses`, seed 3, 0.05 mm noise), the fifth moved by
    (3, -4, 0) mm; the four-point fit's TCP error [mm] (``tcp_error_mm``) and its RMS (``rms_mm``)."""
    import numpy as np

    from ..sim.tool.touch_poses import TCP_TRUE_MM, touch_poses
    from ..tcp.touchup import four_point_tcp

    T = touch_poses(7, np.random.default_rng(3), noise=0.05)
    T[4, :3, 3] += np.array([3.0, -4.0, 0.0])
    fit = four_point_tcp(T)
    return {"tcp_error_mm": float(np.linalg.norm(fit.tcp_mm - TCP_TRUE_MM)), "rms_mm": float(fit.rms_mm)}


# ------------------------------------------------------------------------------------- robots.md
@functools.lru_cache(maxsize=None)
def robot_file_checks() -> dict:
    """docs/robots.md, computed from the robot files: ``ur10e.zero.{x|y|z}`` (the flange at q = 0
    [mm]); ``nao.camera_top.{x|z}`` and ``nao.left_hand.{x|y|z}`` at the zero pose [mm];
    ``bx200l.reach_mm``: the largest horizontal distance of the wrist centre (origin of link 4's
    frame) from the J1 axis within the J2/J3 limits (a 201 x 201 grid refined by L-BFGS-B)."""
    import numpy as np
    from scipy.optimize import minimize

    from ..robots import load_robot

    out = {}
    T = load_robot("ur10e").fk(np.zeros((1, 6)))[0]
    out.update({f"ur10e.zero.{c}": float(T[i, 3]) for i, c in enumerate("xyz")})
    nao = load_robot("nao_h25")
    q = np.zeros((1, nao.n_joints))
    cam = nao.fk(q, "camera_top")[0]
    hand = nao.fk(q, "left_hand")[0]
    out.update({"nao.camera_top.x": float(cam[0, 3]), "nao.camera_top.z": float(cam[2, 3])})
    out.update({f"nao.left_hand.{c}": float(hand[i, 3]) for i, c in enumerate("xyz")})
    m = load_robot("kawasaki_bx200l")
    lo, hi = m.limits[1:3, 0], m.limits[1:3, 1]

    def reach(x):
        qq = np.zeros((len(x), 6))
        qq[:, 1:3] = x
        p = m.link_frames(qq)[:, 3, :3, 3]
        return np.hypot(p[:, 0], p[:, 1])

    A, B = np.meshgrid(np.linspace(lo[0], hi[0], 201), np.linspace(lo[1], hi[1], 201), indexing="ij")
    grid = np.column_stack([A.ravel(), B.ravel()])
    x0 = grid[np.argmax(reach(grid))]
    r = minimize(lambda x: -reach(x[None])[0], x0, bounds=list(zip(lo, hi)), method="L-BFGS-B")
    out["bx200l.reach_mm"] = float(-r.fun)
    return out


@functools.lru_cache(maxsize=None)
def boby_nominal_all_poses() -> dict:
    """docs/robots.md "How these files were checked", FANUC: on the ``boby_fanuc`` data, the nominal
    ``fanuc_r2000ic_165f`` with a fitted base and 3 SMR points (started 250 mm out on the flange
    axis) over all 36 poses: ``rms``, ``mean``, ``max`` [mm] of the point errors."""
    import numpy as np

    from ..calib import Target
    from ..io.datasets import read_boby_fanuc
    from ..robots import load_robot
    from ..workflows.datasets._fitting import error_stats, fit

    ds = read_boby_fanuc()
    targets = [Target(n, None, (0.0, 0.0, 250.0)) for n in ds.targets]
    p, r = fit(load_robot("fanuc_r2000ic_165f"), ds.joints, targets, ds.points, free=[])
    pred = p.predict_points(r.state, q=ds.joints, stations=np.zeros(ds.n_poses, int))
    return {**error_stats(pred, ds.points), "converged": float(r.converged)}


@functools.lru_cache(maxsize=None)
def hilti_flat_rigid_per_station() -> dict:
    """docs/robots.md "How these files were checked", Hilti: the nominal ``hilti_trailblazer`` URDF
    (prism at the tool frame) and one rigid fit (Kabsch) per station (column height x solution
    space) of all its points on ``flat``; ``rms``, ``mean``, ``max`` [mm] over every point."""
    import numpy as np

    from ..calib import Target, rigid_fit
    from ..io.datasets import read_hilti_trailblazer
    from ..robots import load_robot
    from ..workflows.datasets._fitting import error_stats, points_in_base

    flat = read_hilti_trailblazer("flat")
    pred = points_in_base(load_robot("hilti_trailblazer"), flat.joints, [Target("prism", None, (0.0, 0.0, 0.0))])[:, 0]
    fitted, measured = [], []
    for g in range(len(flat.station_labels)):
        sel = flat.stations == g
        if sel.sum() < 3:
            continue
        T = rigid_fit(pred[sel], flat.points[sel, 0])
        fitted.append(pred[sel] @ T[:3, :3].T + T[:3, 3])
        measured.append(flat.points[sel, 0])
    return error_stats(np.concatenate(fitted), np.concatenate(measured))


# -------------------------------------------------------------------------------------- fleet.md
def monte_carlo_test_plan():
    """The pose plan of docs/fleet.md's Monte-Carlo figure and of ``tests/test_fleet.py``'s
    Monte-Carlo test: UR10, 30 D-optimal poses of 400 feasible candidates (seed 2), as
    ``robocal plan-poses`` plans them. Returns the joints (30, 6) [rad]."""
    from ..calib.plan import plan_campaign
    from ..robots import load_robot
    from ..workflows.calibration.plan_poses import candidate_poses

    model = load_robot("ur10")
    qk, _ = candidate_poses(model, 30, 400, 2)
    return qk[plan_campaign(model, qk, 30)["indices"]]


@functools.lru_cache(maxsize=None)
def fleet_monte_carlo() -> dict:
    """docs/fleet.md "monte-carlo": ``monte_carlo_plan`` (serial) of :func:`monte_carlo_test_plan`,
    200 samples, 0.02 mm, 200 check poses, seed 4: ``after.median`` [mm], ``predicted`` [mm] (the
    first-order prediction), ``ratio`` and ``unconverged`` (samples stopped at the iteration limit).
    ~6 s of CPU."""
    import numpy as np

    from ..workflows.fleet.study import monte_carlo_plan

    r = monte_carlo_plan("ur10", monte_carlo_test_plan(), client=None, samples=200, noise_mm=0.02, check_poses=200,
                         seed=4)
    med = float(np.median(r["rms_after_mm"]))
    return {"after.median": med, "predicted": float(r["predicted_model_std_mm"]),
            "ratio": med / float(r["predicted_model_std_mm"]), "unconverged": float(len(r["unconverged_samples"])),
            "samples": float(r["samples"])}


# ------------------------------------------------------------------------------------ thermal.md
@functools.lru_cache(maxsize=None)
def thermal_drift_identification() -> dict:
    """docs/thermal.md "2. Drift identification", measured on ``tests/test_thermal_core.py``'s cell
    (:mod:`robocal.sim.thermal.drift_setup`): the eight known deltas from 20 noise-free poses (seed 5):
    ``linear.max_error`` (the single linear solve's largest error, mm or rad), ``linear.rms_after_mm``,
    ``exact2.max_error`` (2 iterations); from 6 poses with 0.02 mm noise (seeds 100-109): the RMS error
    over the seeds per delta, ``noisy.lengths_mm.{min|max}`` and ``noisy.angles_deg.{min|max}``, the
    condition numbers ``noisy.condition.{min|max}``, the largest ``noisy.max_abs_z`` and the RMS of the
    reported sigmas of the angles ``noisy.angles_sigma_deg.{min|max}``. ~1 s."""
    import numpy as np

    from ..robots import load_robot
    from ..sim.thermal.drift_setup import (CENTRE_MM, DELTA, FOV_MM, P_E_MM, SUBSET, noisy_six_pose_fits, sensor_frame,
                                           warm_params)
    from ..thermal import design_sphere_poses, identify_drift, predict_sphere

    kuka = load_robot("kuka_kr150_r3100")
    rng = np.random.default_rng(5)
    T_sb = sensor_frame(rng)
    q = design_sphere_poses(kuka, CENTRE_MM, P_E_MM, 20, rng, spread_mm=FOV_MM, tilt_deg=60)
    Pw = predict_sphere(kuka, T_sb, P_E_MM, q, params=warm_params(kuka))
    lin = identify_drift(kuka, T_sb, P_E_MM, q, Pw, subset=SUBSET)
    exact = identify_drift(kuka, T_sb, P_E_MM, q, Pw, subset=SUBSET, iterations=2)
    out = {"linear.max_error": float(np.abs(lin.delta - DELTA).max()), "linear.rms_after_mm": float(lin.rms_after_mm),
           "exact2.max_error": float(np.abs(exact.delta - DELTA).max())}
    err, z, cond, sig = [], [], [], []
    for r in noisy_six_pose_fits(kuka):
        err.append(r.delta - DELTA)
        z.append((r.delta - DELTA) / r.std)
        sig.append(r.std)
        cond.append(float(r.condition_number))
    rms = np.sqrt(np.mean(np.square(err), axis=0))
    rms_sig = np.sqrt(np.mean(np.square(sig), axis=0))
    lengths, angles = rms[:5], np.degrees(rms[5:])
    out.update({"noisy.lengths_mm.min": float(lengths.min()), "noisy.lengths_mm.max": float(lengths.max()),
                "noisy.angles_deg.min": float(angles.min()), "noisy.angles_deg.max": float(angles.max()),
                "noisy.angles_sigma_deg.min": float(np.degrees(rms_sig[5:]).min()),
                "noisy.angles_sigma_deg.max": float(np.degrees(rms_sig[5:]).max()),
                "noisy.condition.min": min(cond), "noisy.condition.max": max(cond),
                "noisy.max_abs_z": float(np.abs(z).max())})
    return out


@functools.lru_cache(maxsize=None)
def thermal_compensation_steps() -> dict:
    """docs/thermal.md "3. Compensation" on ``tests/test_thermal_core.py``'s program (50 taught points,
    seed 7, the known warm deltas): ``drift_before_max_mm``; the position error [mm] left after one
    and two Newton steps (``{one_step|two_steps}.{median_mm|max_mm}``); with the defaults ``iterations_max``, ``all_converged``, and position
    only ``position_only.iterations_max``. ~0.1 s."""
    import numpy as np

    from ..robots import load_robot
    from ..sim.thermal.drift_setup import taught_program, warm_params
    from ..thermal import compensate_program

    kuka = load_robot("kuka_kr150_r3100")
    q = taught_program(kuka, 50, np.random.default_rng(7))
    Xw = warm_params(kuka)
    out = {}
    for k, name in ((1, "one_step"), (2, "two_steps")):
        e = compensate_program(kuka, Xw, q, max_iterations=k, tol_mm=0.0, tol_rad=0.0).position_error_mm
        out.update({f"{name}.median_mm": float(np.median(e)), f"{name}.max_mm": float(e.max())})
    full = compensate_program(kuka, Xw, q)
    po = compensate_program(kuka, Xw, q, position_only=True)
    return {**out, "drift_before_max_mm": float(full.drift_before_mm.max()),
            "iterations_max": float(full.iterations.max()), "all_converged": float(full.all_converged),
            "position_only.iterations_max": float(po.iterations.max())}


@functools.lru_cache(maxsize=None)
def thermal_orthonormality() -> dict:
    """docs/thermal.md "1. System calibration": the thesis-penalty method's raw rotation
    orthonormality error ``|R R^T - I|_F`` on the 20 seeds of the system-calibration set-up
    (:func:`robocal.docs.figure_producers_setups.system_calibration_seed`): ``median``, ``max``."""
    import numpy as np

    from .figure_producers_setups import system_calibration_seed

    e = [system_calibration_seed(seed).thesis.orthonormality_error for seed in range(20)]
    return {"median": float(np.median(e)), "max": float(np.max(e))}


@functools.lru_cache(maxsize=None)
def thermal_deformation_transfer() -> dict:
    """docs/thermal.md "What is outside the model, measured" (``tests/test_thermal_realism.py``'s set-up,
    :func:`robocal.sim.thermal.deformation_transfer.deformation_transfer`): the realistic cells 3, 4, 5
    at motor temperatures 9/25/22/16/7/5 K; the largest shares [%] of the bending outside the span at
    the monitored points (``bend.span.max``) and left by the fit on the sphere poses (``bend.transfer.max``);
    the sag's smallest in-span share at the car body (``sag.in_span.min`` = 100 - span) and its range
    left by the sphere fit (``sag.transfer.{min|max}``). ~1 s."""
    import numpy as np

    from ..sim.thermal.deformation_transfer import TRANSFER_MOTOR_TEMPERATURES_K, deformation_transfer
    from ..sim.thermal.simulator import ThermalCell

    rows = []
    for seed in (3, 4, 5):
        cell = ThermalCell.standard(seed, preset="realistic")
        rows.append(deformation_transfer(cell, TRANSFER_MOTOR_TEMPERATURES_K, "bend")
                    + deformation_transfer(cell, TRANSFER_MOTOR_TEMPERATURES_K, "sag"))
    bend_span, bend_transfer, _, sag_span, sag_transfer, _ = 100.0 * np.array(rows).T
    return {"bend.span.max": float(bend_span.max()), "bend.transfer.max": float(bend_transfer.max()),
            "sag.in_span.min": float(100.0 - sag_span.max()), "sag.transfer.min": float(sag_transfer.min()),
            "sag.transfer.max": float(sag_transfer.max())}


@functools.lru_cache(maxsize=None)
def thermal_selection_ranges() -> dict:
    """docs/thermal.md "Screening robustness", the prose under the table (producer ``thermal/realistic``,
    20 seeds with 20 bootstrap resamples each): the five most often screened parameters' smallest and
    largest share [%] over the seeds and the resamples (``five.{min|max}``), and the largest share of
    any other parameter (``others.max``)."""
    from .figure_producers import PRODUCERS

    r = PRODUCERS["thermal/realistic"]()
    five = ("a2", "theta3", "d4", "beta2", "alpha4")
    shares = {k.split(".", 1)[1]: [] for k in r if k.startswith(("selection.", "bootstrap."))}
    for k, v in r.items():
        if k.startswith(("selection.", "bootstrap.")):
            shares[k.split(".", 1)[1]].append(v)
    return {"five.min": min(min(shares[n]) for n in five), "five.max": max(max(shares[n]) for n in five),
            "others.max": max(max(v) for n, v in shares.items() if n not in five)}


# ------------------------------------------------------------------- self-calibration-simulator.md
@functools.lru_cache(maxsize=None)
def self_calibration_rendered(robot: str, seed: int) -> dict:
    """docs/self-calibration-simulator.md "Measured": ``simulate_self_calibration(ROBOT, seed=SEED,
    n_images_per_chain=40)`` (NAO: both hands; the KR 150: the world board; the other settings default)
    rendered into a temporary folder and detected (``detect_images``, as ``tests/test_self_calibration_sim.py``
    checks smaller runs): ``full.{detected|total}``, ``partial.{rejected|total}`` and the corner error
    of the used full views against the true projection, ``rms_px`` (RMS of the per-corner distance) and
    ``max_px``. ~25-45 s of CPU."""
    import numpy as np

    from ..io.detection import detect_images
    from ..io.images import list_images
    from ..sim.cameras.self_calibration import simulate_self_calibration

    chains = ("left_hand", "right_hand") if robot == "nao_h25" else ("world",)
    with tempfile.TemporaryDirectory() as tmp:
        r = simulate_self_calibration(robot, chains=chains, n_images_per_chain=40, seed=seed, out_dir=Path(tmp))
        dets = detect_images(list_images(Path(tmp) / "images"), r.board)
    full = np.asarray(r.fully_visible, bool)
    used = np.array([d.used for d in dets])
    err = np.concatenate([np.linalg.norm(d.image_points - p, axis=1)
                          for d, p, f in zip(dets, r.image_points_true, full) if f and d.used])
    return {"full.detected": float(np.sum(used & full)), "full.total": float(full.sum()),
            "partial.rejected": float(np.sum(~used & ~full)), "partial.total": float((~full).sum()),
            "rms_px": float(np.sqrt(np.mean(err ** 2))), "max_px": float(err.max())}


@functools.lru_cache(maxsize=None)
def self_calibration_rendered_range() -> dict:
    """The smallest and largest corner-error RMS [px] of the three runs of :func:`self_calibration_rendered`
    (``rms_px.{min|max}``): the prose under the table."""
    rms = [self_calibration_rendered(r, s)["rms_px"] for r, s in SELF_CALIBRATION_RUNS]
    return {"rms_px.min": min(rms), "rms_px.max": max(rms)}


#: the runs of docs/self-calibration-simulator.md's table: (robot, seed)
SELF_CALIBRATION_RUNS = (("nao_h25", 1), ("nao_h25", 7), ("kuka_kr150_r3100", 3))


@functools.lru_cache(maxsize=None)
def bent_board_gap() -> dict:
    """docs/self-calibration-simulator.md, the bent-board row (``tests/test_self_calibration_sim.py::
    test_bent_board_images_follow_the_bent_corners``' call): ``simulate_self_calibration("nao_h25",
    chains=("left_hand",), n_images_per_chain=2, partial_fraction=0, board_bow_mm=0.4, seed=4)``; per
    view the largest distance [px] of the bent board's true corners from a flat board's projection in
    the same pose: ``gap_px.{min|max}`` over the views. ~0.1 s."""
    import numpy as np

    from ..sim.cameras.self_calibration import simulate_self_calibration

    r = simulate_self_calibration("nao_h25", chains=("left_hand",), n_images_per_chain=2, partial_fraction=0.0,
                                  board_bow_mm=0.4, seed=4)
    X = r.board.object_points()
    gaps = [float(np.max(np.linalg.norm(r.camera.project((T[:3, :3] @ X.T).T + T[:3, 3]).pixels - p, axis=1)))
            for p, T in zip(r.image_points_true, r.T_camera_board)]
    return {"gap_px.min": min(gaps), "gap_px.max": max(gaps)}


# ----------------------------------------------------------------------------------- datasets.md
@functools.lru_cache(maxsize=None)
def positioner_reference_fit() -> dict:
    """docs/datasets.md "ros_industrial_positioner": the independent screw-axis fit
    (:func:`robocal.workflows.datasets.positioner_reference.reference_axes`, no robocal code) on the 150 training
    records of seed 0 (``calibrate_positioner(seed=0, n_train=150)``'s split, as
    ``tests/test_positioner_real_data.py``), with the target origin alone: ``origin.angle_deg``,
    ``origin.common_normal_mm`` and their sigmas ``origin.{angle|common_normal}_sigma``. ~3 s."""
    import numpy as np

    from ..io.datasets import read_ros_industrial_positioner
    from ..workflows.datasets.ros_industrial_positioner import calibrate_positioner
    from ..workflows.datasets.positioner_reference import reference_axes

    ds = read_ros_industrial_positioner()
    run = calibrate_positioner(seed=0, n_train=150, data=ds)
    train = np.asarray(run["train"])
    (angle, normal), (s_angle, s_normal), _ = reference_axes(ds.per_pose["T_camera_target"][train], ds.joints[train],
                                                             n_points=1)
    return {"origin.angle_deg": float(angle), "origin.common_normal_mm": float(normal),
            "origin.angle_sigma": float(s_angle), "origin.common_normal_sigma": float(s_normal)}


# ------------------------------------------------------------------------------------ handeye.md
def rendered_board_views(spec: str, n_images: int = 3, seed: int = 3, noise_seed: int = 11) -> tuple:
    """Rendered views of a board with known truth (``tests/test_camera_detection.py``'s set-up and
    docs/handeye.md's detection figures): the default camera, ``n_images`` hand-eye poses (``seed``),
    the board's texture rendered with the renderer's blur, lighting and noise (``noise_seed``).

    Returns
    -------
    (Board, Camera, truth, list of images, BoardRenderer)
        ``truth.T_camera_target`` (n_images, 4, 4) [mm]; images (H, W) uint8.
    """
    import numpy as np

    from ..io.boards import board_image, parse_board
    from ..sim.cameras.camera_cell import default_camera, simulate_hand_eye_poses
    from ..sim.cameras.camera_render import BoardRenderer
    from ..workflows.cameras.camera_simulate import _texel_mm

    board = parse_board(spec)
    cam = default_camera()
    truth = simulate_hand_eye_poses(board.object_points(), n_images=n_images, camera=cam, front_z=board.front_z,
                                    seed=seed)
    texture, affine = board_image(board, _texel_mm(board))
    renderer = BoardRenderer(cam, texture, affine)
    rng = np.random.default_rng(noise_seed)
    return board, cam, truth, [renderer.render(T, rng) for T in truth.T_camera_target], renderer


@functools.lru_cache(maxsize=None)
def checkerboard_classic_vs_sb() -> dict:
    """docs/handeye.md "Side by side with OpenCV", the corner finder: the three rendered 9 x 6
    checkerboard views of :func:`rendered_board_views`; the corner RMS [px] against the exact
    projections of robocal's classic path (``findChessboardCorners`` + ``cornerSubPix``, ``classic``)
    and of ``findChessboardCornersSB`` with ``NORMALIZE_IMAGE`` with and without ``ACCURACY``
    (``sb.{min|max}``; its corner order taken as the one closer to the truth). ~1 s."""
    import cv2
    import numpy as np

    from ..io.detection import detect_board

    board, cam, truth, images, _ = rendered_board_views("checkerboard:9x6:30mm")
    obj = board.object_points()
    classic, sb = [], {"accuracy": [], "plain": []}
    for im, T in zip(images, truth.T_camera_target):
        tp = cam.project((T[:3, :3] @ obj.T).T + T[:3, 3]).pixels
        classic.append(np.linalg.norm(detect_board(im, board).image_points - tp, axis=1))
        for k, flags in (("accuracy", cv2.CALIB_CB_NORMALIZE_IMAGE | cv2.CALIB_CB_ACCURACY),
                         ("plain", cv2.CALIB_CB_NORMALIZE_IMAGE)):
            _, corners = cv2.findChessboardCornersSB(im, (board.cols, board.rows), flags=flags)
            c = corners.reshape(-1, 2).astype(float)
            c = min((c, c[::-1]), key=lambda x: float(np.linalg.norm(x - tp)))
            sb[k].append(np.linalg.norm(c - tp, axis=1))

    def rms(e):
        return float(np.sqrt(np.mean(np.concatenate(e) ** 2)))

    return {"classic": rms(classic), "sb.min": min(rms(v) for v in sb.values()), "sb.max": max(rms(v) for v in sb.values())}


# -------------------------------------------------------------------------------- robot-files.md
#: a Rokae-style 6-axis arm in Craig's modified DH as its vendor tables write it (J2 || J3; illustrative
#: dimensions of a 7 kg arm): name, alpha [deg], a [mm], theta [deg], d [mm], limits [deg]
ROKAE_STYLE_MDH = [("J1", 0.0, 0.0, 0.0, 380.0, 170), ("J2", -90.0, 30.0, -90.0, 0.0, 130),
                   ("J3", 0.0, 340.0, 0.0, 0.0, 150), ("J4", -90.0, 35.0, 0.0, 345.0, 170),
                   ("J5", 90.0, 0.0, 0.0, 0.0, 115), ("J6", -90.0, 0.0, 0.0, 80.0, 350)]


def rokae_style_robot_file(path, with_beta: bool) -> Path:
    """Write :data:`ROKAE_STYLE_MDH` as a robot file at ``path``, with ``beta = 0.0`` lines on every
    joint or without any."""
    lines = ['format = "robocal-robot/1"', 'name = "rokae_style"', 'model = "mdh"', 'length_unit = "mm"',
             'angle_unit = "deg"', 'source = "test: Rokae-style MDH table, illustrative dimensions"']
    for name, alpha, a, theta, d, lim in ROKAE_STYLE_MDH:
        lines += ["", "[[joints]]", f'name = "{name}"', f"alpha = {alpha}", f"a = {a}"]
        lines += ["beta = 0.0"] if with_beta else []
        lines += [f"theta = {theta}", f"d = {d}", f"limits = [{-lim}.0, {lim}.0]"]
    Path(path).write_text("\n".join(lines) + "\n", encoding="utf-8")
    return Path(path)


def parallel_beta_campaign(folder) -> dict:
    """docs/robot-files.md's parallel-axis measurement and ``tests/test_parallel_beta.py``'s campaign:
    the Rokae-style arm with hidden errors (seed 7: 0.2 mm lengths, 0.03 deg offsets) and its J3 axis
    really tilted (beta3 = 0.05 deg), 80 poses measured at the flange with 0.01 mm noise; ``robocal
    calibrate`` (``--sigma 0.01 --fix a6,theta6,d6``) of the file without ``beta`` lines (``plain``),
    with them (``declared``) and with ``beta3`` held (``no_beta``). Returns ``{key: (stdout, result.json)}``."""
    import math

    import numpy as np

    from ..io.measurements import Measurements, write_measurements
    from ..robots import load_robot
    from ..sim import VirtualRobot
    from .figure_producers_cli import run_cli as run

    d = Path(folder)
    plain = rokae_style_robot_file(d / "rokae_plain.toml", with_beta=False)
    declared = rokae_style_robot_file(d / "rokae_beta.toml", with_beta=True)
    nominal = load_robot(declared)
    rng = np.random.default_rng(7)
    virtual = VirtualRobot.perturbed(nominal, rng, angle_sigma_deg=0.0, length_sigma_mm=0.2,
                                     offset_sigma_deg=0.03, joint_noise_deg=0.0)
    true = virtual.true_model.with_params(beta3=math.radians(0.05))
    virtual = VirtualRobot(nominal, true)
    q = virtual.random_configurations(80, rng)
    p = virtual.true_poses(q)[:, :3, 3] + rng.normal(0, 0.01, (80, 3))
    data = write_measurements(d / "m.csv", Measurements(q, p, joint_names=nominal.controller_joints,
                                                        metadata={"robot": "rokae_style"}),
                              length_unit="mm", angle_unit="deg")
    out = {}
    # the target sits at the flange origin: the last link's a6, theta6, d6 trade off with it
    for key, robot, fix in (("plain", plain, "a6,theta6,d6"), ("declared", declared, "a6,theta6,d6"),
                            ("no_beta", plain, "a6,theta6,d6,beta3")):
        text = run("calibrate", robot, data, "--out", d / key, "--sigma", 0.01, "--no-report", "--fix", fix,
                   ok=(0,) if key != "no_beta" else (0, 3, 4))
        out[key] = (text, json.loads((d / key / "result.json").read_text()))
    return out


@functools.lru_cache(maxsize=None)
def parallel_beta_holdout() -> dict:
    """The held-out RMS [mm] of :func:`parallel_beta_campaign`'s three calibrations
    (``{plain|declared|no_beta}.holdout_rms_mm``) and ``no_beta_over_plain``. ~2 s."""
    with tempfile.TemporaryDirectory() as tmp:
        c = parallel_beta_campaign(tmp)
    out = {f"{k}.holdout_rms_mm": float(v[1]["validation"]["after"]["rms"]) for k, v in c.items()}
    out["no_beta_over_plain"] = out["no_beta.holdout_rms_mm"] / out["plain.holdout_rms_mm"]
    return out


# ---------------------------------------------------------------------------- self-calibration.md
@functools.lru_cache(maxsize=None)
def nao_rendered_pipeline() -> dict:
    """docs/self-calibration.md "End to end on rendered NAO images" (the run of
    ``benchmarks/bench_self_calibration.py --nao``): ``simulate_self_calibration("nao_h25",
    n_images_per_chain=40, seed=0)`` rendered to a temporary folder, then the whole pipeline
    ``self_calibrate(..., board_on=left_hand,right_hand, joint_noise_deg=0.05)``. Fields ``n_images``,
    ``n_used``, ``n_misassigned`` (used images put on the other hand), ``n_identifiable``,
    ``max_abs_z`` and ``max_error_deg`` of the identifiable offsets against the simulator's truth,
    ``sigma_deg.{min|max}``, ``rms_px`` (back-projection with the joints as read). ~40-60 s."""
    import numpy as np

    from ..sim.cameras.self_calibration import simulate_self_calibration
    from ..workflows.cameras.self_calibration import self_calibrate

    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        run = simulate_self_calibration("nao_h25", n_images_per_chain=40, seed=0, out_dir=root)
        s = self_calibrate("nao_h25", images=root / "images", joints=root / "joint_log.csv", frames=root / "frames.csv",
                           board=run.board.spec, camera_end_effector="camera_top", board_on=["left_hand", "right_hand"],
                           camera_file=root / "camera.json", joint_noise_deg=0.05)
    chain = dict(zip(run.images, run.chain_of_image))
    used = [im for im in s["images"] if im["used"]]
    off = {o["name"]: o for o in s["joint_offsets"]}
    err, z, sig = [], [], []
    for r in s["joint_report"]:
        if r["identifiable"]:
            o = off[r["name"]]
            e = o["value"] - run.joint_offsets_rad[r["joint"]]
            err.append(abs(e))
            z.append(abs(e) / o["sigma"])
            sig.append(o["sigma"])
    return {"n_images": float(s["n_images"]), "n_used": float(len(used)),
            "n_misassigned": float(sum(im["board_on"] != chain[im["name"]] for im in used)),
            "n_identifiable": float(len(z)), "max_abs_z": float(max(z)), "max_error_deg": float(np.degrees(max(err))),
            "sigma_deg.min": float(np.degrees(min(sig))), "sigma_deg.max": float(np.degrees(max(sig))),
            "rms_px": float(s["reprojection_rms_px"])}


#: the board and the views per arm of :func:`justin_head_capture`
JUSTIN_CAPTURE_BOARD = "checkerboard:7x4:25mm"
JUSTIN_CAPTURE_PER_ARM = 4


def justin_head_capture(root) -> tuple:
    """Rendered head-camera images of a board in each hand of the DLR Justin tree with three joint
    offsets (theta23 +1.5, theta15 -2.0, theta7 +1.0 deg), 4 views per arm (seed 7), a joint log on
    another clock and a frames file in ``root`` (``tests/test_self_calibration_pipeline.py``'s
    capture and docs/self-calibration.md's figures). Returns ``(root, offsets [rad], image names,
    image times, log times, logged joints)``."""
    import numpy as np

    from ..camera import Camera
    from ..io.boards import board_image, parse_board
    from ..io.camera_files import write_camera_json
    from ..io.images import write_png
    from ..io.joint_log_files import write_frames, write_joint_log
    from ..robots import load_robot
    from ..sim.cameras.camera_render import BoardRenderer
    from ..sim.cameras.self_calibration import capture_schedule
    from ..sim.cameras.self_calibration_views import ViewLimits, camera_board_poses, visible_configurations
    from ..transforms import so3_exp, transforms_from

    cam = Camera(800.0, 800.0, 319.5, 239.5, (-0.1, 0.05, 0.0, 0.0, 0.0), "brown", (640, 480))
    boards = {"left": transforms_from(so3_exp(np.array([0.1, -0.2, 0.3])), np.array([10.0, 20.0, 120.0])),
              "right": transforms_from(so3_exp(np.array([-0.2, 0.1, 2.0])), np.array([-15.0, 5.0, 110.0]))}
    mount = transforms_from(so3_exp(np.array([0.01, -0.02, 0.015])), np.array([3.0, -2.0, 5.0]))
    n_per_arm = JUSTIN_CAPTURE_PER_ARM
    root = Path(root)
    m = load_robot("dlr_justin19")
    rng = np.random.default_rng(7)
    offsets = {"theta23": np.radians(1.5), "theta15": np.radians(-2.0), "theta7": np.radians(1.0)}
    truth = m.params.values.copy()
    for n, v in offsets.items():
        truth[m.params.names.index(n)] += v
    true_model = m.with_params(truth)
    board = parse_board(JUSTIN_CAPTURE_BOARD)
    X = board.object_points()
    texture, affine = board_image(board, 1.0)
    renderer = BoardRenderer(cam, texture, affine)
    q, T = [], []
    for c in ("left", "right"):
        qc = visible_configurations(true_model, cam, X, camera_end_effector="head", T_ee_camera=mount, carrier=c,
                                    T_carrier_board=boards[c], n=n_per_arm, rng=rng, q_center=np.zeros(19),
                                    q_spread=np.pi, front_z=board.front_z, pitch_mm=board.pitch_mm,
                                    limits=ViewLimits(margin_px=30.0, depth_mm=(50.0, np.inf), max_tilt_deg=55.0))
        q.append(qc)
        T.append(camera_board_poses(true_model, qc, "head", mount, c, boards[c]))
    q, T = np.concatenate(q), np.concatenate(T)
    images = root / "images"
    images.mkdir(parents=True)
    names = [f"frame_{i:03d}.png" for i in range(len(q))]
    for n, Ti in zip(names, T):
        write_png(images / n, renderer.render(Ti, rng))
    t_img, t_log, pose = capture_schedule(len(q), rng)
    q_log = np.where(pose[:, None] >= 0, q[np.clip(pose, 0, None)], 0.0)
    write_joint_log(root / "joints.csv", t_log, q_log, m.controller_joints)
    write_frames(root / "frames.csv", names, t_img)
    write_camera_json(root / "camera.json", cam)
    return root, offsets, names, t_img, t_log, q_log


@functools.lru_cache(maxsize=None)
def justin_reading_noise() -> dict:
    """docs/self-calibration.md "the joint-reading noise by default" (``tests/test_self_calibration_pipeline.py::
    test_joint_reading_noise_is_estimated_by_default``): :func:`justin_head_capture` with 0.05 deg
    reading noise added to the log (seed 5); the pipeline (``self_calibrate``) by default, which
    first solves with the readings taken as exact and then estimates the noise
    (``estimate_joint_noise``; the exact solve is recorded on the way): ``exact.variance_factor``,
    ``exact.max_abs_z`` (the three offsets' largest |error| / sigma), ``default.max_abs_z``,
    ``default.joint_noise_deg``. ~5 s."""
    from unittest import mock

    import numpy as np

    from ..io.joint_log_files import write_frames, write_joint_log
    from ..robots import load_robot
    from ..workflows.cameras import self_calibration as workflow

    seen = {}

    def recording(solve_with):
        seen["exact"] = solve_with(None)
        return estimate(solve_with)

    estimate = workflow.estimate_joint_noise
    with tempfile.TemporaryDirectory() as tmp:
        root, offsets, names, t_img, t_log, q_log = justin_head_capture(Path(tmp) / "capture")
        alt = Path(tmp) / "noisy"
        alt.mkdir()
        write_frames(alt / "frames.csv", names, t_img)
        noisy = q_log + np.radians(0.05) * np.random.default_rng(5).normal(size=q_log.shape)
        write_joint_log(alt / "joints.csv", t_log, noisy, load_robot("dlr_justin19").controller_joints)
        with mock.patch.object(workflow, "estimate_joint_noise", recording):
            s = workflow.self_calibrate("dlr_justin19", images=root / "images", joints=alt / "joints.csv",
                                        frames=alt / "frames.csv", board=JUSTIN_CAPTURE_BOARD, camera_end_effector="head",
                                        board_on=["left", "right"], camera_file=root / "camera.json")
    ex = seen["exact"]
    got = {n: (v, sg) for n, v, sg in zip(ex.joint_offset_names, ex.joint_offsets, ex.joint_offset_sigma)}
    out = {"exact.variance_factor": float(ex.variance_factor),
           "exact.max_abs_z": float(max(abs(got[n][0] - v) / got[n][1] for n, v in offsets.items()))}
    got = {j["name"]: j for j in s["joint_offsets"]}
    out["default.max_abs_z"] = float(max(abs(got[n]["value"] - v) / got[n]["sigma"] for n, v in offsets.items()))
    out["default.joint_noise_deg"] = float(s["joint_noise_deg"] or 0.0)
    return out


PAGES_PRODUCERS = {
    "iso9283/adequacy": iso9283_adequacy,
    "iso9283/verify_backlash_trials": verify_backlash_trials,
    "iso9283/verify_backlash_command": verify_backlash_command,
    "iso9283/wear_per_day": iso9283_wear_per_day,
    "reliability/lm_stop_linear": lm_stop_linear,
    "reliability/camera_gate": camera_gate_stretched,
    "reliability/touchup_one_pose_off": touchup_one_pose_off,
    "robots/file_checks": robot_file_checks,
    "robots/boby_nominal_all_poses": boby_nominal_all_poses,
    "robots/hilti_flat_rigid": hilti_flat_rigid_per_station,
    "fleet/monte_carlo": fleet_monte_carlo,
    "thermal_core/identification": thermal_drift_identification,
    "thermal_core/compensation": thermal_compensation_steps,
    "thermal_core/orthonormality": thermal_orthonormality,
    "thermal_core/deformation_transfer": thermal_deformation_transfer,
    "thermal/selection_ranges": thermal_selection_ranges,
    **{f"self_calibration_sim/{r}/{k}": functools.partial(self_calibration_rendered, r, k) for r, k in SELF_CALIBRATION_RUNS},
    "self_calibration_sim/rendered_range": self_calibration_rendered_range,
    "self_calibration_sim/bent_board": bent_board_gap,
    "datasets/positioner_reference": positioner_reference_fit,
    "handeye/classic_vs_sb": checkerboard_classic_vs_sb,
    "robot_files/parallel_beta": parallel_beta_holdout,
    "self_calibration/nao_rendered": nao_rendered_pipeline,
    "self_calibration/justin_reading_noise": justin_reading_noise,
}

#: the data sets (folders under ``robocal.io.datasets.datasets_root()``) a producer of this module reads
PAGES_DATASETS_NEEDED = {"robots/boby_nominal_all_poses": ("boby_fanuc",), "robots/hilti_flat_rigid": ("hilti_trailblazer",),
                         "datasets/positioner_reference": ("ros_industrial_handeye",)}

#: longer than ~5 s of CPU: run with ``--all`` / ``ROBOCAL_SLOW=1``
SLOW_PAGES_PRODUCERS = {"iso9283/verify_backlash_trials", "reliability/camera_gate", "fleet/monte_carlo",
                        "thermal/selection_ranges", "self_calibration_sim/rendered_range", "self_calibration/nao_rendered",
                        "self_calibration/justin_reading_noise",
                        *(f"self_calibration_sim/{r}/{k}" for r, k in SELF_CALIBRATION_RUNS)}
