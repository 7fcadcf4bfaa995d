"""The simulated trials of the fault diagnosis of `robocal verify` (tests/test_verify.py and
docs/iso9283.md "Quick verification"): an IRB 140 whose calibrated model is exact to 0.01 mm per
coordinate, 10 random poses, a reflector 150 mm beyond the flange and 100 mm off its axis, a tracker
with 0.02 mm noise, and one joint with an offset jump or a backlash."""

from __future__ import annotations

import numpy as np

from ..robots import load_robot

__all__ = ["REFLECTOR_MM", "backlash_trials", "offset_jump_trials", "with_backlash_columns"]

#: a reflector on a tool 150 mm beyond the flange and 100 mm off its axis (a typical SMR holder) [mm]
REFLECTOR_MM = np.array([0.0, 100.0, 150.0])
#: tracker noise per coordinate [mm] and the calibrated model's uncertainty per coordinate [mm]
TRACKER_SIGMA_MM = 0.02
MODEL_SIGMA_MM = 0.01
N_POSES = 10


def _points(model, q):
    """The reflector's positions (N, 3) [mm] at joints ``q`` (N, 6) [rad]."""
    T = model.fk(q)
    return T[:, :3, :3] @ REFLECTOR_MM + T[:, :3, 3]


def _jacobian(model, q, h=1e-6):
    """``∂p/∂q`` (N, 3, n) [mm/rad] by central differences."""
    n = q.shape[1]
    J = np.empty((len(q), 3, n))
    for j in range(n):
        dq = np.zeros(n)
        dq[j] = h
        J[:, :, j] = (_points(model, q + dq) - _points(model, q - dq)) / (2 * h)
    return J


def offset_jump_trials(joint: int, trials: int = 100, jump_deg: float = 0.05, seed: int | None = None) -> dict:
    """A ``jump_deg`` offset jump of ``joint`` (0-based), ``trials`` checks of 10 random poses
    (within 20-80 % of each joint's range; seed ``10 + joint`` unless given).

    Returns
    -------
    dict
        ``detected`` (checks whose decision is not ok), ``named`` (checks naming the joint),
        ``trials``.
    """
    from ..performance.verify import verify_positions

    model = load_robot("abb_irb140")
    rng = np.random.default_rng(10 + joint if seed is None else seed)
    lo, hi = model.limits[:, 0], model.limits[:, 1]
    detected = named = 0
    for _ in range(trials):
        q = lo + (hi - lo) * rng.uniform(0.2, 0.8, (N_POSES, 6))
        pred = _points(model, q)
        dq = np.zeros(6)
        dq[joint] = np.radians(jump_deg)
        meas = _points(model, q + dq) + rng.normal(0, TRACKER_SIGMA_MM, (N_POSES, 3))
        C = np.tile(np.eye(3) * MODEL_SIGMA_MM ** 2, (N_POSES, 1, 1))
        v = verify_positions(meas, pred, instrument_sigma_mm=TRACKER_SIGMA_MM, prediction_covariance_mm2=C,
                             joint_jacobian=_jacobian(model, q), joint_names=model.controller_joints)
        detected += v.decision != "ok"
        named += v.suspect_joint == model.controller_joints[joint]
    return {"detected": detected, "named": named, "trials": trials}


def backlash_trials(joint: int, trials: int = 100, backlash_deg: float = 0.1, jump_deg: float = 0.05,
                    seed: int | None = None) -> dict:
    """A ``backlash_deg`` backlash of ``joint`` (0-based; the joint stops b/2 short in the direction
    it moved: the simulator's model), 10 poses approached from random sides, ``trials`` checks (seed
    ``40 + joint`` unless given); on the same poses and approach signs, a ``jump_deg`` offset jump.

    Returns
    -------
    dict
        ``detected`` (backlash checks not ok), ``named`` (named as that joint's backlash),
        ``offset_named`` (the offset jump named as that joint's offset), ``trials``, and
        ``backlash_estimates_rad`` (list: the reported backlash of each correctly named check).
    """
    from ..performance.verify import verify_positions

    model = load_robot("abb_irb140")
    rng = np.random.default_rng(40 + joint if seed is None else seed)
    lo, hi = model.limits[:, 0], model.limits[:, 1]
    b = np.radians(backlash_deg)
    name = model.controller_joints[joint]
    detected = named = offset_named = 0
    estimates = []
    for _ in range(trials):
        q = lo + (hi - lo) * rng.uniform(0.2, 0.8, (N_POSES, 6))
        s = rng.choice([-1.0, 1.0], size=(N_POSES, 6))
        pred = _points(model, q)
        q_true = q.copy()
        q_true[:, joint] -= 0.5 * b * s[:, joint]
        meas = _points(model, q_true) + rng.normal(0, TRACKER_SIGMA_MM, (N_POSES, 3))
        C = np.tile(np.eye(3) * MODEL_SIGMA_MM ** 2, (N_POSES, 1, 1))
        J = _jacobian(model, q)
        v = verify_positions(meas, pred, instrument_sigma_mm=TRACKER_SIGMA_MM, prediction_covariance_mm2=C,
                             joint_jacobian=J, joint_names=model.controller_joints, approach_signs=s)
        detected += v.decision != "ok"
        if v.suspect_joint == name and v.suspect_cause == "backlash":
            named += 1
            estimates.append(float(v.suspect_offset))
        dq = np.zeros(6)
        dq[joint] = np.radians(jump_deg)
        meas_o = _points(model, q + dq) + rng.normal(0, TRACKER_SIGMA_MM, (N_POSES, 3))
        v = verify_positions(meas_o, pred, instrument_sigma_mm=TRACKER_SIGMA_MM, prediction_covariance_mm2=C,
                             joint_jacobian=J, joint_names=model.controller_joints, approach_signs=s)
        offset_named += v.suspect_joint == name and v.suspect_cause == "offset"
    return {"detected": detected, "named": named, "offset_named": offset_named, "trials": trials,
            "backlash_estimates_rad": estimates}


def with_backlash_columns(text: str, joint: str = "J2", backlash_deg: float = 0.15, seed: int = 7) -> str:
    """A robocal measurement file (CSV text, joints in degrees) with ``approach_J1`` ... ``approach_J6``
    columns drawn at random (seed) and ``joint``'s reading moved by ``+-backlash_deg / 2`` by its
    approach side (the encoder reads b/2 more than the arm reached in the direction it moved)."""
    lines = text.splitlines()
    head = [i for i, s in enumerate(lines) if not s.startswith("#")][0]
    k = lines[head].split(",").index(joint)
    j = int(joint[1:]) - 1
    rng = np.random.default_rng(seed)
    out = lines[:head] + [lines[head] + "," + ",".join(f"approach_J{i}" for i in range(1, 7))]
    for s in lines[head + 1:]:
        v = s.split(",")
        sign = rng.choice([-1, 1], size=6)
        v[k] = repr(float(v[k]) + 0.5 * backlash_deg * float(sign[j]))
        out.append(",".join(v + [f"{x:+d}" for x in sign]))
    return "\n".join(out) + "\n"
