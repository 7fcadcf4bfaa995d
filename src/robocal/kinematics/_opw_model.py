"""The canonical OPW model: its parameters and its forward kinematics (see
:mod:`robocal.kinematics.ik_analytic` for the frames and the relation to a robot model).

Lengths in mm, angles in rad.
"""

from __future__ import annotations
from ..errors import InputError

from dataclasses import dataclass, field

import numpy as np

from ..transforms import rot_y, rot_z

__all__ = ["NotAnalyticError", "OPWParameters", "opw_fk"]

TWO_PI = 2.0 * np.pi


class NotAnalyticError(InputError):
    """The robot model is not exactly of the OPW class; the message says which condition failed."""


@dataclass(frozen=True)
class OPWParameters:
    """OPW parameters of a robot model (see the module docstring for the frames).

    Lengths in mm, angles in rad. ``theta_opw = signs * q_model + offsets`` with
    ``q_model = coupling @ q`` (controller joints ``q``).
    """

    a1: float
    a2: float
    b: float
    c1: float
    c2: float
    c3: float
    c4: float
    offsets: np.ndarray          # (6,) OPW angle at q_model = 0
    signs: np.ndarray            # (6,) +-1
    T_world_base: np.ndarray     # (4, 4) OPW base frame in the world
    T_flange_ee: np.ndarray      # (4, 4) end effector (model's first) in the OPW flange frame
    coupling: np.ndarray         # (6, 6) q_model = coupling @ q
    limits: np.ndarray           # (6, 2) controller joint limits
    name: str = ""
    coupling_inv: np.ndarray = field(init=False, repr=False)
    integer_columns: np.ndarray = field(init=False, repr=False)  # (6,) adding 2 pi to q_j is a symmetry

    def __post_init__(self):
        C = np.asarray(self.coupling, dtype=float)
        object.__setattr__(self, "coupling_inv", np.linalg.inv(C))
        object.__setattr__(self, "integer_columns", np.all(np.abs(C - np.round(C)) < 1e-12, axis=0))

    def opw_angles(self, q) -> np.ndarray:
        """OPW angles (..., 6) from controller joints (..., 6)."""
        qm = np.asarray(q, dtype=float) @ self.coupling.T
        return self.signs * qm + self.offsets

    def controller_joints(self, theta) -> np.ndarray:
        """Controller joints (..., 6) from OPW angles (..., 6) (no wrapping)."""
        qm = (np.asarray(theta, dtype=float) - self.offsets) * self.signs
        return qm @ self.coupling_inv.T

    def fk(self, q) -> np.ndarray:
        """``T_world_ee`` (..., 4, 4) from controller joints (..., 6) through the OPW model."""
        return self.T_world_base @ opw_fk(self, self.opw_angles(q)) @ self.T_flange_ee


def opw_fk(params: OPWParameters, theta) -> np.ndarray:
    """Pose of the OPW flange in the OPW base frame, (..., 4, 4), from OPW angles (..., 6)."""
    t = np.asarray(theta, dtype=float)
    P = params
    R1 = rot_z(t[..., 0])
    R13 = rot_y(t[..., 1] + t[..., 2])
    R03 = R1 @ R13
    # Points in the arm plane frame (after Rz(t1)).
    s2, c2_ = np.sin(t[..., 1]), np.cos(t[..., 1])
    elbow = np.stack([P.a1 + P.c2 * s2, np.zeros_like(s2), P.c1 + P.c2 * c2_], axis=-1)
    wc1 = elbow + (R13 @ np.array([P.a2, P.b, P.c3]))
    R36 = rot_z(t[..., 3]) @ rot_y(t[..., 4]) @ rot_z(t[..., 5])
    R = R03 @ R36
    p = (R1 @ wc1[..., None])[..., 0] + P.c4 * R[..., :, 2]
    T = np.zeros(t.shape[:-1] + (4, 4))
    T[..., :3, :3] = R
    T[..., :3, 3] = p
    T[..., 3, 3] = 1.0
    return T



def wrap(x):
    """Angles wrapped to [-pi, pi)."""
    return (np.asarray(x) + np.pi) % TWO_PI - np.pi
