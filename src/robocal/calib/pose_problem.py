"""The 6-D calibration problem: measured positions *and* orientations of a tool frame.

``PoseCalibrationProblem(model, q, points, rotations, ...)`` (docs/calibration.md, "6-D
measurements") builds

Parameter blocks (state ``PoseState(params, bases, tool)``, or ``(params, bases, targets, tool)``
with several target points)
    ``geometry``  :class:`~robocal.calib.blocks.RobotGeometry` (optionally with a weak Gaussian
                  prior around the nominal values);
    ``base``      :class:`~robocal.calib.blocks.StationFrames`, one station;
    ``targets``   :class:`~robocal.calib.blocks.TargetPoints`, only with several points per pose;
    ``tool``      :class:`~robocal.calib.blocks.ToolFrame`, flange -> measured frame. With one
                  point per pose the point is the measured frame's origin (6 variables); with
                  several, the points are separate targets and only the tool rotation is free.

Residual blocks: points (:class:`~robocal.calib.residuals.ToolPointResidual` or
:class:`~robocal.calib.residuals.PointResidual`) and orientations
(:class:`~robocal.calib.residuals.ToolRotationResidual`, ``rotation_weight`` mm per rad).

Initial values: the base frame by a rigid fit of the nominal predictions to the measured points;
when the points are (nearly) collinear, from the measured orientations
(:func:`~robocal.calib.initial.frame_from_orientations`); the tool rotation then as the mean
of ``(R_inst_ee)^T R_measured``.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from .blocks import GaussianPrior, RobotGeometry, StationFrames, TargetPoints, ToolFrame
from .core import Problem
from .errors import ProblemError
from .initial import base_and_tool_from_orientations, collinearity, frame_from_orientations, mean_rotation, rigid_fit
from .problem import Target
from .residuals import PointResidual, TargetChain, ToolPointResidual, ToolRotationResidual, tool_chain
from .residuals.chain import _frame_jacobian

__all__ = ["PoseCalibrationProblem", "PoseState", "MultiPoseState", "geometry_prior", "NEARLY_COLLINEAR"]

#: Predicted points whose spread across their line is below this fraction of the spread along it
#: (:func:`~.initial.collinearity`) cannot fix the rotation about the line: with orientations
#: measured, the start comes from them instead of a rigid fit of the points.
NEARLY_COLLINEAR = 1e-3


class PoseState(NamedTuple):
    """params (P,), bases (1, 4, 4), tool (1, 4, 4); ``targets`` (1, 3) is the tool origin."""

    params: np.ndarray
    bases: np.ndarray
    tool: np.ndarray
    compliance: np.ndarray | None = None  # (n_c,) joint compliances (elastic problems only)
    gravity: np.ndarray | None = None  # gravity parameters (elastic problems only)
    lateral: np.ndarray | None = None  # (2 n_l,) lateral compliances (the full elastic model only)

    @property
    def targets(self) -> np.ndarray:
        return self.tool[:, :3, 3]


class MultiPoseState(NamedTuple):
    """params (P,), bases (1, 4, 4), targets (K, 3) [mm] in the flange frame, tool (1, 4, 4)."""

    params: np.ndarray
    bases: np.ndarray
    targets: np.ndarray
    tool: np.ndarray
    compliance: np.ndarray | None = None
    gravity: np.ndarray | None = None
    lateral: np.ndarray | None = None


def _pose_state(values) -> PoseState:
    return PoseState(*values)


def _multi_pose_state(values) -> MultiPoseState:
    return MultiPoseState(*values)


def geometry_prior(model, names, sigma_mm: float, sigma_rad: float) -> GaussianPrior:
    """A Gaussian prior around the nominal values of the parameters ``names``: ``sigma_mm`` for
    lengths, ``sigma_rad`` for angles."""
    units = [model.params.units[model.params.index(n)] for n in names]
    return GaussianPrior(np.array([sigma_rad if u == "rad" else sigma_mm for u in units], dtype=float))


class PoseCalibrationProblem(Problem):
    """Measured tool positions and orientations of a robot.

    model: nominal robot; q (N, n_ctrl); points (N, K, 3) [mm] (or (N, 3)) in the instrument
    frame; rotations (N, 3, 3) measured orientations of the tool frame; targets: K
    :class:`~robocal.calib.problem.Target` (their ``point`` the initial value in the flange frame;
    default one target at the origin); free: geometry parameter names; point_sigma_mm [mm];
    rotation_weight [mm per rad]; prior_sigma: ``(mm, rad)`` for a weak prior on the geometry, or
    ``None``; base_initial: (4, 4) or ``"fit"``; tool_rotation0: (3, 3) initial tool rotation
    (default: estimated from the data); elastic: optional
    :class:`~robocal.calib.elastic.ElasticModel` (gravity-induced joint deflection, read by the
    point and the rotation residuals; the state then has ``compliance``, ``gravity`` (and
    ``lateral``); docs/elastic.md).
    """

    def __init__(self, model, q, points, rotations, *, targets=None, free=None, point_sigma_mm=None,
                 rotation_weight: float = 1000.0, prior_sigma=None, base_initial="fit", tool_rotation0=None,
                 elastic=None):
        self.model = model
        self.elastic = elastic
        self.q = q = np.asarray(q, dtype=float)
        N = len(q)
        pts = np.asarray(points, dtype=float)
        self.points = pts[:, None] if pts.ndim == 2 else pts
        self.targets = tuple(targets) if targets else (Target("tool"),)
        K = len(self.targets)
        if self.points.shape != (N, K, 3):
            raise ProblemError(f"points: expected shape ({N}, {K}, 3), got {self.points.shape}")
        self.rotations = np.asarray(rotations, dtype=float)
        if self.rotations.shape != (N, 3, 3):
            raise ProblemError(f"rotations: expected shape ({N}, 3, 3), got {self.rotations.shape}")
        self.point_mask = np.all(np.isfinite(self.points), axis=-1)
        self.point_sigma = point_sigma_mm
        self.rotation_weight = float(rotation_weight)
        self.stations, self.n_stations, self.estimate_base = np.zeros(N, dtype=int), 1, True
        self.ee_of_target = np.array([model.end_effector_index(t.end_effector) for t in self.targets], dtype=int)
        names = [n for n, f in zip(model.params.names, model.params.free) if f] if free is None else list(free)
        prior = None if prior_sigma is None or not names else geometry_prior(model, names, *prior_sigma)
        self.prior_sigma = prior_sigma
        geometry = RobotGeometry(model, names, prior=prior)
        self.free_params = geometry.names
        self.single = K == 1
        T_base, T_tool, self.base_start = self._initial_frames(base_initial, tool_rotation0)
        self.base_initial = T_base[None]
        frames = StationFrames(self.base_initial)
        tool = ToolFrame(T_tool, end_effector=self.targets[0].end_effector,
                         free=True if self.single else ["tool.rx", "tool.ry", "tool.rz"])
        self.deflection = None
        if elastic is not None:
            from .elastic import build_deflection

            self.deflection = build_deflection(model, q, elastic, [t.end_effector for t in self.targets])
        blocks, residuals = self._blocks(geometry, frames, tool)
        blocks += [] if self.deflection is None else list(self.deflection.blocks)
        super().__init__(blocks, residuals, n_poses=N, kinds=("point", "rotation", "prior"))
        self._make_state = _pose_state if self.single else _multi_pose_state

    def _blocks(self, geometry, frames, tool):
        sigma = self.point_sigma
        if self.single:
            self.chain = tool_chain(self.model, self.q, geometry, frames, tool, deflection=self.deflection)
            pts = ToolPointResidual(self.chain, tool, self.points[:, 0], sigma)
            blocks = [geometry, frames, tool]
        else:
            targets = TargetPoints([t.name for t in self.targets], [t.point for t in self.targets],
                                   end_effectors=[t.end_effector for t in self.targets])
            self.chain = TargetChain(self.model, self.q, geometry, frames, targets, deflection=self.deflection)
            pts = PointResidual(self.chain, self.points, sigma)
            blocks = [geometry, frames, targets, tool]
        rot_chain = tool_chain(self.model, self.q, geometry, frames, tool, deflection=self.deflection)
        rot = ToolRotationResidual(rot_chain, tool, self.rotations, weight_mm_per_rad=self.rotation_weight,
                                   sigma=sigma)
        self.tool_block = tool
        return blocks, [pts, rot]

    def _initial_frames(self, base_initial, tool_rotation0):
        """(T_base (4, 4), T_tool (4, 4), how the base was started: ``fit`` / ``orientations`` / ``given``)."""
        nominal = self.model.replace(T_world_base=np.eye(4))
        T_ee = nominal.fk_all(self.q)[:, self.ee_of_target[0]]
        P0 = np.array([t.point for t in self.targets], dtype=float)
        pred = np.einsum("nij,kj->nki", T_ee[:, :3, :3], P0) + T_ee[:, None, :3, 3]
        R_tool = np.eye(3) if tool_rotation0 is None else np.asarray(tool_rotation0, dtype=float)
        how = "given"
        if isinstance(base_initial, str):
            if base_initial != "fit":
                raise ProblemError(f"base_initial: expected a (4, 4) transform or 'fit', got {base_initial!r}")
            T_base = None
            if collinearity(pred.reshape(-1, 3)) >= NEARLY_COLLINEAR:
                try:
                    T_base, how = rigid_fit(pred.reshape(-1, 3), self.points.reshape(-1, 3)), "fit"
                except ValueError:
                    T_base = None
            if T_base is None:  # (nearly) a line of points: the orientations fix the rotation
                T_base, R_tool = self._start_from_orientations(T_ee, pred, R_tool, tool_rotation0)
                how = "orientations"
        else:
            T_base = np.asarray(base_initial, dtype=float)
        if tool_rotation0 is None and how != "orientations":
            R_ie = T_base[:3, :3] @ T_ee[:, :3, :3]
            R_tool = mean_rotation(np.swapaxes(R_ie, 1, 2) @ self.rotations)
        T_tool = np.eye(4)
        T_tool[:3, :3] = R_tool
        T_tool[:3, 3] = P0[0] if self.single else 0.0
        return T_base, T_tool, how

    def _start_from_orientations(self, T_ee, pred, R_tool, tool_rotation0):
        """(T_base, R_tool) from the measured orientations: base and tool rotation estimated
        together from the data (:func:`~.initial.base_and_tool_from_orientations`) unless the
        tool rotation is given; when the data cannot separate them, the base from the given (or
        identity) tool rotation."""
        P, Q = pred.reshape(-1, 3), self.points.reshape(-1, 3)
        if tool_rotation0 is None:
            try:
                return base_and_tool_from_orientations(T_ee[:, :3, :3], self.rotations, P, Q)
            except ValueError:
                pass
        return frame_from_orientations(T_ee[:, :3, :3] @ R_tool, self.rotations, P, Q), R_tool

    def predict_points(self, state, q=None, stations=None, jacobian: bool = False, payload="default",
                       gravity=None):
        """Predicted points (N, K, 3) in the instrument frame (the tool origin for one target), and
        optionally their Jacobian (N, K, 3, n_variables). Only one station: ``stations`` is ignored.
        ``payload`` / ``gravity``: for an elastic problem at new poses, as
        :meth:`~robocal.calib.problem.CalibrationProblem.predict_points`."""
        q = self.q if q is None else np.asarray(q, dtype=float)
        c, st = self.chain, np.zeros(len(q), dtype=int)
        d = self.deflection
        elastic = None if d is None else tuple(getattr(state, b.name) for b in d.blocks)
        kw = {"elastic": elastic, "payload": payload, "gravity": gravity}
        if not self.single:
            wants = tuple(b in self._plan for b in c.parameter_blocks) if jacobian else None
            out = c.predict(state.params, state.bases, state.targets, q, st, wants, **kw)
            return out.points if not jacobian else (out.points, self.scatter_columns(out.jac, out.points.shape))
        others = () if d is None else tuple(b in self._plan for b in d.blocks)
        wants = (c.geometry in self._plan, c.frames in self._plan, True) + others
        out = c.predict(state.params, state.bases, state.targets, q, st, wants if jacobian else None, **kw)
        if not jacobian:
            return out.points
        R = out.jac.pop(c.targets)[..., :3]  # (N, 1, 3, 3) = R_inst_ee
        out.jac[self.tool_block] = R @ _frame_jacobian(state.targets[0])
        return out.points, self.scatter_columns(out.jac, out.points.shape)
