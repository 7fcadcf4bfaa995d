"""The simulator's true robot runs an ISO 9283 plan: what a laser tracker would record.

The controller drives the plan's nominal joints; the true robot (hidden parameters) lands where its
true kinematics put the tool, with the effects that make a real robot's repeatability:

* **joint noise** (each arrival, independent): ``joint_noise_deg``;
* **backlash**: a joint that arrives moving in the positive direction stops ``b/2`` short, one that
  arrives moving negative ``b/2`` beyond — so a pose approached from different directions lands in
  different places (what vAP measures);
* **thermal drift** over the run: J2 and J3 offsets growing as ``D·(1 − exp(−t/τ))``;
* **path following**: a circle is driven ``path_radial_error_mm`` inside its commanded radius.

The tracker adds a random error per coordinate of ``MPE(d)/4`` (its MPE at the distance, read as an
expanded bound). :func:`simulate_iso_run` returns the measurement rows and the same rows without the
instrument error (the truth every figure is tested against).
"""

from __future__ import annotations

import numpy as np

from ..performance.adequacy import InstrumentMPE
from ..transforms import rotvec_from_matrix
from .robot import as_rng

__all__ = ["IsoEffects", "simulate_iso_run"]


class IsoEffects:
    """Repeatability effects of the simulated robot (degrees, mm, hours)."""

    def __init__(self, joint_noise_deg: float = 0.002, backlash_deg: float = 0.004, drift_deg: float = 0.005,
                 drift_time_constant_h: float = 1.0, path_radial_error_mm: float = 0.05, seconds_per_move: float = 3.0):
        self.joint_noise = np.radians(joint_noise_deg)
        self.backlash = np.radians(backlash_deg)
        self.drift = np.radians(drift_deg)
        self.tau_s = drift_time_constant_h * 3600.0
        self.path_radial_error_mm = float(path_radial_error_mm)
        self.seconds_per_move = float(seconds_per_move)


def _tool_poses(true_model, q, T_flange_tool, in_world: bool = False):
    T = true_model.fk(q) if in_world else np.linalg.inv(true_model.T_world_base) @ true_model.fk(q)
    return T if T_flange_tool is None else T @ T_flange_tool


def simulate_iso_run(true_model, protocol: dict, *, seed, effects: IsoEffects | None = None,
                     mpe: InstrumentMPE, instrument_at_mm, sample_rate_hz: float = 250.0, in_world: bool = False):
    """Run the plan on the true robot.

    Parameters
    ----------
    true_model : RobotModel
        The simulated robot's true kinematics (its base frame is the test's frame).
    protocol : dict
        A plan from :func:`robocal.workflows.performance.iso9283_plan.build_iso_plan`.
    seed : int or numpy.random.Generator
    effects : IsoEffects, optional
    mpe : InstrumentMPE
        The tracker's MPE; its random error per coordinate is ``MPE(d)/4``.
    instrument_at_mm : array_like, shape (3,)
        Tracker position in the base frame [mm].
    in_world : bool
        Report the attained poses in ``true_model``'s world frame instead of its base frame: the
        frame the plant registers its instrument to (e.g. the calibrated base frame, with the true
        robot's base placed in it).

    Returns
    -------
    (rows, true_rows) : list of dict
        ``{"id", "time_s", "x", "y", "z", "a", "b", "c"}`` (mm; attained orientation as a rotation
        vector in degrees), measured and true.
    """
    rng = as_rng(seed)
    fx = effects or IsoEffects()
    n = true_model.n_joints
    tool = None if protocol.get("tool") is None else np.asarray(protocol["tool"], float)
    station = np.asarray(instrument_at_mm, float).reshape(3)
    t = 0.0
    q_prev = np.asarray(protocol["poses"]["P1"]["joints_rad"], float)
    rows, true_rows = [], []
    thermal = np.zeros(n)

    def arrive(q_cmd, q_from):
        direction = np.sign(q_cmd - q_from)
        q = q_cmd - 0.5 * fx.backlash * direction
        if fx.joint_noise > 0:
            q = q + rng.normal(0.0, fx.joint_noise, n)
        thermal[:] = 0.0
        if n >= 3:
            thermal[1] = thermal[2] = fx.drift * (1.0 - np.exp(-t / fx.tau_s))
        return q + thermal

    def record(mid, T_true):
        p = T_true[:3, 3]
        rv = np.degrees(rotvec_from_matrix(T_true[:3, :3]))
        sigma = mpe.at(np.linalg.norm(p - station)) / 4.0
        noisy = p + rng.normal(0.0, sigma, 3)
        base = {"id": mid, "time_s": round(t, 3)}
        true_rows.append(dict(base, x=p[0], y=p[1], z=p[2], a=rv[0], b=rv[1], c=rv[2]))
        rows.append(dict(base, x=noisy[0], y=noisy[1], z=noisy[2], a=rv[0], b=rv[1], c=rv[2]))

    for m in protocol["measurements"]:
        test = m["test"]
        if test in ("pose", "vap", "drift"):
            if test == "drift":
                t = max(t, m["time_min"] * 60.0)
                # a cycle through the other poses before each measurement of P1
                q_prev = np.asarray(protocol["poses"]["P2"]["joints_rad"], float)
            if test == "vap":
                q_prev = np.asarray(protocol["approach_points"][m["approach_from"]]["joints_rad"], float)
                t += fx.seconds_per_move
            q_cmd = np.asarray(protocol["poses"][m["pose"]]["joints_rad"], float)
            q = arrive(q_cmd, q_prev)
            t += fx.seconds_per_move
            record(m["id"], _tool_poses(true_model, q, tool, in_world))
            q_prev = q_cmd
        elif test in ("line", "circle"):
            path = protocol["paths"][test]
            qp = np.asarray(path["joints_rad"], float)
            pts = np.asarray(path["points_mm"], float)
            seg = np.linalg.norm(np.diff(pts, axis=0), axis=1)
            duration = max(len(qp) * 0.1, 2.0)
            k = max(int(duration * sample_rate_hz), 4 * len(qp))
            s = np.linspace(0.0, 1.0, k)
            cum = np.concatenate([[0.0], np.cumsum(seg)]) / max(seg.sum(), 1e-12)
            q_dense = np.stack([np.interp(s, cum, qp[:, j]) for j in range(n)], axis=1)
            q_dense = q_dense + rng.normal(0.0, fx.joint_noise, n)              # this cycle's repeatability
            T = _tool_poses(true_model, q_dense, tool, in_world)
            P = T[:, :3, 3].copy()
            if test == "circle" and fx.path_radial_error_mm:
                c = np.asarray(path["centre_mm"], float)
                radial = P - c
                radial -= np.outer(radial @ np.asarray(path["normal"], float), path["normal"])
                P -= fx.path_radial_error_mm * radial / np.linalg.norm(radial, axis=1, keepdims=True)
            for i in range(k):
                sigma = mpe.at(np.linalg.norm(P[i] - station)) / 4.0
                noisy = P[i] + rng.normal(0.0, sigma, 3)
                base = {"id": m["id"], "time_s": round(t + i / sample_rate_hz, 4)}
                rv = np.degrees(rotvec_from_matrix(T[i, :3, :3]))
                true_rows.append(dict(base, x=P[i, 0], y=P[i, 1], z=P[i, 2], a=rv[0], b=rv[1], c=rv[2]))
                rows.append(dict(base, x=noisy[0], y=noisy[1], z=noisy[2], a=rv[0], b=rv[1], c=rv[2]))
            t += k / sample_rate_hz + fx.seconds_per_move
            q_prev = qp[-1]
    return rows, true_rows
