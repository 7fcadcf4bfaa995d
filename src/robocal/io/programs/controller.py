"""How a controller turns a Cartesian target into joints: its nominal model, the target's
configuration data and its current joints.

OPW-class robots (KUKA, ABB, FANUC...): every closed-form solution within the limits
(:func:`robocal.kinematics.arm_configuration.ik_candidates`), filtered by the target's
:class:`~.configuration.ArmConfiguration`; among those left (several only when the data leaves
turns open, or without data) the one nearest the current joints. Other robots (UR): the inverse
kinematics nearest the current joints (a numeric solve started there), as the UR controller does
for ``movel``/``movej`` to a pose.
"""

from __future__ import annotations

import numpy as np

from ...kinematics.arm_configuration import arm_signature, ik_candidates
from ...kinematics.ik import ik_numeric
from ...kinematics.ik_analytic import is_analytic
from ...kinematics.model import EndEffector

__all__ = ["with_tool", "controller_joints"]


def with_tool(model, T_flange_tcp):
    """``model`` in its base frame (identity ``T_world_base``) with the TCP ``T_flange_tcp`` (4, 4)
    [mm] on its flange (the first end effector's frame) as its only end effector."""
    ee = model.end_effectors[0]
    tcp = EndEffector("tcp", ee.link, np.asarray(ee.T_link_ee, dtype=float) @ np.asarray(T_flange_tcp, dtype=float))
    return model.replace(T_world_base=np.eye(4), end_effectors=(tcp,))


def controller_joints(model, T_base_tcp, configuration, q_current):
    """Joints (6,) [rad] the controller commands for the TCP pose ``T_base_tcp`` (4, 4) [mm].

    model: the nominal model with the program's tool (:func:`with_tool`); configuration: the
    target's :class:`~.configuration.ArmConfiguration`; q_current: (n,) the joints the robot is at.
    Returns ``(q, reason)``: ``q`` None when no solution fits (``reason`` says why).
    """
    q_current = np.asarray(q_current, dtype=float)
    if not is_analytic(model):
        if not configuration.nearest:
            return None, "configuration data on a robot without closed-form IK"
        # every solution found from the current joints and from spread-out starts; each joint turned
        # by whole turns to the value nearest the current one; the nearest solution wins
        lo, hi = model.limits[:, 0], model.limits[:, 1]
        seeds = np.random.default_rng(0).uniform(np.maximum(lo, -np.pi), np.minimum(hi, np.pi), (48, len(lo)))
        seeds = np.vstack([q_current, seeds])
        rs = ik_numeric(model, np.broadcast_to(T_base_tcp, (len(seeds), 4, 4)), seeds, tol_mm=1e-8, tol_rad=1e-11,
                        max_iterations=200)
        if not rs.converged.any():
            return None, f"not reached ({rs.position_error_mm[0]:.3g} mm left from the current joints)"
        sol = rs.q[rs.converged]
        turns = np.round((q_current - sol) / (2 * np.pi)) * 2 * np.pi
        shifted = sol + turns
        inside = np.all((shifted >= lo - 1e-9) & (shifted <= hi + 1e-9), axis=1)
        sol = np.where(inside[:, None], shifted, sol)
        return sol[int(np.argmin(np.linalg.norm(sol - q_current, axis=1)))], ""
    cand = ik_candidates(model, T_base_tcp[None])[0]
    if len(cand) == 0:
        return None, "out of reach (no solution within the joint limits)"
    if not configuration.nearest:
        ok = configuration.matches(arm_signature(model, cand), cand)
        if not ok.any():
            return None, f"no solution within the joint limits with configuration {configuration.text}"
        cand = cand[ok]
    k = int(np.argmin(np.max(np.abs(cand - q_current), axis=1)))
    return cand[k], ""
