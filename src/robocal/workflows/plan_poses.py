"""``robocal plan-poses``: measurement poses for a calibration, chosen and written as a joint program.

Random candidate configurations within the joint limits (seeded), kept if the flange lies in the
workspace box and (with a tracker position) the reflector is in range and faces the tracker; then
D-optimal selection and the first-order prediction of :func:`robocal.calib.plan.plan_campaign`.
The poses go to a ``robocal-program/1`` joint file (degrees) a user can load or convert.
"""

from __future__ import annotations

import numpy as np

from ..calib.plan import plan_campaign, visible_candidates
from ..io.programs import JointProgram, write_joint_program
from ..robots import load_robot

__all__ = ["candidate_poses", "parse_box", "plan_poses"]


def parse_box(text: str) -> np.ndarray:
    """``"xmin,xmax,ymin,ymax,zmin,zmax"`` [mm] -> (3, 2)."""
    try:
        v = np.array([float(x) for x in str(text).replace(";", ",").split(",")], dtype=float)
    except ValueError:
        raise ValueError(f"--workspace: expected six numbers xmin,xmax,ymin,ymax,zmin,zmax [mm], got {text!r}") from None
    if v.shape != (6,) or np.any(v[1::2] <= v[::2]):
        raise ValueError(f"--workspace: expected xmin,xmax,ymin,ymax,zmin,zmax [mm] with min < max, got {text!r}")
    return v.reshape(3, 2)


def plan_poses(robot, out_file, *, count: int, candidates: int = 1000, workspace=None, tracker_at=None,
               tool=(0.0, 0.0, 100.0), sigma_mm: float = 0.02, seed: int = 0, margin: float = 0.05,
               overwrite: bool = False) -> dict:
    """Plan ``count`` poses of ``robot`` out of ``candidates`` and write them to ``out_file``.

    workspace: (3, 2) box [mm] in the robot base frame for the flange; tracker_at: (3,) [mm] the
    instrument in the robot base frame (line of sight and range); tool: reflector in the flange
    frame [mm]; sigma_mm: instrument noise per coordinate. Returns the plan
    (:func:`~robocal.calib.plan.plan_campaign`) plus ``q`` (count, n), ``n_candidates``, ``file``.
    """
    from ..io.output_paths import check_outputs

    check_outputs(out_file, {"the robot file": robot}, overwrite=overwrite)
    model = load_robot(robot)
    qk = candidate_poses(model, count, candidates, seed, workspace=workspace, tracker_at=tracker_at, tool=tool,
                         margin=margin)
    plan = plan_campaign(model, qk, count, tool=tool, sigma_mm=sigma_mm)
    chosen = qk[plan["indices"]]
    names = tuple(f"P{i + 1:03d}" for i in range(count))
    prog = JointProgram(chosen, names, tuple(model.controller_joints), {"angle_unit": "deg"})
    note = (f"robocal plan-poses: {count} of {len(qk)} visible candidates (seed {seed}), D-optimal; "
            f"predicted held-out RMS {plan['holdout_rms_mm']:.4f} mm at {sigma_mm} mm noise")
    path = write_joint_program(out_file, prog, model, overwrite=overwrite, metadata={"note": note})
    return {**plan, "q": chosen, "n_candidates": len(qk), "file": path, "model": model}


def candidate_poses(model, count: int, candidates: int, seed: int, *, workspace=None, tracker_at=None,
                    tool=(0.0, 0.0, 100.0), margin: float = 0.05) -> np.ndarray:
    """The candidate configurations (M, n) of :func:`plan_poses`: ``candidates`` seeded uniform draws
    within the joint limits (``margin`` of each range kept free), kept if the flange is in the
    ``workspace`` box and the reflector visible from ``tracker_at``; a clear error when fewer than
    ``count`` remain."""
    if count < 1 or candidates < count:
        raise ValueError(f"--count must be at least 1 and at most --candidates ({candidates}), got {count}")
    rng = np.random.default_rng(seed)
    lo, hi = model.limits[:, 0], model.limits[:, 1]
    span = hi - lo
    q = rng.uniform(lo + margin * span, hi - margin * span, (int(candidates), model.n_joints))
    T = model.replace(T_world_base=np.eye(4)).fk(q)
    pts = T[:, :3, 3] + T[:, :3, :3] @ np.asarray(tool, dtype=float)
    keep = np.ones(len(q), dtype=bool)
    if workspace is not None:
        box = np.asarray(workspace, dtype=float)
        keep &= np.all((T[:, :3, 3] >= box[:, 0]) & (T[:, :3, 3] <= box[:, 1]), axis=1)
    if tracker_at is not None:
        keep &= visible_candidates(pts, T[:, :3, 2], tracker_at)
    if keep.sum() < count:
        raise ValueError(f"only {int(keep.sum())} of {candidates} candidate poses are inside the workspace box and "
                         f"visible from the tracker; need {count}: more --candidates, a larger box or another "
                         "tracker position")
    return q[keep]
