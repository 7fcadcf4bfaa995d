"""Inputs of the ``robocal thermal`` commands, prepared from what :mod:`robocal.io.thermal_files`
reads: a run directory with its robot model, poses selected by id, cold references matched by joints."""

from __future__ import annotations

import fnmatch
from pathlib import Path

import numpy as np

from ...io.measurements import Measurements
from ...io.thermal_files import COLD_MATCH_TOL_RAD, read_run_dir, run_dir_robot
from ...robots import load_robot

__all__ = ["load_run_dir", "select_poses", "match_cold_reference"]


def load_run_dir(directory, robot=None, *, setup=None) -> dict:
    """:func:`robocal.io.thermal_files.read_run_dir` with the robot resolved: ``robot`` is a
    :class:`~robocal.kinematics.RobotModel`, a robot name or file, or None (the robot the run
    directory names). The returned dict holds the ``model`` used."""
    if robot is None:
        robot = run_dir_robot(directory, setup)
    model = load_robot(robot) if isinstance(robot, (str, Path)) else robot
    return read_run_dir(directory, model, setup=setup)


def select_poses(meas: Measurements, patterns, path="") -> Measurements:
    """The poses whose id matches any of the shell-style ``patterns`` (``c020-p0[1-6]``, ``p03``;
    several per string, comma or space separated); all poses without patterns."""
    pats = [p for v in patterns for p in str(v).replace(",", " ").split()]
    if not pats:
        return meas
    keep = [i for i, pid in enumerate(meas.pose_ids) if any(fnmatch.fnmatchcase(pid, p) for p in pats)]
    if not keep:
        ex = ", ".join(meas.pose_ids[:3])
        raise ValueError(f"{path}: no pose id matches {', '.join(pats)} (ids are like {ex})")
    return meas.subset(keep)


def match_cold_reference(q, cold: Measurements, path="", ids=None) -> np.ndarray:
    """The cold sphere centre (m, 3) [mm] for each pose of ``q`` (m, n) [rad | mm]: the row of
    ``cold`` at the same joints (within :data:`~robocal.io.thermal_files.COLD_MATCH_TOL_RAD`)."""
    q = np.asarray(q, float)
    d = np.abs(q[:, None, :] - cold.joints[None]).max(axis=2)          # (m, N)
    best = d.argmin(axis=1)
    bad = np.flatnonzero(d[np.arange(len(q)), best] > COLD_MATCH_TOL_RAD)
    if bad.size:
        who = ids[bad[0]] if ids is not None else str(bad[0] + 1)
        raise ValueError(f"{path}: no cold reference at the joints of sphere pose {who!r} "
                         f"({bad.size} pose(s) unmatched); the cold file must contain every pose measured now")
    return cold.points[best, 0]
