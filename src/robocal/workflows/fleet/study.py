"""``robocal fleet study ...``: the embarrassingly parallel studies, as chunked Dask tasks.

* :func:`monte_carlo_plan`: Monte-Carlo uncertainty of a pose plan. Each sample is a virtual
  robot with its own hidden true parameters (:meth:`robocal.sim.VirtualRobot.perturbed`) measured
  at the planned poses by a tracker with Gaussian noise, calibrated (the calibration core:
  :class:`~robocal.calib.problem.CalibrationProblem`, :func:`~robocal.calib.solve`), and checked
  against its truth at other poses: the distribution of the accuracy the plan delivers, beside
  the first-order prediction of :func:`robocal.calib.plan.plan_campaign`.
* :func:`pose_set_selection`: many candidate sets (one per seed, drawn exactly as ``robocal
  plan-poses --seed S`` draws them), each planned by D-optimal selection and ranked by its
  predicted workspace accuracy (noise-free); the best seed is reported (``robocal plan-poses --seed
  <best>`` writes that plan), and whether the differences are within one campaign's noise.
* :func:`thermal_screening`: ``robocal thermal screen`` on each robot's run folder, one task per
  robot.

Samples are seeded independently (``numpy.random.SeedSequence(seed).spawn(n)``; set ``i`` uses seed
``seed + i``), so a result does not depend on the chunking, the number of workers or the order
tasks finish in: the Dask run equals the serial loop bit for bit. Chunks are sized by
:mod:`robocal.workflows.fleet.chunks` from the measured time of one item and of one empty task.
"""

from __future__ import annotations

import time
import warnings

import numpy as np

from ...calib import solve
from ...calib.cell import default_cell, sample_feasible
from ...calib.solve import NotConvergedWarning
from ...calib.plan import predicted_model_std, predicted_workspace_accuracy
from ...calib.problem import CalibrationProblem, Target
from ...metrics import error_statistics
from ...robots import load_robot
from ...sim.robot import VirtualRobot
from .chunks import MAX_OVERHEAD_SHARE, chunk_size, chunks, measure_task_overhead, overhead_share
from .cluster import run_tasks, default_workers
from ..calibration.plan_poses import plan_cell, plan_in_cell

__all__ = ["monte_carlo_plan", "pose_set_selection", "thermal_screening", "mc_samples", "pose_sets"]


# -- Monte-Carlo uncertainty of a plan -------------------------------------------------------------

def _mc_one(nominal, q_plan, q_check, tool, noise_mm, spread, seed_seq):
    """(RMS before, RMS after [mm] at ``q_check``, converged) of one virtual robot calibrated from ``q_plan``."""
    rng = np.random.default_rng(seed_seq)
    virtual = VirtualRobot.perturbed(nominal, rng, length_sigma_mm=spread[0], angle_sigma_deg=spread[1],
                                     offset_sigma_deg=spread[2], joint_noise_deg=0.0, joint_noise_mm=0.0)
    tool = np.asarray(tool, dtype=float)

    def points(model, q):  # (N, 3) reflector in the instrument (= nominal base) frame
        T = model.fk(q)
        return T[:, :3, 3] + T[:, :3, :3] @ tool

    measured = points(virtual.true_model, q_plan) + rng.normal(0.0, noise_mm, (len(q_plan), 3))
    problem = CalibrationProblem(nominal, q_plan, [Target("reflector", point=tuple(tool))], measured[:, None, :],
                                 base_initial=nominal.T_world_base, point_sigma_mm=noise_mm)
    with warnings.catch_warnings():  # reported per sample instead (the third value)
        warnings.simplefilter("ignore", NotConvergedWarning)
        result = solve(problem)
    truth = points(virtual.true_model, q_check)
    after = problem.predict_points(result.state, q=q_check)[:, 0] - truth
    before = points(nominal, q_check) - truth
    return (float(np.sqrt(np.mean(np.sum(before**2, axis=1)))), float(np.sqrt(np.mean(np.sum(after**2, axis=1)))),
            bool(result.converged))


def mc_samples(span, *, robot, q_plan, q_check, tool, noise_mm, spread, seed, n_samples) -> list:
    """The Monte-Carlo samples ``span = (start, stop)`` (one task): [(before, after, converged), ...]."""
    nominal = load_robot(robot).replace(T_world_base=np.eye(4))
    seqs = np.random.SeedSequence(seed).spawn(n_samples)[span[0]:span[1]]
    return [_mc_one(nominal, q_plan, q_check, tool, noise_mm, spread, s) for s in seqs]


# -- pose selection over candidate sets -------------------------------------------------------------

#: Reference poses of the workspace accuracy a pose set is ranked by (seeded, the same for every set).
WORKSPACE_POSES = 200


def workspace_poses(model, tool, seed: int = 0) -> np.ndarray:
    """The reference poses (R, n) of :func:`pose_set_selection`: poses a floor-mounted robot can take,
    spread over its joint limits (seeded by ``seed`` alone: every candidate set is judged on them)."""
    q, _ = sample_feasible(default_cell(tool), model, WORKSPACE_POSES, np.random.default_rng([seed, 2]))
    return q


def _plan_one(model, count, candidates, seed, tool, sigma_mm, tracker_at, workspace, q_ref):
    cell = plan_cell(model, None, tracker_at, tool)
    plan = plan_in_cell(model, cell, count=count, candidates=candidates, workspace=workspace, sigma_mm=sigma_mm,
                        seed=seed, efficiency=False)
    acc = predicted_workspace_accuracy(model, plan, q_ref, tool=tuple(cell.reflector_mm))
    return {"seed": int(seed), "workspace_model_std_mm": acc["rms_mm"], "relative_spread": acc["relative_spread"],
            "holdout_rms_mm": plan["holdout_rms_mm"],
            "holdout_model_std_mm": plan["holdout_model_std_mm"], "n_candidates": int(plan["n_candidates"]),
            "n_identifiable": len(plan["identifiable"])}


def pose_sets(span, *, robot, count, candidates, seed, tool, sigma_mm, tracker_at=None, workspace=None) -> list:
    """The candidate sets ``seed + span[0] .. seed + span[1] - 1`` (one task), each planned."""
    model = load_robot(robot)
    q_ref = workspace_poses(model, tool, seed)
    return [_plan_one(model, count, candidates, seed + i, tool, sigma_mm, tracker_at, workspace, q_ref)
            for i in range(*span)]


# -- running a chunked study -----------------------------------------------------------------------

def _chunked(client, fn, n, kwargs, workers, progress, item_s=None):
    """Run ``fn(span, **kwargs)`` over ``range(n)`` in chunks (items 0 and 1 first, in this process:
    the first warms the caches, the second is timed); returns (items, chunking report)."""
    first = fn((0, 1), **kwargs)
    t0 = time.perf_counter()
    first += fn((1, 2), **kwargs)
    item_s = time.perf_counter() - t0 if item_s is None else item_s
    overhead = measure_task_overhead(client) if client is not None else 0.0
    k = chunk_size(n - 2, item_s, overhead, workers)
    spans = [(a + 2, b + 2) for a, b in chunks(n - 2, k)]
    t1 = time.perf_counter()
    parts = run_tasks(client, fn, spans, progress=progress, **kwargs)
    wall = time.perf_counter() - t1
    items = list(first) + [x for part in parts for x in part]
    report = {"items": n, "chunk_size": k, "tasks": len(spans), "workers": workers, "item_seconds": item_s,
              "task_overhead_seconds": overhead, "overhead_share": overhead_share(overhead, item_s, k) if spans else 0.0,
              "max_overhead_share": MAX_OVERHEAD_SHARE, "wall_seconds": wall}
    return items, report


def _workers(client) -> int:
    if client is None:
        return 1
    return sum(w.get("nthreads", 1) for w in client.scheduler_info()["workers"].values()) or default_workers()


def monte_carlo_plan(robot, q_plan, *, samples: int = 200, noise_mm: float = 0.02, check_poses: int = 200,
                     tool=(0.0, 0.0, 100.0), spread=(0.5, 0.05, 0.05), seed: int = 0, client=None,
                     progress=None) -> dict:
    """Monte-Carlo accuracy of calibrating ``robot`` from the poses ``q_plan`` (N, n) [rad | mm].

    samples: virtual robots; noise_mm: tracker noise per coordinate; check_poses: seeded random
    poses the robot can take on its floor (docs/cells.md) where each calibrated model is compared with its truth; tool: reflector in the flange
    frame [mm]; spread: (length sigma [mm], angle sigma [deg], joint offset sigma [deg]) of the
    hidden true parameters. Returns the per-sample RMS before/after [mm], their statistics, the
    samples whose solve stopped at the iteration limit (``unconverged_samples``, reported, kept),
    the first-order prediction and the chunking report.
    """
    if samples < 2:
        raise ValueError(f"--samples must be at least 2, got {samples}")
    if not noise_mm > 0:
        raise ValueError(f"--noise must be a positive number of mm, got {noise_mm}")
    model = load_robot(robot)
    q_plan = np.asarray(q_plan, dtype=float)
    q_check, _ = sample_feasible(default_cell(tool), model, check_poses, np.random.default_rng([seed, 1]))
    kwargs = {"robot": robot, "q_plan": q_plan, "q_check": q_check, "tool": tuple(tool), "noise_mm": noise_mm,
              "spread": tuple(spread), "seed": seed, "n_samples": samples}
    items, report = _chunked(client, mc_samples, samples, kwargs, _workers(client), progress)
    before = np.array([it[0] for it in items])
    after = np.array([it[1] for it in items])
    unconverged = [i for i, it in enumerate(items) if not it[2]]
    predicted = predicted_model_std(model, q_plan, q_check, tool=tool, sigma_mm=noise_mm)
    return {"robot": model.name, "n_poses": int(len(q_plan)), "samples": samples, "noise_mm": noise_mm,
            "seed": seed, "rms_before_mm": before.tolist(), "rms_after_mm": after.tolist(),
            "before": error_statistics(before), "after": error_statistics(after),
            "unconverged_samples": unconverged, "predicted_model_std_mm": predicted, "chunking": report}


def pose_set_selection(robot, *, sets: int = 100, count: int = 40, candidates: int = 800, sigma_mm: float = 0.02,
                       tool=(0.0, 0.0, 100.0), tracker_at=None, workspace=None, seed: int = 0, client=None,
                       progress=None) -> dict:
    """``sets`` candidate sets of ``robot`` (seeds ``seed .. seed + sets - 1``), each planned as
    ``robocal plan-poses`` plans it, ranked by the predicted workspace accuracy (a noise-free
    criterion: the first-order model error over :func:`workspace_poses`, without the instrument noise
    a held-out RMS adds). ``within_noise``: the sets whose accuracy is within one real campaign's
    spread (``relative_spread`` of the best) of the best -- the choice among them is noise."""
    if sets < 2:
        raise ValueError(f"--sets must be at least 2, got {sets}")
    kwargs = {"robot": robot, "count": count, "candidates": candidates, "seed": seed, "tool": tuple(tool),
              "sigma_mm": sigma_mm, "tracker_at": tracker_at, "workspace": workspace}
    items, report = _chunked(client, pose_sets, sets, kwargs, _workers(client), progress)
    acc = np.array([it["workspace_model_std_mm"] for it in items])
    best = items[int(np.argmin(acc))]
    band = best["workspace_model_std_mm"] * (1.0 + best["relative_spread"])
    within = [it["seed"] for it in items if it["workspace_model_std_mm"] <= band]
    return {"robot": load_robot(robot).name, "sets": items, "best": best, "criterion": "workspace_model_std_mm",
            "spread_mm": {"min": float(acc.min()), "median": float(np.median(acc)), "max": float(acc.max())},
            "noise_band_mm": float(band), "within_noise": within,
            "differences_within_noise": bool(np.median(acc) <= band), "chunking": report}


# -- thermal screening per robot -------------------------------------------------------------------

def _screen(run, **kwargs) -> dict:
    from ..thermal.commands import screen_run

    robot_id, run_dir = run
    try:
        r = screen_run(run_dir, **kwargs)
    except Exception as exc:  # one robot's bad run folder never stops the others
        return {"id": robot_id, "status": "failed", "reason": str(exc)}
    return {"id": robot_id, "status": "ok", "run_dir": str(run_dir), "robot": r["robot"], "selected": r["selected"],
            "traditional": r["traditional"], "lambda_percent": r["lambda_percent"]}


def thermal_screening(runs, *, n_keep: int = 8, client=None, progress=None) -> dict:
    """``robocal thermal screen`` on every ``(robot id, run folder)`` of ``runs``, one task per robot
    (a screening takes seconds: far above the task overhead)."""
    rows = run_tasks(client, _screen, list(runs), progress=progress, n_keep=n_keep)
    return {"robots": rows, "ok": sum(r["status"] == "ok" for r in rows), "failed": sum(r["status"] != "ok" for r in rows)}
