"""A stable fingerprint of a robot model's kinematics (which files belong to which model)."""

from __future__ import annotations

import hashlib

import numpy as np

from .model import RobotModel

__all__ = ["model_fingerprint"]


def model_fingerprint(model: RobotModel) -> str:
    """Hex SHA-256 (first 16 digits) of everything forward kinematics depends on.

    Covers the model kind, every link's convention, parent, axis and parameter values, the joint
    coupling, the joint limits, the base frame and the end effectors. Values are rounded to 1e-9
    (mm / rad), so a model re-read from its file gets the same fingerprint; any calibration change
    gives a different one. The name is not part of it (a renamed copy is the same kinematics).
    """
    h = hashlib.sha256()

    def add(*items):
        for it in items:
            if isinstance(it, np.ndarray) or isinstance(it, (list, tuple)) and it and not isinstance(it[0], str):
                a = np.round(np.asarray(it, dtype=float), 9) + 0.0   # + 0.0: no negative zeros
                h.update(a.tobytes())
            else:
                h.update(str(it).encode("utf-8"))
            h.update(b"|")

    add(model.kind, model.n_joints)
    for L in model.links:
        add(L.joint_type, L.convention, L.parent, tuple(L.axis))
        for name in sorted(L.params):
            add(name, np.array([L.params[name]]))
    add(model.coupling, model.limits, model.T_world_base)
    for e in model.end_effectors:
        add(e.name, e.link, e.T_link_ee)
    return h.hexdigest()[:16]
