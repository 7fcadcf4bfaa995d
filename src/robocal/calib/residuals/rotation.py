"""Measured end-effector orientations (6-D pose measurements: a tracker with 3 reflectors, a 6-D probe)."""

from __future__ import annotations

import numpy as np

from ...transforms import skew, so3_exp, so3_log
from ..blocks.manifolds import so3_right_jacobian_inverse
from ..errors import ProblemError
from .base import ResidualBlock

__all__ = ["RotationResidual", "deflected_rotation"]


def _left_jacobian(phi) -> np.ndarray:
    """Left Jacobian of SO(3) at rotation vectors phi (N, 3): (N, 3, 3)."""
    th = np.linalg.norm(phi, axis=-1)[:, None, None]
    K = skew(phi)
    small = th < 1e-6
    ths = np.where(small, 1.0, th)
    a = np.where(small, 0.5, (1.0 - np.cos(ths)) / ths**2)
    b = np.where(small, 1.0 / 6.0, (ths - np.sin(ths)) / ths**3)
    return np.eye(3) + a * K + b * (K @ K)


def deflected_rotation(model, q, ee, geometry, deflection, ev, jacobian):
    """The rotation (N, 3, 3) in the base frame of end effector ``ee`` (index) at joints ``q``
    (N, n_ctrl) with the ``deflection`` (torsion at the deflected joints, then ``exp(Phi)`` of the
    lateral rotations), and the rotation Jacobians (N, 3, size) in the base frame (a left rotation
    ``d`` of the result) of the geometry and deflection blocks the evaluation ``ev`` wants."""
    d = deflection
    values = {b: ev[b] for b in d.blocks}
    c, grav = values[d.compliance], values[d.gravity]
    dq, gt, tau_sel = d.deflections(q, c, grav)
    qm = q @ model.coupling.T + dq
    T_all, ptw, jtw, masks = d.model_joints.kinematics_with(qm, ev[geometry], np.eye(4), [ee])
    R = T_all[:, 0, :3, :3]
    carried = model._ee_ancestors[ee][model.moving].astype(float)  # (n_model,)
    jac = {}
    if jacobian and ev.wants(geometry):
        jac[geometry] = (ptw[:, :3] * masks[0])[..., geometry.index]
    W = jtw[:, :3, d.compliance.joints] * carried[d.compliance.joints]  # (N, 3, n_c) joint axes
    if jacobian:
        jj = d.jacobians(W[:, None], gt, tau_sel, c, ev.wants(d.compliance), ev.wants(d.gravity))
        jac.update({b: J[:, 0] for b, J in jj.items()})
    if d.lateral is not None:
        lat = d.lateral
        jl = lat.joints
        c_lat = values[lat].reshape(-1, 2)
        E = gt.lateral_axes[:, jl] * carried[jl][None, :, None, None]  # (N, n_l, 2, 3)
        M = gt.lateral_moments(d.gravity.theta(grav))[:, jl]
        Phi = np.einsum("nja,njai->ni", 1e-6 * c_lat[None] * M, E)
        Rx = so3_exp(Phi)
        R = Rx @ R  # a rotation d of R before the lateral one turns the result by Rx d
        jac = {b: Rx @ J for b, J in jac.items()}
        Jl = _left_jacobian(Phi)  # d exp(Phi) = [Jl dPhi] exp(Phi)
        if jacobian and ev.wants(lat):
            jac[lat] = Jl @ np.swapaxes((1e-6 * M[..., None] * E).reshape(len(R), -1, 3), 1, 2)
        if jacobian and ev.wants(d.gravity):
            Lb = gt.lateral_basis[:, jl] * (1e-6 * c_lat)[None, :, :, None, None]
            Jg = np.einsum("njabv,njai->nibv", Lb, E)
            Jg = d.gravity.variable_jacobian(Jg)
            jac[d.gravity] = jac.get(d.gravity, 0.0) + Jl @ Jg
    return R, jac


class RotationResidual(ResidualBlock):
    """``r = log(R_measured R_predicted^T) * weight_mm_per_rad / sigma``, 3 rows per pose.

    ``R_predicted = R_inst_base(station) R_base_ee(q; params)`` (small rotation error in the
    instrument frame). A rotation ``d`` of the prediction changes the error by ``-Jr^-1(err) d``
    (the inverse right Jacobian of SO(3)), so the prediction derivative is ``Jr^-1 dR``.

    model, q (N, n_ctrl), geometry (RobotGeometry), frames (StationFrames), measured (N, 3, 3);
    end_effector: name or index (default the first); stations (N,); weight_mm_per_rad: how many mm
    one rad counts (set it to sigma_point / sigma_rotation); sigma [mm] as for points;
    deflection: optional :class:`~robocal.calib.residuals.deflection.Deflection` (the same as the
    point chain's): the end effector turns with the deflected joints and the lateral rotations.
    """

    kind = "rotation"

    def __init__(self, model, q, geometry, frames, measured, *, end_effector=None, stations=None,
                 weight_mm_per_rad: float = 1000.0, sigma: float | None = None, deflection=None):
        self.q = np.asarray(q, dtype=float)
        N = len(self.q)
        self.measured = np.asarray(measured, dtype=float)
        if self.measured.shape != (N, 3, 3):
            raise ProblemError(f"rotations: expected shape ({N}, 3, 3), got {self.measured.shape}")
        self.model, self.geometry, self.frames = model, geometry, frames
        self.ee = model.end_effector_index(end_effector)
        self.stations = np.zeros(N, dtype=int) if stations is None else np.asarray(stations, dtype=int)
        self.rotation_weight = float(weight_mm_per_rad)
        self.deflection = deflection
        extra = () if deflection is None else deflection.blocks
        super().__init__((geometry, frames) + extra, np.repeat(np.arange(N), 3), sigma)

    def evaluate(self, ev, jacobian):
        if self.deflection is not None:
            R_base, jac_base = self._elastic(ev, jacobian)
            Jg = jac_base.pop(self.geometry, None)
        else:
            T_all, ptw, _, masks = self.model.kinematics_with(self.q, ev[self.geometry], np.eye(4), [self.ee])
            R_base, jac_base = T_all[:, 0, :3, :3], {}
            Jg = (ptw[:, :3] * masks[0])[..., self.geometry.index] if ev.wants(self.geometry) else None
        Rb = ev[self.frames][self.stations, :3, :3]
        R_pred = Rb @ R_base
        err = so3_log(self.measured @ np.swapaxes(R_pred, 1, 2))  # small rotation, instrument frame
        w, rw = self.weight, self.rotation_weight
        r = (err * rw).ravel() * w
        if not jacobian:
            return r, None
        Jr_inv = so3_right_jacobian_inverse(err)
        N = len(self.q)
        jac = {}
        if ev.wants(self.geometry):
            jac[self.geometry] = ((Jr_inv @ (Rb @ Jg)) * rw).reshape(N * 3, -1) * w
        for blk, Jb in jac_base.items():
            jac[blk] = ((Jr_inv @ (Rb @ Jb)) * rw).reshape(N * 3, -1) * w
        if ev.wants(self.frames):
            G = self.frames.n_frames
            Jf = np.zeros((N, 3, G, 6))
            Jf[np.arange(N), :, self.stations, :3] = Jr_inv
            jac[self.frames] = (Jf * rw).reshape(N * 3, 6 * G) * w
        return r, jac

    def _elastic(self, ev, jacobian):
        return deflected_rotation(self.model, self.q, self.ee, self.geometry, self.deflection, ev, jacobian)

    @classmethod
    def example(cls, rng):
        from ...transforms import so3_exp
        from .examples import example_chain

        from .examples import example_elastic_chain

        out = []
        for factory, kw in ((example_chain, {}), (example_elastic_chain, {}), (example_elastic_chain, {"lateral": True})):
            chain = factory(rng, n_poses=5, n_stations=2, **kw)
            meas = so3_exp(rng.normal(0, 1, (5, 3)))
            out.append(cls(chain.model, chain.q, chain.geometry, chain.frames, meas, end_effector="side",
                           stations=chain.stations, weight_mm_per_rad=100.0, sigma=0.1, deflection=chain.deflection))
        return out
