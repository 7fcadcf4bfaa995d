"""What ``robocal calibrate`` solves: the problems built from a measurement file and the options.

* :func:`split_by_ids` -- a given train / held-out protocol (pose ids) instead of a seeded split;
* :func:`build_problems` -- the "before" problem (geometry held nominal) and the calibration
  problem: position-only (:class:`~robocal.calib.CalibrationProblem`) or, when the file has
  orientations, 6-D (:class:`~robocal.calib.pose_problem.PoseCalibrationProblem`: positions and
  orientations, a 6-DoF tool frame);
* :func:`tool_frame_summary` -- the identified tool frame with its uncertainty, JSON-ready.
"""

from __future__ import annotations

import math

import numpy as np

from ...calib import CalibrationProblem, Target
from ...calib.pose_problem import PoseCalibrationProblem, geometry_prior
from ...transforms import euler_from_matrix

__all__ = ["DEFAULT_ROTATION_WEIGHT", "DEFAULT_PRIOR", "split_by_ids", "build_problems", "tool_frame_summary"]

#: mm per rad: a 6-D probe measures ~0.02 mm and ~0.01 deg (1.7e-4 rad), 0.02 / 1.7e-4 ~ 100
DEFAULT_ROTATION_WEIGHT = 100.0
#: (mm, deg): a weak prior, a few times the machining and assembly tolerances of an arm
DEFAULT_PRIOR = (1.0, 0.5)


def _id_list(values) -> list:
    """Pose ids from option values (comma or space separated; ``@FILE`` reads them from a file)."""
    from pathlib import Path

    out = []
    for v in values or ():
        text = Path(v[1:]).read_text(encoding="utf-8") if str(v).startswith("@") else str(v)
        out += [s for s in text.replace(",", " ").split() if s]
    return out


def split_by_ids(pose_ids, train_ids=(), holdout_ids=()) -> tuple:
    """(train indices, held-out indices, notes) of a given protocol.

    pose_ids: the file's pose ids (N,). train_ids / holdout_ids: option values (see
    :func:`_id_list`); with one list only, the other is every remaining pose. An unknown id, a
    duplicate or an id in both lists raises ``ValueError``.
    """
    ids = [str(p) for p in pose_ids]
    index = {p: i for i, p in enumerate(ids)}
    lists = {}
    for what, values in (("--train-ids", train_ids), ("--holdout-ids", holdout_ids)):
        got = _id_list(values)
        unknown = [p for p in got if p not in index]
        if unknown:
            raise ValueError(f"{what}: pose id(s) not in the measurement file: {', '.join(unknown[:10])}"
                             f"{' ...' if len(unknown) > 10 else ''} (the file has {', '.join(ids[:5])} ...)")
        dup = sorted({p for p in got if got.count(p) > 1})
        if dup:
            raise ValueError(f"{what}: pose id(s) given twice: {', '.join(dup)}")
        lists[what] = [index[p] for p in got] if values else None
    tr, ho = lists["--train-ids"], lists["--holdout-ids"]
    if tr is None and ho is None:
        raise ValueError("split_by_ids: give train ids, held-out ids or both")
    if tr is None:
        tr = [i for i in range(len(ids)) if i not in set(ho)]
    if ho is None:
        ho = [i for i in range(len(ids)) if i not in set(tr)]
    both = sorted(set(tr) & set(ho))
    if both:
        raise ValueError(f"pose id(s) in both --train-ids and --holdout-ids: {', '.join(ids[i] for i in both)}")
    unused = len(ids) - len(tr) - len(ho)
    notes = [f"{unused} pose(s) of the file in neither list (not used)"] if unused else []
    return np.array(sorted(tr), dtype=int), np.array(sorted(ho), dtype=int), notes


def _elastic_words(elastic) -> str:
    return "; joint compliance under gravity (" + ("mass model" if not elastic.lumped else
                                                   "lumped gravity parameters") + ")"


def build_problems(nominal, meas, train, *, free_names, sigma_mm, tool=None, use_orientation: bool = True,
                   rotation_weight: float | None = None, prior=None, elastic=None) -> dict:
    """The calibration problems of the training poses ``train`` of ``meas``.

    tool: initial target point (3,) [mm] in the flange frame. use_orientation: use the file's
    orientations when it has them. rotation_weight: mm per rad (default
    :data:`DEFAULT_ROTATION_WEIGHT`). prior: ``(sigma_mm, sigma_deg)`` of a Gaussian prior on
    the geometry around nominal, or ``None``. elastic: an
    :class:`~robocal.calib.elastic.ElasticModel` (3-D and 6-D files) or ``None``.

    Returns ``{problem0, problem, six_d, description, rotation_weight, notes}``.
    """
    point0 = (0.0, 0.0, 0.0) if tool is None else tuple(float(v) for v in tool)
    targets = [Target(t, point=point0) for t in meas.targets]
    q, p = meas.joints[train], meas.points[train]
    six_d = use_orientation and meas.rotations is not None
    prior_rad = None if prior is None else (float(prior[0]), math.radians(float(prior[1])))
    notes = []
    if not six_d:
        gp = None if prior_rad is None or not free_names else geometry_prior(nominal, free_names, *prior_rad)
        p0 = CalibrationProblem(nominal, q, targets, p, free=[], base_initial="fit", point_sigma_mm=sigma_mm)
        p1 = CalibrationProblem(nominal, q, targets, p, free=free_names, base_initial="fit", point_sigma_mm=sigma_mm,
                                geometry_prior=gp, elastic=elastic)
        if meas.rotations is not None:
            notes.append("the file's orientation columns were NOT used (--no-orientation)")
        what = f"positions of {len(targets)} target(s)"
        if elastic is not None:
            what += _elastic_words(elastic)
        return {"problem0": p0, "problem": p1, "six_d": False, "rotation_weight": None, "notes": notes,
                "description": what}
    w = DEFAULT_ROTATION_WEIGHT if rotation_weight is None else float(rotation_weight)
    if not w > 0:
        raise ValueError(f"--rotation-weight must be a positive number of mm per rad, got {rotation_weight}")
    R = meas.rotations[train]
    p0 = PoseCalibrationProblem(nominal, q, p, R, targets=targets, free=[], point_sigma_mm=sigma_mm,
                                rotation_weight=w)
    p1 = PoseCalibrationProblem(nominal, q, p, R, targets=targets, free=free_names, point_sigma_mm=sigma_mm,
                                rotation_weight=w, prior_sigma=prior_rad, base_initial=p0.base_initial[0],
                                tool_rotation0=p0.tool_block.initial[0, :3, :3], elastic=elastic)
    if p0.base_start == "orientations":
        notes.append("the measured points are (nearly) collinear: the base frame and the tool rotation were started "
                     "from the measured orientations")
    what = "the tool frame (6 DoF)" if len(targets) == 1 else f"{len(targets)} target point(s) + tool rotation"
    if elastic is not None:
        what += _elastic_words(elastic)
    return {"problem0": p0, "problem": p1, "six_d": True, "rotation_weight": w, "notes": notes,
            "description": f"6-D: positions and orientations, rotation weight {w:g} mm/rad; {what}"}


def tool_frame_summary(result, problem) -> dict | None:
    """The identified tool frame ``T_flange_measured`` of a 6-D problem: 4x4, rotation vector and
    ``rpy`` [rad], origin [mm], each with its standard deviation (NaN = held); ``None`` otherwise."""
    block = getattr(problem, "tool_block", None)
    if block is None:
        return None
    T = result.value(block)[0]
    idx = {n: i for i, n in enumerate(result.names)}
    std = [float(result.std[idx[n]]) if n in idx else float("nan") for n in block.names]
    return {"T_flange_measured": T, "rotvec_rad": result.values[[idx[n] for n in block.names[:3]]]
            if all(n in idx for n in block.names[:3]) else None,
            "rpy_rad": euler_from_matrix(T[:3, :3], "rpy"), "xyz_mm": T[:3, 3],
            "std_rotvec_rad": std[:3], "std_xyz_mm": std[3:], "variables": list(block.names)}
