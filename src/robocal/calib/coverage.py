"""Coverage gates: does a campaign support the calibrated model over the robot's working range?

A calibration fits the poses it was given, and a held-out split drawn from the same poses shares
their blind spots: a campaign where joint 4 never moved claims 0.04 mm held-out error while the
model is 0.7 mm off elsewhere. These gates judge the campaign itself, by name:

* a joint that moved less than :data:`MIN_JOINT_SPAN_DEG` over the calibration poses (while turning
  it would move a measured target: a reflector on the joint-6 axis does not need joint 6);
* two joints locked together (|correlation| of their values above :data:`LOCKED_CORRELATION`);
* fewer identified parameters than a full campaign identifies with the same targets (the
  identifiability of :func:`robocal.calib.plan.calibration_identifiability` on poses spread over
  the working range);
* a held-out split inside the same narrow range (named in the joint's reason).

Each failure is a reason of a :class:`~robocal.calib.sanity.Verdict` (status failed, exit 3 at the
command line); :func:`joint_coverage` is the table the report shows.
"""

from __future__ import annotations

import math

import numpy as np

from .sanity import Verdict

__all__ = ["MIN_JOINT_SPAN_DEG", "MIN_JOINT_SPAN_FRACTION", "MIN_LEVER_MM_PER_RAD", "LOCKED_CORRELATION",
           "REFERENCE_POSES", "joint_coverage", "coverage_verdict"]

#: A revolute joint must move at least this much over the calibration poses [deg].
MIN_JOINT_SPAN_DEG = 10.0
#: A prismatic joint must move at least this fraction of its range.
MIN_JOINT_SPAN_FRACTION = 0.05
#: A joint whose turning moves no measured target by at least this [mm per rad] is not judged.
MIN_LEVER_MM_PER_RAD = 1.0
#: Two moving joints whose values correlate beyond this (in absolute value) are locked together.
LOCKED_CORRELATION = 0.99
#: Poses of the full reference campaign the identified set is compared with.
REFERENCE_POSES = 60


def joint_coverage(model, q_train, q_holdout=None) -> list:
    """Per controller joint: ``{joint, unit, min, max, span, range, fraction, holdout_min,
    holdout_max}`` of the calibration (and held-out) poses, in deg (revolute) or mm, ``range`` the
    joint's working range (its limits; None when unlimited), ``fraction`` = span / range (or None)."""
    q_train = np.atleast_2d(np.asarray(q_train, dtype=float))
    pris = model.prismatic_joints
    rows = []
    for k, name in enumerate(model.controller_joints):
        s = 1.0 if pris[k] else 180.0 / math.pi
        lo, hi = model.limits[k] * s
        v = q_train[:, k] * s
        rng = float(hi - lo) if np.isfinite(hi - lo) else None
        row = {"joint": name, "unit": "mm" if pris[k] else "deg", "min": float(v.min()), "max": float(v.max()),
               "span": float(v.max() - v.min()), "range": rng,
               "fraction": float((v.max() - v.min()) / rng) if rng else None}
        if q_holdout is not None and len(q_holdout):
            h = np.atleast_2d(q_holdout)[:, k] * s
            row["holdout_min"], row["holdout_max"] = float(h.min()), float(h.max())
        rows.append(row)
    return rows


#: Poses per block in :func:`_levers` (two FK results of a block: ~2 MB).
_LEVER_BLOCK = 8192


def _levers(model, q, targets_mm, ee_of_target) -> np.ndarray:
    """(n_ctrl,) median over poses of the largest target displacement per unit joint motion [mm/rad | mm/mm]."""
    eps = 1e-6
    m = model.replace(T_world_base=np.eye(4))
    n = model.n_joints
    ees = sorted(set(ee_of_target))
    worst = np.zeros((n, len(q)))
    for first in range(0, len(q), _LEVER_BLOCK):  # blocks of poses: bounded memory on a big campaign
        qb = q[first:first + _LEVER_BLOCK]
        base = [m.fk(qb, e) for e in ees]
        for k in range(n):
            dq = qb.copy()
            dq[:, k] += eps
            w = worst[k, first:first + len(qb)]
            for j, e in enumerate(ees):
                T0, T1 = base[j], m.fk(dq, e)
                for t, ee in zip(targets_mm, ee_of_target):
                    if ee != e:
                        continue
                    p0 = T0[:, :3, 3] + T0[:, :3, :3] @ t
                    p1 = T1[:, :3, 3] + T1[:, :3, :3] @ t
                    np.maximum(w, np.linalg.norm(p1 - p0, axis=1) / eps, out=w)
    return np.array([float(np.median(worst[k])) for k in range(n)])


def coverage_verdict(model, q_train, q_holdout=None, *, targets_mm=((0.0, 0.0, 0.0),), ee_of_target=(0,),
                     identified=None, free=None, reference_q=None) -> Verdict:
    """The coverage gates of a calibration of ``model`` from the poses ``q_train`` (N, n) [rad | mm].

    q_holdout: the held-out poses (M, n) or None; targets_mm: (K, 3) the fitted target points in
    their end effectors' frames [mm] (the levers of the joints, the reference campaign's target);
    identified: names of the identified model parameters (None: the parameter gate is skipped);
    free: the model parameters the calibration was asked for; reference_q: the full reference
    campaign (R, n) (default: none, the parameter gate is skipped).
    """
    q_train = np.atleast_2d(np.asarray(q_train, dtype=float))
    checks: dict = {}
    reasons = []
    cov = joint_coverage(model, q_train, q_holdout)
    targets = np.atleast_2d(np.asarray(targets_mm, dtype=float))
    levers = _levers(model, q_train, targets, list(ee_of_target))
    pris = model.prismatic_joints
    narrow = []
    for k, row in enumerate(cov):
        limit = MIN_JOINT_SPAN_FRACTION * (row["range"] or 0.0) if pris[k] else MIN_JOINT_SPAN_DEG
        matters = levers[k] >= MIN_LEVER_MM_PER_RAD
        passed = (not matters) or row["span"] >= limit
        checks[f"coverage_{row['joint']}"] = {"value": row["span"], "limit": float(limit), "unit": row["unit"],
                                              "passed": bool(passed)}
        if not passed:
            narrow.append(k)
            held = ""
            if "holdout_min" in row and row["holdout_max"] - row["holdout_min"] < limit:
                held = (f"; the held-out poses span the same narrow range ({row['holdout_min']:.4g} .. "
                        f"{row['holdout_max']:.4g} {row['unit']}), so their error says nothing about the rest")
            reasons.append(
                f"joint {row['joint']} moved only {row['span']:.3g} {row['unit']} over the calibration poses "
                f"({row['min']:.4g} .. {row['max']:.4g} of its {row['range'] or float('inf'):.4g} {row['unit']} range; limit "
                f"{limit:.3g} {row['unit']}): the model is not supported over the robot's working range{held}; "
                f"measure with {row['joint']} spread over its range")
    moving = [k for k in range(len(cov)) if k not in narrow and levers[k] >= MIN_LEVER_MM_PER_RAD
              and np.std(q_train[:, k]) > 0]
    worst = 0.0
    for a in range(len(moving)):
        for b in range(a + 1, len(moving)):
            i, j = moving[a], moving[b]
            c = float(np.corrcoef(q_train[:, i], q_train[:, j])[0, 1])
            worst = max(worst, abs(c))
            if abs(c) > LOCKED_CORRELATION:
                ni, nj = model.controller_joints[i], model.controller_joints[j]
                reasons.append(f"joints {ni} and {nj} moved locked together (correlation {c:+.4f}, limit "
                               f"{LOCKED_CORRELATION:g}): their parameters cannot be told apart and the model is not "
                               f"supported where they move independently; measure with {ni} and {nj} moved apart")
    checks["locked_joints"] = {"value": worst, "limit": LOCKED_CORRELATION, "unit": "|correlation|",
                               "passed": worst <= LOCKED_CORRELATION}
    if identified is not None and reference_q is not None:
        from .plan import calibration_identifiability

        ref, _, _ = calibration_identifiability(model, np.asarray(reference_q, dtype=float), tool=tuple(targets[0]),
                                             free=free)
        names = set(model.params.names)
        want = [n for n in ref.identifiable if n in names]
        missing = [n for n in want if n not in set(identified)]
        checks["identified_parameters"] = {"value": float(len(want) - len(missing)), "limit": float(len(want)),
                                           "unit": "parameters", "passed": not missing}
        if missing:
            shown = ", ".join(missing[:8]) + (f" and {len(missing) - 8} more" if len(missing) > 8 else "")
            reasons.append(f"only {len(want) - len(missing)} of the {len(want)} parameters a full campaign identifies "
                           f"were identified (not: {shown}): the campaign does not determine the model the robot "
                           "file asks for; measure poses spread over every joint's range")
    return Verdict(tuple(reasons), checks)
