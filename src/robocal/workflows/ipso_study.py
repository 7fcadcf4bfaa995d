"""The IPSO paper's simulation (ER10L-C10) and the tracker simulation, each calibrated by LM,
IPSO and IPSO+LM: holdout errors, parameter recovery, time, noise floor (issue 13).

``python -m robocal.workflows.ipso_study [--seeds 20]`` prints the tables of docs/calibration.md
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

from ..calib import Problem, solve
from ..calib.blocks import RobotGeometry, StationFrames, ToolFrame
from ..calib.residuals import ToolPointResidual, ToolRotationResidual, tool_chain
from ..calib.swarm import solve_swarm
from ..robots import load_robot

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


def _pose_problem(nominal, q, T_meas, names=None, start=None):
    geometry = RobotGeometry(nominal, names, initial=start)
    frames = StationFrames(np.eye(4), free=False)
    tool = ToolFrame(np.eye(4), free=False)
    chain = tool_chain(nominal, q, geometry, frames, tool)
    residuals = [ToolPointResidual(chain, tool, T_meas[:, :3, 3]),
                 ToolRotationResidual(chain, tool, T_meas[:, :3, :3], weight_mm_per_rad=ROTATION_WEIGHT)]
    return Problem([geometry, frames, tool], residuals, n_poses=len(q), kinds=("point", "rotation"))


def pose_errors(model, q, p_meas, R_meas):
    """(position RMS [mm], orientation RMS [deg]) of ``model``'s flange at commanded q against the measured poses."""
    T = model.replace(T_world_base=np.eye(4)).fk(q)
    dp = np.linalg.norm(T[:, :3, 3] - p_meas, axis=1)
    c = np.clip((np.einsum("nij,nij->n", R_meas, T[:, :3, :3]) - 1.0) / 2.0, -1.0, 1.0)
    return float(np.sqrt(np.mean(dp**2))), float(np.degrees(np.sqrt(np.mean(np.arccos(c) ** 2))))


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
    model = res.model
    hold_mm, hold_deg = pose_errors(model, exp.q_hold, exp.p_hold, exp.R_hold)
    est = dict(zip(res.names, res.values))
    ident = [n for n in res.identifiability.identifiable if n in est]
    idx = [exp.nominal.params.index(n) for n in ident]
    err = np.array([est[n] for n in ident]) - exp.true.params.values[idx]
    is_rad = np.array([exp.nominal.params.units[i] == "rad" for i in idx], dtype=bool)
    return {"method": method, "holdout_mm": hold_mm, "holdout_deg": hold_deg,
            "param_mm": float(np.sqrt(np.mean(err[~is_rad] ** 2))) if (~is_rad).any() else float("nan"),
            "param_mrad": float(1e3 * np.sqrt(np.mean(err[is_rad] ** 2))) if is_rad.any() else float("nan"),
            "seconds": seconds, "objective": float(getattr(res, "objective", np.nan)),
            "at_floor": bool(hold_mm <= 1.10 * exp.floor_mm), "converged": bool(res.converged),
            "n_identified": len(ident)}
