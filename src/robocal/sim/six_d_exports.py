"""A simulated 6-D campaign written as the vendors' exports (issue 31): a UR10 carrying a 6-DoF
probe, its poses as a Leica T-Mac-like 6DoF export (semicolon CSV, decimal comma, ``Rx, Ry, Rz
[deg]`` fixed-axis angles, quote-prefixed time stamps) and its joints as a UR RTDE log
(``timestamp actual_q_0 .. actual_q_5``, radians). Used by ``tests/test_six_d_import.py`` and by
the documented figures of docs/testing.md (:mod:`robocal.docs.figures`): same draws.

Lengths mm, angles rad unless a name says deg.
"""

from __future__ import annotations

from datetime import datetime, timedelta
from pathlib import Path

import numpy as np

from ..robots import load_robot
from ..transforms import euler_from_matrix, so3_exp
from .robot import VirtualRobot

__all__ = ["EXPORT_T0", "PROBE_ROBOT", "PROBE_SIGMA_MM", "PROBE_W_MM_PER_RAD", "export_times", "probe_campaign",
           "probe_tool", "write_leica_tmac", "write_rtde_log"]

PROBE_ROBOT = "ur10"
#: position noise per coordinate [mm]; the rotation noise is PROBE_SIGMA_MM / PROBE_W_MM_PER_RAD [rad]
PROBE_SIGMA_MM = 0.02
#: mm per rad: the CLI's default rotation weight (0.02 mm ~ 0.0115 deg)
PROBE_W_MM_PER_RAD = 100.0
#: the first export time stamp; one pose every 4 s
EXPORT_T0 = datetime(2022, 10, 11, 15, 6, 48, 43000)


def probe_tool() -> np.ndarray:
    """T_flange_probe (4, 4) [mm] of the campaign (the hidden truth the calibration recovers)."""
    T = np.eye(4)
    T[:3, :3] = so3_exp([0.3, -0.2, 0.9])
    T[:3, 3] = [20.0, -35.0, 140.0]
    return T


def probe_campaign(n: int = 60, seed: int = 11, effects: bool = False) -> dict:
    """The UR10 6-D campaign (seeded): a perturbed UR10 without encoder noise whose last link's
    placement is nominal (the probe frame carries it), ``n`` random configurations, the probe's
    poses in a tracker frame, with 0.02 mm / 0.02/100 rad noise.

    Parameters
    ----------
    n : int
        Poses.
    seed : int
        Seed of the robot, the joints and the noise.
    effects : bool
        The ``realistic`` campaign effects the model lacks
        (:func:`robocal.sim.first_order.poses_with_effects`, transmission phases from ``seed + 1000``).

    Returns
    -------
    dict
        ``q`` (n, 6) [rad], ``T`` (n, 4, 4) the measured probe poses [mm], ``T_free`` (n, 4, 4) the
        noise-free ones, ``virtual`` (the :class:`VirtualRobot`), ``T_inst`` (4, 4) the tracker
        frame, ``rng`` (the generator after the draws), ``phases`` (2, 6) or None.
    """
    nominal = load_robot(PROBE_ROBOT)
    rng = np.random.default_rng(seed)
    virtual = VirtualRobot.perturbed(nominal, rng, joint_noise_deg=0.0)
    true = virtual.true_model.params.values.copy()
    for name in ("theta6", "d6", "a6", "alpha6"):  # the probe frame carries the last link's placement
        i = nominal.params.index(name)
        true[i] = nominal.params.values[i]
    virtual = VirtualRobot(nominal, virtual.true_model.with_params(true))
    q = virtual.random_configurations(n, rng)
    T_inst = np.eye(4)
    T_inst[:3, :3] = so3_exp([0.02, -0.05, 2.4])
    T_inst[:3, 3] = [2800.0, 900.0, -350.0]
    phases = None
    if effects:
        from .first_order import poses_with_effects

        phases = np.random.default_rng(seed + 1000).uniform(0.0, 2 * np.pi, (2, q.shape[1]))
        T = poses_with_effects(virtual.true_model, q, T_inst, probe_tool(), phases)[1]
    else:
        T = T_inst @ virtual.true_poses(q) @ probe_tool()
    T_free = T.copy()
    T[:, :3, 3] += rng.normal(0, PROBE_SIGMA_MM, (n, 3))
    T[:, :3, :3] = so3_exp(rng.normal(0, PROBE_SIGMA_MM / PROBE_W_MM_PER_RAD, (n, 3))) @ T[:, :3, :3]
    return {"q": q, "T": T, "T_free": T_free, "virtual": virtual, "T_inst": T_inst, "rng": rng, "phases": phases}


def export_times(n: int, start: datetime = EXPORT_T0, step_s: float = 4.0) -> list:
    """``n`` time stamps ``step_s`` seconds apart from ``start``."""
    return [start + timedelta(seconds=step_s * k) for k in range(n)]


def _stamp(t: datetime) -> str:
    return t.strftime("%d.%m.%Y %H:%M:%S.") + f"{t.microsecond // 1000:03d}"


def write_leica_tmac(path, T, times) -> Path:
    """Write probe poses ``T`` (N, 4, 4) [mm] as a Leica T-Mac-like 6DoF export: semicolon CSV in
    Latin-1, decimal comma, ``Rx, Ry, Rz [deg]`` fixed-axis (``rpy``) angles, a quote-prefixed
    ``dd.mm.yyyy HH:MM:SS.mmm`` time per row (``times``: N datetimes). Returns the path."""
    path = Path(path)
    rpy = np.degrees(euler_from_matrix(T[:, :3, :3], "rpy"))
    lines = ["Leica T-Mac 6DoF export;;;;;;;", "Units: Millimeters;;;;;;;",
             "Name;X;Y;Z;Rx [deg];Ry [deg];Rz [deg];Time"]
    for k, (p, r, t) in enumerate(zip(T[:, :3, 3], rpy, times)):
        cells = [f"P{k + 1:03d}"] + [f"{v:.4f}".replace(".", ",") for v in (*p, *r)] + [f"'{_stamp(t)}"]
        lines.append(";".join(cells))
    path.write_text("\n".join(lines) + "\n", encoding="latin-1")
    return path


def write_rtde_log(path, q) -> Path:
    """Write joints ``q`` (N, 6) [rad] as a UR RTDE log (space-separated ``timestamp actual_q_0 ..
    actual_q_5``, one row every 4 s from 12.5 s). Returns the path."""
    path = Path(path)
    lines = ["timestamp " + " ".join(f"actual_q_{j}" for j in range(6))]
    lines += [f"{12.5 + 4.0 * k:.3f} " + " ".join(f"{v:.9f}" for v in row) for k, row in enumerate(q)]
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path


def write_pose_targets(path, targets, q_hint, joint_names) -> Path:
    """Write tool-pose targets ``targets`` (N, 4, 4) [mm] in the measuring frame as a
    ``robocal-targets/1`` file (quaternions, with the joints ``q_hint`` (N, n) [rad] written in deg
    as the configuration hint under ``joint_names``), for ``robocal correct``. Returns the path."""
    from ..transforms import quaternion_from_matrix

    path = Path(path)
    quat = quaternion_from_matrix(targets[:, :3, :3])
    rows = ["# format: robocal-targets/1", "# length_unit: mm", "# angle_unit: deg", "# orientation: quaternion",
            "# frame: world", "name,x,y,z,qw,qx,qy,qz," + ",".join(joint_names)]
    rows += [",".join([f"T{k}"] + [repr(float(v)) for v in (*targets[k, :3, 3], *quat[k], *np.degrees(q_hint[k]))])
             for k in range(len(targets))]
    path.write_text("\n".join(rows) + "\n", encoding="utf-8")
    return path


def read_corrected_joints(path, joint_names) -> np.ndarray:
    """The joints (N, n) [rad] of ``robocal correct``'s output file (columns ``joint_names`` in deg)."""
    lines = [x for x in Path(path).read_text(encoding="utf-8").splitlines() if not x.startswith("#")]
    cols = lines[0].split(",")
    return np.radians([[float(row.split(",")[cols.index(j)]) for j in joint_names] for row in lines[1:]])
