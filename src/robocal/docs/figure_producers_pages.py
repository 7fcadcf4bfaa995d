"""Producers of the documented figures of docs/iso9283.md, docs/reliability.md, docs/robots.md,
docs/fleet.md, docs/thermal.md and the smaller pages that no other producer computes
(:mod:`robocal.docs.figures`). Each runs the page's commands or the test's own set-up (shared with
the test through ``robocal.sim``) and returns a flat ``{field: value}`` dict; cached."""

from __future__ import annotations

import functools
import json
import tempfile
from pathlib import Path

__all__ = ["PAGES_DATASETS_NEEDED", "PAGES_PRODUCERS", "SLOW_PAGES_PRODUCERS", "iso9283_simulated_run"]


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
}

#: the data sets (folders under ``robocal.io.datasets.datasets_root()``) a producer of this module reads
PAGES_DATASETS_NEEDED = {"robots/boby_nominal_all_poses": ("boby_fanuc",), "robots/hilti_flat_rigid": ("hilti_trailblazer",)}

#: longer than ~5 s of CPU: run with ``--all`` / ``ROBOCAL_SLOW=1``
SLOW_PAGES_PRODUCERS = {"iso9283/verify_backlash_trials", "reliability/camera_gate", "fleet/monte_carlo"}
