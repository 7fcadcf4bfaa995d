"""The 6-D probe campaign of tests/test_six_d_cli.py and docs/testing.md: a KUKA KR150 R3100 with
hidden true parameters (the last link's left nominal, so the tool frame alone carries the flange ->
probe transform), a 6-DoF probe on a 35 / -20 / 180 mm, ~38 deg tool, measured with 0.02 mm and
0.02 / 100 rad noise."""

from __future__ import annotations

import numpy as np

from ..io.measurements import Measurements
from ..robots import load_robot
from ..transforms import so3_exp
from .robot import VirtualRobot

__all__ = ["SIX_D_ROBOT", "SIX_D_SIGMA_MM", "SIX_D_W_MM_PER_RAD", "six_d_true_tool", "six_d_campaign"]

SIX_D_ROBOT = "kuka_kr150_r3100"
#: position noise per coordinate [mm]; the rotation noise is SIX_D_SIGMA_MM / SIX_D_W_MM_PER_RAD [rad]
SIX_D_SIGMA_MM = 0.02
SIX_D_W_MM_PER_RAD = 100.0


def six_d_true_tool() -> np.ndarray:
    """T_flange_probe (4, 4) [mm] of the campaign."""
    T = np.eye(4)
    T[:3, :3] = so3_exp([0.25, -0.15, 0.6])
    T[:3, 3] = [35.0, -20.0, 180.0]
    return T


def six_d_campaign(n: int = 60, seed: int = 3, q=None, effects: bool = False):
    """(Measurements, truth) of the campaign (seeded). ``q`` (n, 6) [rad]: the joints (default: drawn
    by the virtual robot). ``effects``: the ``realistic`` campaign effects the model lacks
    (:func:`robocal.sim.first_order.poses_with_effects`, transmission phases from ``seed + 1000``).
    truth: ``T_tool``, ``T_inst_base``, ``T_inst`` (4, 4) [mm], ``model`` (the true robot), ``q``,
    ``T_free`` (n, 4, 4) the noise-free measured poses, ``phases`` (2, 6) or None."""
    nominal = load_robot(SIX_D_ROBOT)
    rng = np.random.default_rng(seed)
    virtual = VirtualRobot.perturbed(nominal, rng)
    true = virtual.true_model.params.values.copy()
    for name in ("theta6", "d6", "a6", "alpha6"):
        i = nominal.params.index(name)
        true[i] = nominal.params.values[i]
    virtual = VirtualRobot(nominal, virtual.true_model.with_params(true))
    q = virtual.random_configurations(n, rng) if q is None else q
    T_inst = np.eye(4)
    T_inst[:3, :3] = so3_exp([0.05, -0.1, 2.0])
    T_inst[:3, 3] = [3200.0, -400.0, -600.0]
    phases = None
    if effects:
        from .first_order import poses_with_effects

        phases = np.random.default_rng(seed + 1000).uniform(0.0, 2 * np.pi, (2, q.shape[1]))
        T = poses_with_effects(virtual.true_model, q, T_inst, six_d_true_tool(), phases)[1]
    else:
        T = T_inst @ virtual.true_poses(q) @ six_d_true_tool()
    p = T[:, :3, 3] + rng.normal(0, SIX_D_SIGMA_MM, (n, 3))
    R = so3_exp(rng.normal(0, SIX_D_SIGMA_MM / SIX_D_W_MM_PER_RAD, (n, 3))) @ T[:, :3, :3]
    meas = Measurements(q, p, joint_names=nominal.controller_joints, rotations=R,
                        metadata={"robot": SIX_D_ROBOT, "instrument": "6-D probe", "frame": "tracker"})
    return meas, {"T_tool": six_d_true_tool(), "T_inst_base": T_inst @ virtual.true_model.T_world_base,
                  "T_inst": T_inst, "model": virtual.true_model, "q": q, "T_free": T, "phases": phases}
