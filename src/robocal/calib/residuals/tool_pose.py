"""6-D pose measurements of a tool frame: its origin (a point) and its orientation.

A 6-D instrument (a laser tracker with a 6-D probe, a three-reflector nest fitted to a frame, an
optical tracker) measures ``T_instrument_measured = T_inst_base(station) . T_base_ee(q) . T_tool``
with ``T_tool`` a :class:`~robocal.calib.blocks.ToolFrame` (flange -> measured frame). Two
residual blocks read it:

* :class:`ToolPointResidual` -- the origin, ``(p_measured - p_predicted) / sigma`` (kind ``point``);
* :class:`ToolRotationResidual` -- ``log(R_measured R_predicted^T) * weight / sigma`` (kind
  ``rotation``), ``weight`` in mm per rad.

Derivatives: the tool frame is left-perturbed in the end-effector frame, ``T_tool <- [exp(w) | v]
T_tool``, so its origin ``t`` moves by ``R_inst_ee (w x t + v)`` and the predicted orientation by
the instrument-frame rotation ``R_inst_ee w``.
"""

from __future__ import annotations

import numpy as np

from ...transforms import skew, so3_log
from ..blocks.manifolds import so3_right_jacobian_inverse
from ..blocks.points import TargetPoints
from ..errors import ProblemError
from .base import ResidualBlock
from .chain import TargetChain
from .points import point_distances
from .rotation import deflected_rotation

__all__ = ["ToolPointResidual", "ToolRotationResidual", "tool_chain"]


def tool_chain(model, q, geometry, frames, tool, stations=None, deflection=None) -> TargetChain:
    """The :class:`TargetChain` of the tool's origin: one point on the tool's end effector (its
    value comes from the tool block at evaluation time; the chain's own target block is a
    placeholder that is never a problem variable). ``deflection``: optional
    :class:`~robocal.calib.residuals.deflection.Deflection` (the elastic model, docs/elastic.md)."""
    origin = TargetPoints([tool.name], tool.initial[0, :3, 3][None], name=f"{tool.name}.origin",
                          end_effectors=[tool.end_effector], free=False)
    return TargetChain(model, q, geometry, frames, origin, stations=stations, deflection=deflection)


def _origin(ev, tool):
    return ev[tool][0, :3, 3][None]


class _ToolPose(ResidualBlock, register=False):
    """Shared set-up: the chain of the tool origin and the tool block (and the chain's deflection
    blocks when it has a deflection)."""

    def __init__(self, chain: TargetChain, tool, row_poses, sigma):
        if chain.n_points != 1:
            raise ProblemError(f"{type(self).__name__}: the chain must carry exactly the tool origin")
        self.chain, self.tool = chain, tool
        self.deflection = chain.deflection
        extra = () if self.deflection is None else self.deflection.blocks
        super().__init__((chain.geometry, chain.frames, tool) + extra, row_poses, sigma)

    def _predict(self, ev, jacobian):
        """(points (N, 1, 3), rotation of the end effector in the instrument frame (N, 3, 3));
        the chain's Jacobians as asked (with a deflection: to first order in the lateral
        rotations, as the points)."""
        c = self.chain
        d = self.deflection
        elastic = None if d is None else tuple(ev[b] for b in d.blocks)
        others = () if d is None else tuple(ev.wants(b) for b in d.blocks)
        if jacobian:
            wants = (ev.wants(c.geometry), ev.wants(c.frames), True) + others
        else:
            wants = (False, False, True) + tuple(False for _ in others)
        out = c.predict(ev[c.geometry], ev[c.frames], _origin(ev, self.tool), c.q, c.stations, wants,
                        elastic=elastic)
        R_inst_ee = out.jac[c.targets][:, 0, :, :3]  # d p / d origin = R_inst_ee
        return out, R_inst_ee


class ToolPointResidual(_ToolPose):
    """The measured origin of the tool frame: 3 rows per measured pose (NaN rows = not measured).

    chain: :func:`tool_chain`; tool: the :class:`~robocal.calib.blocks.ToolFrame`; measured (N, 3)
    [mm] in the instrument frame; sigma: per coordinate [mm] (``None``: weight 1).
    """

    kind = "point"

    def __init__(self, chain: TargetChain, tool, measured, sigma: float | None = None):
        measured = np.asarray(measured, dtype=float).reshape(len(chain.q), 3)
        self.measured = measured
        self.mask = np.all(np.isfinite(measured), axis=1)
        super().__init__(chain, tool, np.repeat(np.flatnonzero(self.mask), 3), sigma)

    def evaluate(self, ev, jacobian):
        out, R = self._predict(ev, jacobian)
        m, w = self.mask, self.weight
        r = ((self.measured - out.points[:, 0]) * w)[m].ravel()
        if not jacobian:
            return r, None
        c = self.chain
        jac = {b: J[:, 0][m].reshape(-1, J.shape[-1]) * w for b, J in out.jac.items() if b is not c.targets}
        if ev.wants(self.tool):
            t = _origin(ev, self.tool)[0]
            Jt = np.concatenate([R @ -skew(t), R], axis=2)  # (N, 3, 6): rotation then origin
            jac[self.tool] = Jt[m].reshape(-1, 6) * w
        return r, jac

    def errors(self, r):
        """Distances [mm] between measured and predicted origins."""
        return point_distances(r, self.sigma)

    @classmethod
    def example(cls, rng):
        out = []
        for chain, tool in _example_chains(rng):
            meas = rng.normal(0, 1000, (5, 3))
            meas[2] = np.nan
            out.append(cls(chain, tool, meas, sigma=0.05))
        return out


class ToolRotationResidual(_ToolPose):
    """The measured orientation of the tool frame: 3 rows per pose.

    ``r = log(R_measured R_predicted^T) * weight_mm_per_rad / sigma`` with ``R_predicted =
    R_inst_base R_base_ee(q) R_tool``. measured (N, 3, 3) in the instrument frame;
    weight_mm_per_rad: how many mm one rad counts (point sigma / rotation sigma).
    """

    kind = "rotation"

    def __init__(self, chain: TargetChain, tool, measured, *, weight_mm_per_rad: float = 1000.0,
                 sigma: float | None = None):
        N = len(chain.q)
        self.measured = np.asarray(measured, dtype=float)
        if self.measured.shape != (N, 3, 3):
            raise ProblemError(f"rotations: expected shape ({N}, 3, 3), got {self.measured.shape}")
        if not weight_mm_per_rad > 0:
            raise ProblemError(f"rotation weight must be positive mm per rad, got {weight_mm_per_rad}")
        self.rotation_weight = float(weight_mm_per_rad)
        super().__init__(chain, tool, np.repeat(np.arange(N), 3), sigma)

    def evaluate(self, ev, jacobian):
        c = self.chain
        R_tool = ev[self.tool][0, :3, :3]
        Rb = ev[c.frames][c.stations, :3, :3]
        ee = int(c.ee_of_target[0])
        jac_base = {}
        if self.deflection is not None:  # torsion at the deflected joints, then exp(Phi) (rotation.py)
            R_base, jac_base = deflected_rotation(c.model, c.q, ee, c.geometry, self.deflection, ev, jacobian)
        elif jacobian and ev.wants(c.geometry):
            T_all, ptw, _, masks = c.model.kinematics_with(c.q, ev[c.geometry], np.eye(4), [ee])
            R_base = T_all[:, 0, :3, :3]
            jac_base[c.geometry] = (ptw[:, :3] * masks[0])[..., c.geometry.index]
        else:
            R_base = c.model.kinematics_with(c.q, ev[c.geometry], np.eye(4), [ee])[0][:, 0, :3, :3]
        R_ie = Rb @ R_base
        R_pred = R_ie @ R_tool
        err = so3_log(self.measured @ np.swapaxes(R_pred, 1, 2))
        k = self.weight * self.rotation_weight
        r = (err * k).ravel()
        if not jacobian:
            return r, None
        Jr_inv = so3_right_jacobian_inverse(err)
        N = len(c.q)
        jac = {b: (Jr_inv @ (Rb @ J)).reshape(N * 3, -1) * k for b, J in jac_base.items()}
        if ev.wants(c.frames):
            G = c.frames.n_frames
            Jf = np.zeros((N, 3, G, 6))
            Jf[np.arange(N), :, c.stations, :3] = Jr_inv
            jac[c.frames] = Jf.reshape(N * 3, 6 * G) * k
        if ev.wants(self.tool):
            Jt = np.zeros((N, 3, 6))
            Jt[:, :, :3] = Jr_inv @ R_ie
            jac[self.tool] = Jt.reshape(N * 3, 6) * k
        return r, jac

    @classmethod
    def example(cls, rng):
        from ...transforms import so3_exp

        return [cls(chain, tool, so3_exp(rng.normal(0, 1, (5, 3))), weight_mm_per_rad=100.0, sigma=0.1)
                for chain, tool in _example_chains(rng)]


def _example_chains(rng):
    """[(tool chain, tool)]: rigid, elastic (joint compliance) and elastic with lateral compliance."""
    from .examples import example_chain, example_elastic_chain, example_frames

    out = []
    for factory, kw in ((example_chain, {}), (example_elastic_chain, {}), (example_elastic_chain, {"lateral": True})):
        base = factory(rng, n_poses=5, n_stations=2, **kw)
        tool = _example_tool(rng, example_frames)
        out.append((tool_chain(base.model, base.q, base.geometry, base.frames, tool, stations=base.stations,
                               deflection=base.deflection), tool))
    return out


def _example_tool(rng, example_frames):
    from ..blocks.tool import ToolFrame

    T = example_frames(rng, 1)[0]
    T[:3, 3] /= 10.0  # a tool of ~100 mm
    return ToolFrame(T, end_effector="side")
