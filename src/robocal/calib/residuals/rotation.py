"""Measured end-effector orientations (6-D pose measurements: a tracker with 3 reflectors, a 6-D probe)."""

from __future__ import annotations

import numpy as np

from ...transforms import so3_log
from ..blocks.manifolds import so3_right_jacobian_inverse
from ..errors import ProblemError
from .base import ResidualBlock

__all__ = ["RotationResidual"]


class RotationResidual(ResidualBlock):
    """``r = log(R_measured R_predicted^T) * weight_mm_per_rad / sigma``, 3 rows per pose.

    ``R_predicted = R_inst_base(station) R_base_ee(q; params)`` (small rotation error in the
    instrument frame). A rotation ``d`` of the prediction changes the error by ``-Jr^-1(err) d``
    (the inverse right Jacobian of SO(3)), so the prediction derivative is ``Jr^-1 dR``.

    model, q (N, n_ctrl), geometry (RobotGeometry), frames (StationFrames), measured (N, 3, 3);
    end_effector: name or index (default the first); stations (N,); weight_mm_per_rad: how many mm
    one rad counts (set it to sigma_point / sigma_rotation); sigma [mm] as for points.
    """

    kind = "rotation"

    def __init__(self, model, q, geometry, frames, measured, *, end_effector=None, stations=None,
                 weight_mm_per_rad: float = 1000.0, sigma: float | None = None):
        self.q = np.asarray(q, dtype=float)
        N = len(self.q)
        self.measured = np.asarray(measured, dtype=float)
        if self.measured.shape != (N, 3, 3):
            raise ProblemError(f"rotations: expected shape ({N}, 3, 3), got {self.measured.shape}")
        self.model, self.geometry, self.frames = model, geometry, frames
        self.ee = model.end_effector_index(end_effector)
        self.stations = np.zeros(N, dtype=int) if stations is None else np.asarray(stations, dtype=int)
        self.rotation_weight = float(weight_mm_per_rad)
        super().__init__((geometry, frames), np.repeat(np.arange(N), 3), sigma)

    def evaluate(self, ev, jacobian):
        T_all, ptw, _, masks = self.model.kinematics_with(self.q, ev[self.geometry], np.eye(4), [self.ee])
        Rb = ev[self.frames][self.stations, :3, :3]
        R_pred = Rb @ T_all[:, 0, :3, :3]
        err = so3_log(self.measured @ np.swapaxes(R_pred, 1, 2))  # small rotation, instrument frame
        w, rw = self.weight, self.rotation_weight
        r = (err * rw).ravel() * w
        if not jacobian:
            return r, None
        Jr_inv = so3_right_jacobian_inverse(err)
        N = len(self.q)
        jac = {}
        if ev.wants(self.geometry):
            Jg = (ptw[:, :3] * masks[0])[..., self.geometry.index]
            jac[self.geometry] = ((Jr_inv @ (Rb @ Jg)) * rw).reshape(N * 3, -1) * w
        if ev.wants(self.frames):
            G = self.frames.n_frames
            Jf = np.zeros((N, 3, G, 6))
            Jf[np.arange(N), :, self.stations, :3] = Jr_inv
            jac[self.frames] = (Jf * rw).reshape(N * 3, 6 * G) * w
        return r, jac

    @classmethod
    def example(cls, rng):
        from ...transforms import so3_exp
        from .examples import example_chain

        chain = example_chain(rng, n_poses=5, n_stations=2)
        meas = so3_exp(rng.normal(0, 1, (5, 3)))
        return cls(chain.model, chain.q, chain.geometry, chain.frames, meas, end_effector="side",
                   stations=chain.stations, weight_mm_per_rad=100.0, sigma=0.1)
