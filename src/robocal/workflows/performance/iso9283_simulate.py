"""``robocal simulate iso9283``: the simulator's true robot executes an ISO 9283 plan.

The true robot is the one ``robocal simulate tracker ROBOT --seed S`` measured (the same seed draws
the same hidden parameters; or its ``.truth.json`` is read). With ``--calibrated MODEL`` the
controller drives the plan's poses corrected by the calibrated model (its inverse kinematics seeded
at the nominal joints, on the same arm configuration): the "after" run of a before/after test.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from ...io.iso9283_files import write_iso_measurements
from ...kinematics.ik import ik_numeric
from ...robots import load_robot
from ...sim.iso9283 import IsoEffects, simulate_iso_run
from ...sim.robot import VirtualRobot

__all__ = ["true_model_for", "corrected_plan", "simulate_iso9283"]


def true_model_for(nominal, *, seed: int | None = None, truth_file=None):
    """The hidden true model of ``robocal simulate tracker`` (same seed or its truth file), with its
    base frame at the origin (the ISO test is stated in the robot's base frame)."""
    if truth_file is not None:
        d = json.loads(Path(truth_file).read_text(encoding="utf-8"))
        true = nominal.with_params(**{k: float(v) for k, v in d["true_parameters"].items()})
    else:
        s_robot = np.random.default_rng(np.random.SeedSequence(int(seed)).spawn(3)[0])
        true = VirtualRobot.perturbed(nominal, s_robot).true_model
    return true.replace(T_world_base=np.eye(4))


def corrected_plan(protocol: dict, calibrated, T_flange_tool=None) -> dict:
    """The plan with every joint target replaced by the calibrated model's inverse kinematics of
    the commanded pose (seeded at the nominal joints: the same arm configuration).

    T_flange_tool: (4, 4) the tool as the calibration identified it (e.g. the reflector's point);
    default the plan's tool."""
    from ...errors import NotConvergedError

    tool = None if protocol.get("tool") is None else np.asarray(protocol["tool"], float)
    if T_flange_tool is not None:
        tool = np.asarray(T_flange_tool, float)
    inv_tool = np.eye(4) if tool is None else np.linalg.inv(tool)

    def fix(points, R, q_nominal):
        P = np.asarray(points, float).reshape(-1, 3)
        T = np.broadcast_to(np.eye(4), (len(P), 4, 4)).copy()
        T[:, :3, :3] = np.asarray(R, float)
        T[:, :3, 3] = P
        T_world = calibrated.T_world_base @ T @ inv_tool
        res = ik_numeric(calibrated, T_world, np.asarray(q_nominal, float).reshape(len(P), -1))
        if not np.all(res.converged):
            raise NotConvergedError("the calibrated model's inverse kinematics did not converge for every ISO pose")
        return res.q

    new = json.loads(json.dumps(protocol))
    for group in ("poses", "approach_points"):
        for pose in new[group].values():
            pose["joints_rad"] = fix(pose["position_mm"], pose["R"], pose["joints_rad"])[0].tolist()
    R = new["poses"]["P1"]["R"]
    for path in new["paths"].values():
        path["joints_rad"] = fix(path["points_mm"], R, path["joints_rad"]).tolist()
    new["corrected_by"] = calibrated.name
    return new


def simulate_iso9283(robot, protocol: dict, out_path, *, seed: int, mpe, instrument_at_mm, truth_file=None,
                     calibrated=None, effects: IsoEffects | None = None, overwrite: bool = False) -> dict:
    """Run ``protocol`` on the true robot and write the tracker's measurement file.

    Returns {``measurements`` (path), ``truth_measurements`` (path of the instrument-free rows,
    ``<name>.truth.csv``), ``n_points``}.
    """
    nominal = load_robot(robot)
    true = true_model_for(nominal, seed=seed, truth_file=truth_file)
    plan = protocol if calibrated is None else corrected_plan(protocol, load_robot(calibrated))
    rows, true_rows = simulate_iso_run(true, plan, seed=np.random.default_rng(np.random.SeedSequence(int(seed)).spawn(4)[3]),
                                       effects=effects, mpe=mpe, instrument_at_mm=instrument_at_mm)
    out = Path(out_path)
    truth_out = out.with_name(out.stem + ".truth.csv")
    write_iso_measurements(out, rows, overwrite=overwrite)
    write_iso_measurements(truth_out, true_rows, overwrite=overwrite)
    return {"measurements": str(out), "truth_measurements": str(truth_out), "n_points": len(rows)}
