"""The robot-calibration problem with every classic measurement kind: a convenience builder over
the blocks of :mod:`robocal.calib.core`.

``CalibrationProblem(model, q, targets, points, free=..., stations=..., rotations=...,
distances=..., on_plane=...)`` builds (METHODS.md section 3; DESIGN.md "One idea underneath
everything")

Parameter blocks (in this order, so a :class:`State` is ``(params, bases, targets, planes)``)
    ``geometry``  :class:`~robocal.calib.blocks.RobotGeometry`, the ``free`` model parameters by name;
    ``base``      :class:`~robocal.calib.blocks.StationFrames`, the robot base in the instrument frame,
                  one frame per station, left-perturbed (``base.rx`` .. or ``base0.*``, ``base1.*``);
    ``targets``   :class:`~robocal.calib.blocks.TargetPoints`, points in their end-effector frame [mm];
    ``planes``    :class:`~robocal.calib.blocks.Planes` for point-on-plane constraints.

Residual blocks (rows in this order), all reading one shared
:class:`~robocal.calib.residuals.TargetChain` except the rotations
    ``points``    :class:`~robocal.calib.residuals.PointResidual`;
    ``rotations`` :class:`~robocal.calib.residuals.RotationResidual`, ``rotation_weight`` mm per rad;
    ``distances`` :class:`~robocal.calib.residuals.DistanceResidual`;
    ``on_plane``  :class:`~robocal.calib.residuals.PointOnPlaneResidual`.

To combine other blocks, build a :class:`~robocal.calib.core.Problem` directly.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from ..kinematics.model import RobotModel
from .blocks import Planes, RobotGeometry, StationFrames, TargetPoints
from .core import Problem
from .errors import ProblemError
from .residuals import DistanceResidual, PointOnPlaneResidual, PointResidual, RotationResidual, TargetChain

__all__ = ["Target", "CalibrationProblem", "State", "ProblemError", "LEGACY_KINDS"]

#: kind codes of :meth:`CalibrationProblem.evaluate`'s labels: 0 point, 1 rotation, 2 distance, 3 plane
LEGACY_KINDS = ("point", "rotation", "distance", "plane")


@dataclass(frozen=True)
class Target:
    """A point carried by an end effector: ``point`` (3,) [mm] in that end effector's frame."""

    name: str
    end_effector: object = None
    point: tuple = (0.0, 0.0, 0.0)
    free: bool = True


class State(NamedTuple):
    """Current estimate: parameter vector of the model (P,) [mm|rad], base transforms (G, 4, 4),
    target points (K, 3) [mm], plane parameters (L, 3) (normal azimuth, elevation [rad], offset [mm]).
    The values of the four parameter blocks, in block order."""

    params: np.ndarray
    bases: np.ndarray
    targets: np.ndarray
    planes: np.ndarray
    compliance: np.ndarray | None = None  # (n_c,) joint compliances (elastic problems only)
    gravity: np.ndarray | None = None  # lumped gravity parameters (elastic problems only)
    lateral: np.ndarray | None = None  # (2 n_c,) lateral compliances (the full elastic model only)


def _checked_joints(model, q):
    q = np.asarray(q, dtype=float)
    if q.ndim != 2 or q.shape[1] != model.n_joints:
        raise ProblemError(f"joints: expected shape (N, {model.n_joints}) for {model.name}, got {q.shape}")
    if not np.all(np.isfinite(q)):
        r, c = np.argwhere(~np.isfinite(q))[0]
        raise ProblemError(f"joints: pose {r}, joint {model.controller_joints[c]} is not a finite number")
    return q


def _checked_stations(stations, N):
    stations = np.zeros(N, dtype=int) if stations is None else np.asarray(stations, dtype=int)
    if stations.shape != (N,) or stations.min(initial=0) < 0:
        raise ProblemError(f"stations: expected (N,) = ({N},) non-negative integers")
    G = int(stations.max(initial=0)) + 1
    missing = sorted(set(range(G)) - set(stations.tolist()))
    if missing:
        raise ProblemError(f"stations: station(s) {missing} have no poses")
    return stations, G


def _nominal_predictions(model, q, targets, ee_of_target):
    """Target positions (N, K, 3) in the robot base frame from the nominal model and initial targets."""
    pts0 = np.array([t.point for t in targets], dtype=float).reshape(-1, 3)
    # the solver's own kernel without derivatives (base frame, no T_world_base): a calibration
    # compiles one kinematics kernel, not two (the FK kernel's cold compile is ~2-3 s)
    pred, _, _ = model.target_points(q, model.params.values, pts0, np.asarray(ee_of_target, dtype=np.int64),
                                     np.zeros(0, dtype=np.int64), want_jacobian=False)
    return pred


def _check_scale(points, mask, pred):
    """Refuse point measurements whose spread is ~1000x off the model's (metres given as mm)."""
    meas = points[mask]
    if len(meas) < 3:
        return
    spread_meas = np.sqrt(np.mean(np.var(meas, axis=0)) * 3)
    spread_pred = np.sqrt(np.mean(np.var(pred[mask], axis=0)) * 3)
    if spread_pred <= 0 or spread_meas <= 0:
        return
    ratio = spread_meas / spread_pred
    if ratio < 0.02 or ratio > 50:
        hint = "metres given as millimetres?" if ratio < 0.02 else "millimetres given as metres?"
        raise ProblemError(
            f"points: the measured positions spread {spread_meas:.4g} mm but the robot model predicts "
            f"{spread_pred:.4g} mm over the same poses (ratio {ratio:.3g}); {hint} Points must be in mm.")


def _fit_bases(pred, points, stations, G):
    """Per-station rigid fit of the nominal model's predicted target positions to the measured ones."""
    from .initial import rigid_fit

    out = np.empty((G, 4, 4))
    for g in range(G):
        sel = stations == g
        try:
            out[g] = rigid_fit(pred[sel].reshape(-1, 3), points[sel].reshape(-1, 3))
        except ValueError as exc:
            raise ProblemError(f"station {g}: cannot fit an initial base frame: {exc}") from None
    return out


def _initial_bases(model, base_initial, points, pred_fn, stations, G):
    if isinstance(base_initial, str):
        if base_initial != "fit":
            raise ProblemError(f"base_initial: expected a (4, 4) transform, (G, 4, 4), 'fit' or None, got {base_initial!r}")
        if points is None:
            raise ProblemError("base_initial='fit' needs point measurements")
        return _fit_bases(pred_fn(), points, stations, G)
    T0 = model.T_world_base if base_initial is None else np.asarray(base_initial, dtype=float)
    return np.broadcast_to(T0, (G, 4, 4)).copy()


def _state(values) -> State:
    return State(*values)


class CalibrationProblem(Problem):
    """Measurements of a robot and the parameters to identify from them.

    Parameters
    ----------
    model: nominal :class:`RobotModel` (its ``T_world_base`` is the initial base in the
        instrument frame unless ``base_initial`` is given).
    q: (N, n_ctrl) controller joints [rad | mm].
    targets: sequence of :class:`Target` (their ``point`` is the initial value).
    points: (N, K, 3) measured target positions in the instrument frame [mm]; NaN marks a target
        not measured at that pose. ``None`` if only other measurement kinds are used.
    free: names of the model parameters to identify (default: the model's free parameters).
    stations: (N,) integer station index per pose (one base frame per station), default all 0.
    estimate_base: identify the base frame(s).
    base_initial: (4, 4) or (G, 4, 4) initial base frame(s) in the instrument frame; ``"fit"`` for a
        rigid fit of the nominal model's predicted target positions to the measured ones per
        station (needs ``points``); default the model's ``T_world_base``.
    point_sigma_mm: measurement standard deviation of one coordinate [mm] (weights; also the
        reference for uncertainty when given).
    rotations: optional (N, 3, 3) measured end-effector orientations (instrument frame) of
        ``rotation_end_effector``; weighted ``rotation_weight`` [mm per rad].
    distances: optional sequence of (pose_a, pose_b, target_index, distance_mm).
    on_plane: optional sequence of (pose, target_index, plane_index); ``planes_initial`` (L, 3).
    geometry_prior: optional :class:`~robocal.calib.blocks.GaussianPrior` on the ``free``
        parameters (e.g. :func:`robocal.calib.pose_problem.geometry_prior`, a weak prior around nominal).
    elastic: optional :class:`~robocal.calib.elastic.ElasticModel`: gravity-induced joint deflection
        identified with the geometry (two more blocks, ``compliance`` and ``gravity``; the state
        then has the fields ``compliance`` and ``gravity``; docs/elastic.md).

    States are :class:`State` tuples; ``evaluate``'s label kind codes follow :data:`LEGACY_KINDS`.
    """

    def __init__(self, model: RobotModel, q, targets, points=None, *, free=None, stations=None,
                 estimate_base: bool = True, base_initial=None, point_sigma_mm: float | None = None,
                 rotations=None, rotation_end_effector=None, rotation_weight: float = 1000.0,
                 distances=None, on_plane=None, planes_initial=None, geometry_prior=None, elastic=None):
        self.model = model
        self.elastic = elastic
        self.geometry_prior = geometry_prior
        self.q = q = _checked_joints(model, q)
        N = len(q)
        self.targets = tuple(targets)
        if not self.targets and points is not None:
            raise ProblemError("points given but no targets")
        self.ee_of_target = np.array([model.end_effector_index(t.end_effector) for t in self.targets], dtype=int)
        K = len(self.targets)
        if points is not None:
            points = np.asarray(points, dtype=float)
            if points.shape != (N, K, 3):
                raise ProblemError(f"points: expected shape ({N}, {K}, 3) (poses, targets, xyz), got {points.shape}")
        self.points = points
        self.point_mask = None if points is None else np.all(np.isfinite(points), axis=-1)
        self.point_sigma = point_sigma_mm
        self.stations, self.n_stations = _checked_stations(stations, N)
        self.estimate_base = estimate_base
        pred = []

        def nominal():
            if not pred:
                pred.append(_nominal_predictions(model, q, self.targets, self.ee_of_target))
            return pred[0]

        if points is not None and np.any(self.point_mask):
            _check_scale(points, self.point_mask, nominal())
        self.base_initial = _initial_bases(model, base_initial, points, nominal, self.stations, self.n_stations)
        self._build(free, rotations, rotation_end_effector, rotation_weight, distances, on_plane, planes_initial)

    def _build(self, free, rotations, rotation_end_effector, rotation_weight, distances, on_plane, planes_initial):
        model, q, N = self.model, self.q, len(self.q)
        geometry = RobotGeometry(model, free, prior=self.geometry_prior)
        self.free_params = geometry.names
        self.free_index = geometry.index
        frames = StationFrames(self.base_initial, free=bool(self.estimate_base))
        targets = TargetPoints([t.name for t in self.targets], [t.point for t in self.targets],
                               end_effectors=[t.end_effector for t in self.targets],
                               free=[bool(t.free) for t in self.targets])
        planes = Planes(planes_initial)
        self.planes_initial = np.array(planes.initial)
        self.deflection = None
        if self.elastic is not None:
            from .elastic import build_deflection

            self.deflection = build_deflection(model, q, self.elastic, [t.end_effector for t in self.targets])
        self.chain = TargetChain(model, q, geometry, frames, targets, stations=self.stations,
                                 deflection=self.deflection)
        sigma = self.point_sigma
        residuals = []
        if self.points is not None:
            residuals.append(PointResidual(self.chain, self.points, sigma))
        self.rotations = None if rotations is None else np.asarray(rotations, dtype=float)
        if self.rotations is not None and self.rotations.shape != (N, 3, 3):
            raise ProblemError(f"rotations: expected shape ({N}, 3, 3), got {self.rotations.shape}")
        self.rotation_ee = model.end_effector_index(rotation_end_effector)
        self.rotation_weight = float(rotation_weight)
        if self.rotations is not None:
            residuals.append(RotationResidual(model, q, geometry, frames, self.rotations, end_effector=self.rotation_ee,
                                              stations=self.stations, weight_mm_per_rad=rotation_weight, sigma=sigma,
                                              deflection=self.deflection))
        self.distances = [] if distances is None else [tuple(d) for d in distances]
        self.on_plane = [] if on_plane is None else [tuple(p) for p in on_plane]
        dist = DistanceResidual(self.chain, self.distances, sigma)
        plane = PointOnPlaneResidual(self.chain, planes, self.on_plane, sigma)
        residuals += [rb for rb in (dist, plane) if rb.n_rows]
        extra = [] if self.deflection is None else list(self.deflection.blocks)
        super().__init__([geometry, frames, targets, planes] + extra, residuals, n_poses=N, kinds=LEGACY_KINDS)
        self._make_state = _state
        self._legacy_slices()

    def growing_scale_columns(self):
        """The compliance and gravity columns of a lumped elastic model (gravity parameters
        identified from the data), else None: their norms at the start (first moments zero, every
        compliance equal) say nothing about their later size (:mod:`robocal.calib._iterate`)."""
        d = self.deflection
        if d is None or not d.gravity.n_free:
            return None
        return np.isin(self.blocks, ("compliance", "gravity"))

    def _legacy_slices(self):
        """Column slices of the four blocks (``_sl_geom``, ``_sl_base``, ``_target_cols``, ``_sl_planes``)."""
        geometry, frames, targets, planes = self.parameter_blocks[:4]

        def sl(blk, start):
            p = self._plan.get(blk)
            return slice(p[0], p[1]) if p is not None else slice(start, start)

        self._sl_geom = sl(geometry, 0)
        self._sl_base = sl(frames, self._sl_geom.stop)
        c = self._sl_base.stop
        self._target_cols = {}
        for k, t in enumerate(self.targets):
            if t.free:
                self._target_cols[k] = slice(c, c + 3)
                c += 3
        self._sl_planes = slice(c, c + 3 * len(self.planes_initial))

    def predict_points(self, state: State, q=None, stations=None, jacobian: bool = False, payload="default",
                       gravity=None):
        """Predicted target positions (N, K, 3) in the instrument frame, and optionally their
        Jacobian (N, K, 3, n_variables). Without ``q`` the problem's poses and stations are used;
        with ``q`` the stations default to 0 (the first base frame). ``payload``: for an elastic
        problem at new poses, ``(end_effector, mass, com)`` or None (default: the problem's);
        ``gravity``: (3,) or (N, 3) [m/s^2] in the robot base frame (default: the problem's)."""
        if q is None:
            q, stations = self.q, self.stations if stations is None else stations
        q = np.asarray(q, dtype=float)
        stations = np.zeros(len(q), dtype=int) if stations is None else np.asarray(stations, dtype=int)
        if stations.shape != (len(q),):
            raise ProblemError(f"stations: expected shape ({len(q)},), got {stations.shape}")
        c = self.chain
        wants = tuple(b in self._plan for b in c.parameter_blocks) if jacobian else None
        elastic = None if self.deflection is None else tuple(
            getattr(state, b.name) for b in self.deflection.blocks)
        out = c.predict(state.params, state.bases, state.targets, q, stations, wants, elastic=elastic,
                        payload=payload, gravity=gravity)
        if not jacobian:
            return out.points
        return out.points, self.scatter_columns(out.jac, out.points.shape)
