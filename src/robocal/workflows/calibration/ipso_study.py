"""The IPSO paper's simulation (ER10L-C10) and the tracker simulation, each calibrated by LM,
IPSO and IPSO+LM: holdout errors, parameter recovery, time, noise floor (issue 13).

``python -m robocal.workflows.calibration.ipso_study [--seeds 20]`` prints the tables of docs/calibration.md
("IPSO against LM"). The tests use the same functions with few seeds.

Paper experiment (:func:`er10l_experiment`): ``er10l_c10`` (24 parameters, stand-in geometry);
true parameters = nominal + uniform errors in ±0.01 rad / ±0.05 mm; 32 commanded configurations
uniform in [-pi, pi]; the robot really moves to the commanded joints plus uniform noise in
±0.1 (``joint_unit`` "rad" as printed, or "deg"); the full flange pose is measured exactly at the
real joints (base and tool known). Objective (7) with k = 1000^2 mm^2/rad^2 (rotation weight
1000 mm/rad: 1 mrad counts as 1 mm). Holdout: 200 more configurations drawn the same way.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from ...calib import Problem, solve
from ...calib.blocks import RobotGeometry, StationFrames, ToolFrame
from ...calib.residuals import ToolPointResidual, ToolRotationResidual, tool_chain
from ...calib.swarm import solve_swarm
from ...robots import load_robot

__all__ = ["Experiment", "er10l_experiment", "run_method", "ROTATION_WEIGHT"]

ROTATION_WEIGHT = 1000.0  # mm per rad: k = 1e6 mm^2 / rad^2 in objective (7)


@dataclass
class Experiment:
    """nominal and true models; problem (the calibration problem on the training poses); q_hold
    (M, 6) commanded holdout joints; p_hold (M, 3) [mm] and R_hold (M, 3, 3) measured there;
    floor_mm: holdout position RMS of the true model (the noise floor)."""

    nominal: object
    true: object
    problem: object
    q_hold: np.ndarray
    p_hold: np.ndarray
    R_hold: np.ndarray
    floor_mm: float
    floor_deg: float
    predict: object = None  # predict(result, q) -> points (M, 3) when the flange is not what is measured


def _pose_problem(nominal, q, T_meas, names=None, start=None):
    geometry = RobotGeometry(nominal, names, initial=start)
    frames = StationFrames(np.eye(4), free=False)
    tool = ToolFrame(np.eye(4), free=False)
    chain = tool_chain(nominal, q, geometry, frames, tool)
    residuals = [ToolPointResidual(chain, tool, T_meas[:, :3, 3]),
                 ToolRotationResidual(chain, tool, T_meas[:, :3, :3], weight_mm_per_rad=ROTATION_WEIGHT)]
    return Problem([geometry, frames, tool], residuals, n_poses=len(q), kinds=("point", "rotation"))


def _orientation_rms_deg(R_ref, R) -> float:
    """RMS rotation angle [deg] between (M, 3, 3) rotation stacks."""
    c = np.clip((np.einsum("nij,nij->n", R_ref, R) - 1.0) / 2.0, -1.0, 1.0)
    return float(np.degrees(np.sqrt(np.mean(np.arccos(c) ** 2))))


def pose_errors(model, q, p_meas, R_meas):
    """(position RMS [mm], orientation RMS [deg]) of ``model``'s flange at commanded q against the measured poses."""
    T = model.replace(T_world_base=np.eye(4)).fk(q)
    dp = np.linalg.norm(T[:, :3, 3] - p_meas, axis=1)
    return float(np.sqrt(np.mean(dp**2))), _orientation_rms_deg(R_meas, T[:, :3, :3])


def er10l_experiment(seed: int, joint_unit: str = "deg", n_train: int = 32, n_hold: int = 200,
                     error_scale: float = 1.0, slip: dict | None = None) -> Experiment:
    """The paper's simulation (module docstring). error_scale multiplies the parameter errors;
    slip: {parameter name: extra true offset [rad | mm]} (e.g. {"theta4": pi}, a slipped joint)."""
    if joint_unit not in ("rad", "deg"):
        raise ValueError(f"joint_unit must be 'rad' or 'deg', got {joint_unit!r}")
    nominal = load_robot("er10l_c10").replace(T_world_base=np.eye(4))
    rng = np.random.default_rng(seed)
    units = np.array(nominal.params.units)
    half = np.where(units == "rad", 0.01, 0.05) * error_scale * np.asarray(nominal.params.free)
    values = nominal.params.values + rng.uniform(-1.0, 1.0, len(half)) * half
    for name, extra in (slip or {}).items():
        values[nominal.params.index(name)] += extra
    true = nominal.with_params(values)
    noise = 0.1 if joint_unit == "rad" else math.radians(0.1)
    q = rng.uniform(-np.pi, np.pi, (n_train + n_hold, 6))
    T_meas = true.fk(q + rng.uniform(-noise, noise, q.shape))
    problem = _pose_problem(nominal, q[:n_train], T_meas[:n_train])
    qh, Th = q[n_train:], T_meas[n_train:]
    floor = pose_errors(true, qh, Th[:, :3, 3], Th[:, :3, :3])
    return Experiment(nominal, true, problem, qh, Th[:, :3, 3], Th[:, :3, :3], *floor)


def run_method(exp: Experiment, method: str, *, seed: int = 0, generations: int = 2000, particles: int = 20,
               **swarm_options) -> dict:
    """Calibrate ``exp.problem`` with ``method`` ("lm", "ipso", "ipso+lm"); one row of the tables:
    holdout position [mm] / orientation [deg] RMS, parameter errors against the truth (RMS over
    the identified parameters: lengths [mm], angles [mrad]), seconds, objective, at_floor
    (holdout position RMS within 10 % of the true model's)."""
    t0 = time.perf_counter()
    if method == "lm":
        res = solve(exp.problem)
    else:
        res = solve_swarm(exp.problem, method=method, seed=seed, generations=generations, particles=particles,
                          **swarm_options)
    seconds = time.perf_counter() - t0
    if exp.predict is None:
        hold_mm, hold_deg = pose_errors(res.model, exp.q_hold, exp.p_hold, exp.R_hold)
    else:
        d = np.linalg.norm(exp.predict(res, exp.q_hold) - exp.p_hold, axis=-1)
        hold_mm, hold_deg = float(np.sqrt(np.mean(d**2))), float("nan")
        if exp.R_hold is not None:  # orientation against the simulation's truth (the tracker measures none)
            hold_deg = _orientation_rms_deg(exp.R_hold, res.model.fk(exp.q_hold)[:, :3, :3])
    est = dict(zip(res.names, res.values))
    ident = [n for n in res.identifiability.identifiable if n in est and n in exp.nominal.params.names]
    idx = [exp.nominal.params.index(n) for n in ident]
    err = np.array([est[n] for n in ident]) - exp.true.params.values[idx]
    is_rad = np.array([exp.nominal.params.units[i] == "rad" for i in idx], dtype=bool)
    return {"method": method, "holdout_mm": hold_mm, "holdout_deg": hold_deg,
            "param_mm": float(np.sqrt(np.mean(err[~is_rad] ** 2))) if (~is_rad).any() else float("nan"),
            "param_mrad": float(1e3 * np.sqrt(np.mean(err[is_rad] ** 2))) if is_rad.any() else float("nan"),
            "seconds": seconds, "objective": float(getattr(res, "objective", np.nan)),
            "at_floor": bool(hold_mm <= 1.10 * exp.floor_mm), "converged": bool(res.converged),
            "n_identified": len(ident)}


def tracker_experiment(seed: int, robot: str = "ur10_dh_beta", n_train: int = 100, n_hold: int = 200,
                       sigma_mm: float = 0.02) -> Experiment:
    """The calibration engine's tracker simulation (tests/test_calibration.py): a perturbed robot
    (0.5 mm / 0.05 deg), one reflector, 0.02 mm noise, tracker in an unknown frame (base fitted)."""
    from ...calib import CalibrationProblem, Target
    from ...sim import LaserTracker, VirtualRobot

    nominal = load_robot(robot)
    vr = VirtualRobot.perturbed(nominal, seed, joint_noise_deg=0.0)
    tracker = LaserTracker.placed(seed + 100, reflectors=np.array([[30.0, 40.0, 100.0]]), sigma_mm=sigma_mm)
    rng = np.random.default_rng(seed + 200)
    q = vr.feasible_configurations(n_train + n_hold, rng, margin=0.1)
    pts = tracker.measure(vr, q, rng).points
    truth = tracker.true_points(vr, q).reshape(len(q), 1, 3)
    problem = CalibrationProblem(nominal, q[:n_train], [Target("r1", None, (0.0, 0.0, 50.0))], pts[:n_train],
                                 point_sigma_mm=sigma_mm, base_initial="fit")
    floor = float(np.sqrt(np.mean(np.sum((truth[n_train:, 0] - pts[n_train:, 0]) ** 2, axis=-1))))

    def predict(res, qh):
        return problem.predict_points(res.state, q=qh)[:, 0]

    # the true flange orientation in the tracker frame: evaluation only (the tracker measures none)
    R_hold_true = (tracker.T_tracker_world @ vr.true_model.fk(q[n_train:]))[:, :3, :3]
    return Experiment(nominal, vr.true_model, problem, q[n_train:], pts[n_train:, 0], R_hold_true, floor, 0.0,
                      predict)


def _summary(rows) -> dict:
    a = {k: np.array([r[k] for r in rows], dtype=float) for k in ("holdout_mm", "holdout_deg", "param_mm",
                                                                  "param_mrad", "seconds")}
    out = {k: float(np.median(v)) for k, v in a.items()}
    out["at_floor"] = f"{sum(r['at_floor'] for r in rows)}/{len(rows)}"
    out["not_converged"] = f"{sum(not r['converged'] for r in rows)}/{len(rows)}"  # next to every figure
    return out


def compare(make, seeds, methods=("lm", "ipso", "ipso+lm"), **options) -> dict:
    """{method: medians over seeds} and the median nominal / floor holdout errors."""
    rows = {m: [] for m in methods}
    floors, nominal = [], []
    for s in seeds:
        exp = make(s)
        floors.append(exp.floor_mm)
        if exp.predict is None:
            nominal.append(pose_errors(exp.nominal, exp.q_hold, exp.p_hold, exp.R_hold)[0])
        for m in methods:
            import warnings

            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                rows[m].append(run_method(exp, m, seed=s, **options))
    out = {m: _summary(r) for m, r in rows.items()}
    out["floor_mm"] = float(np.median(floors))
    out["nominal_mm"] = float(np.median(nominal)) if nominal else float("nan")
    out["per_seed"] = [dict(r, seed=s, floor_mm=f) for m in methods for s, f, r in zip(seeds, floors, rows[m])]
    return out


_PER_SEED_COLUMNS = ("experiment", "seed", "method", "holdout_mm", "holdout_deg", "param_mm", "param_mrad",
                     "seconds", "objective", "floor_mm", "at_floor", "converged", "n_identified")


def per_seed_csv(tables: dict) -> str:
    """{experiment title: compare() output} -> CSV text, one row per experiment, seed and method
    (units in the header: mm, deg, mrad, s; objective (7) in mm^2)."""
    lines = ["# robocal IPSO study, one row per seed; holdout_mm [mm], holdout_deg [deg], param_mm [mm], "
             "param_mrad [mrad], seconds [s], objective [mm^2], floor_mm [mm]", ",".join(_PER_SEED_COLUMNS)]
    for title, table in tables.items():
        for r in table["per_seed"]:
            row = dict(r, experiment=title.replace(",", ";"))
            lines.append(",".join(f"{row[c]:.6g}" if isinstance(row[c], float) else str(row[c])
                                  for c in _PER_SEED_COLUMNS))
    return "\n".join(lines) + "\n"


def _print(title, table):
    print(f"\n### {title}\nnoise floor (true model) {table['floor_mm']:.4g} mm; nominal model {table['nominal_mm']:.4g} mm")
    print("| method | holdout pos. [mm] | holdout orient. [deg] | param. error lengths [mm] | angles [mrad] | time [s] | "
          "at floor | not converged |")
    print("|---|---|---|---|---|---|---|---|")
    for m, r in table.items():
        if isinstance(r, dict):
            print(f"| {m} | {r['holdout_mm']:.4g} | {r['holdout_deg']:.4g} | {r['param_mm']:.4g} | "
                  f"{r['param_mrad']:.4g} | {r['seconds']:.3g} | {r['at_floor']} | {r['not_converged']} |")


def main(argv=None):
    import argparse

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=20)
    ap.add_argument("--hard-seeds", type=int, default=5)
    ap.add_argument("--per-seed", metavar="CSV", help="also write every seed's row to this CSV file (not overwritten)")
    a = ap.parse_args(argv)
    seeds, hard = range(a.seeds), range(a.hard_seeds)
    print("medians over seeds; at floor = holdout position RMS within 10 % of the true model's")
    tables = {}

    def run(title, table):
        tables[title] = table
        _print(title, table)

    run(f"ER10L-C10, joint noise +-0.1 deg ({a.seeds} seeds)", compare(lambda s: er10l_experiment(s, "deg"), seeds))
    run(f"ER10L-C10, joint noise +-0.1 rad as printed ({a.seeds} seeds)",
        compare(lambda s: er10l_experiment(s, "rad"), seeds))
    run(f"UR10 (DH + beta) tracker simulation, 100 poses ({a.seeds} seeds)", compare(tracker_experiment, seeds))
    run(f"ER10L, errors x30 (+-0.3 rad / +-1.5 mm), box +-0.3 rad / +-1.5 mm ({a.hard_seeds} seeds)",
        compare(lambda s: er10l_experiment(s, "deg", error_scale=30.0), hard, box_rad=0.3, box_mm=1.5))
    run(f"ER10L, theta4 slipped by 180 deg, box +-pi rad / +-0.5 mm ({a.hard_seeds} seeds)",
        compare(lambda s: er10l_experiment(s, "deg", slip={"theta4": np.pi}), hard, box_rad=np.pi))
    if a.per_seed:
        from ...io.atomic import atomic_write_text

        atomic_write_text(a.per_seed, per_seed_csv(tables))
        print(f"\nper-seed rows written to {a.per_seed}")


if __name__ == "__main__":
    main()
