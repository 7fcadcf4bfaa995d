"""The line-shaped 6-D re-registration campaign of docs/calibration.md (``--frames-only``) and
tests/test_frames_only.py: a KUKA KR150 R3100 flange moving along an 800 mm straight line (``n``
poses, orientation varying by ~2 deg), carrying a 6-DoF probe turned by ~170 deg, measured by an
instrument somewhere new (0.02 mm, 0.0002 rad noise)."""

from __future__ import annotations

import numpy as np

from ..kinematics.ik import ik_numeric
from ..robots import load_robot
from ..transforms import so3_exp

__all__ = ["LINE_ROBOT", "LINE_TOOL_ROTVEC", "line_campaign_poses"]

LINE_ROBOT = "kuka_kr150_r3100"
#: the probe's rotation on the flange (rotation vector [rad], ~170 deg)
LINE_TOOL_ROTVEC = (2.9, 0.3, 0.2)


def line_campaign_poses(seed: int = 5, n: int = 20, effects: bool = False) -> dict:
    """The campaign's joints and measurements (seeded).

    Returns ``{model, q (n, 6) [rad], points (n, 3) [mm], rotations (n, 3, 3), tool (4, 4),
    instrument (4, 4), T_measured (n, 4, 4)}``: ``tool`` T_flange_probe and ``instrument``
    T_instrument_base [mm]; ``T_measured`` the noise-free measured probe poses. ``effects``: the
    robot and instrument have the ``realistic`` campaign effects
    (:func:`robocal.sim.first_order.poses_with_effects`, phases drawn from ``seed + 1000``)."""
    m = load_robot(LINE_ROBOT)
    rng = np.random.default_rng(seed)
    q0 = np.radians([10.0, -80.0, 100.0, 5.0, 40.0, 20.0])
    T0 = m.fk(q0)
    d = np.array([0.6, 0.7, -0.2])
    d /= np.linalg.norm(d)
    T = np.repeat(T0[None], n, axis=0)
    T[:, :3, 3] = T0[:3, 3] + np.linspace(-400, 400, n)[:, None] * d
    T[:, :3, :3] = so3_exp(rng.normal(0, 0.03, (n, 3))) @ T0[:3, :3]
    q = ik_numeric(m, T, q0).q
    tool = np.eye(4)
    tool[:3, :3], tool[:3, 3] = so3_exp(list(LINE_TOOL_ROTVEC)), [30.0, 10.0, 150.0]
    inst = np.eye(4)
    inst[:3, :3], inst[:3, 3] = so3_exp([0.03, 0.02, -2.2]), [3000.0, -500.0, -400.0]
    if effects:
        from .first_order import poses_with_effects

        phases = np.random.default_rng(seed + 1000).uniform(0.0, 2 * np.pi, (2, q.shape[1]))
        Tm = poses_with_effects(m, q, inst, tool, phases)[1]
    else:
        Tm = inst @ m.fk(q) @ tool
    p = Tm[:, :3, 3] + rng.normal(0, 0.02, (n, 3))
    R = so3_exp(rng.normal(0, 0.0002, (n, 3))) @ Tm[:, :3, :3]
    return {"model": m, "q": q, "points": p, "rotations": R, "tool": tool, "instrument": inst, "T_measured": Tm}
