"""Arm configuration of a 6R robot with a spherical wrist, as controllers define it.

A controller told a Cartesian target also needs to know *which* of the inverse-kinematics
solutions to take. Controllers describe the choice by three joint-space properties and by the
turns of joints whose range exceeds a full turn:

- shoulder: the wrist centre lies in front of axis 1 or behind it ("overhead"/"back"),
- elbow: the elbow angle ``gamma`` (0 with the arm stretched from axis 2 to the wrist centre) is
  positive ("up": KUKA status bit 1 set, ABB "wrist centre in front of the lower arm", FANUC ``U``)
  or negative,
- wrist: the sign of controller joint 5.

These are computed on the *nominal* (OPW-class) model, the one the controller runs
(:mod:`robocal.kinematics.ik_analytic` for the frames). :func:`ik_candidates` lists every
closed-form solution within the joint limits, including the other turns (``q +- 2 pi``) of joints
whose range allows them, so a controller's choice can be made by filtering.
"""

from __future__ import annotations

import itertools

import numpy as np

from ._opw_model import wrap
from .ik_analytic import _params_of, ik_analytic

__all__ = ["arm_signature", "ik_candidates"]


def arm_signature(model, q) -> np.ndarray:
    """Shoulder, elbow and wrist of joint vectors ``q`` (N, 6) [rad] on the OPW-class ``model``.

    Returns (N, 3) bool: ``back`` (wrist centre behind axis 1), ``elbow_down`` (elbow angle
    ``gamma < 0``), ``wrist_negative`` (controller joint 5 < 0). Raises
    :class:`~robocal.kinematics.ik_analytic.NotAnalyticError` for a model not of the OPW class.
    """
    P = _params_of(model)
    q = np.atleast_2d(np.asarray(q, dtype=float))
    theta = P.opw_angles(q)
    t2, t3 = theta[:, 1], theta[:, 2]
    xs = P.a1 + P.c2 * np.sin(t2) + P.c3 * np.sin(t2 + t3) + P.a2 * np.cos(t2 + t3)
    gamma = wrap(t3 + np.arctan2(P.a2, P.c3))
    return np.stack([xs < 0.0, gamma < 0.0, q[:, 4] < 0.0], axis=1)


def ik_candidates(model, T_base_ee) -> list:
    """Every closed-form IK solution within the joint limits, per pose.

    T_base_ee: (N, 4, 4) poses [mm] of the model's first end effector (in the model's world
    frame). Returns a list of N arrays (M_i, 6) [rad]: the 8 branches of
    :func:`~robocal.kinematics.ik_analytic.ik_analytic` and, for every joint whose range holds
    another turn, the solutions with ``q_j +- 2 pi`` (duplicates removed).
    """
    P = _params_of(model)
    q8, valid = ik_analytic(P, np.asarray(T_base_ee, dtype=float).reshape(-1, 4, 4))
    lo, hi = P.limits[:, 0], P.limits[:, 1]
    shifts = np.array([0.0, -2 * np.pi, 2 * np.pi, -4 * np.pi, 4 * np.pi])
    out = []
    for qs, ok in zip(q8, valid):
        found = []
        for q in qs[ok]:
            options = []
            for j in range(6):
                if P.integer_columns[j]:
                    vals = q[j] + shifts
                    options.append([v for v in vals if lo[j] - 1e-9 <= v <= hi[j] + 1e-9])
                else:
                    options.append([q[j]] if lo[j] - 1e-9 <= q[j] <= hi[j] + 1e-9 else [])
            for combo in itertools.product(*options):
                c = np.array(combo)
                if not any(np.max(np.abs(c - f)) < 1e-9 for f in found):
                    found.append(c)
        out.append(np.array(found).reshape(-1, 6))
    return out
