"""The calibration problem: parameter blocks, measurement models, stacked residuals and Jacobian.

One problem covers every geometric calibration (METHODS.md section 3; DESIGN.md "One idea
underneath everything"):

Parameter blocks
    ``geometry``  selected kinematic parameters of the robot model (joint offsets included), by name;
    ``base``      the robot base in the instrument frame, one 6-vector per station (pose group):
                  a left perturbation ``T = [R(w) | v] . T0`` (rotation vector w [rad], v [mm]), always
                  valid and re-centred after every accepted step (no penalty terms);
    ``targets``   points (reflectors, markers, sphere centres) in their end-effector frame [mm];
    ``planes``    planes (unit normal as 2 angles + offset) for point-on-plane constraints.

Measurement models (residual kinds)
    ``points``    3-D positions of the targets in the instrument frame (laser tracker, CMM,
                  vision sphere centre); several targets per pose give full 6-D information;
    ``rotations`` measured orientation of an end-effector frame, weighted ``rotation_weight``
                  mm per rad against positions;
    ``distances`` distance between the same target at two poses (ballbar-like);
    ``on_plane``  a target that lies on a plane.

The problem is immutable; :meth:`CalibrationProblem.evaluate` returns residuals and the analytic
Jacobian for a state (a :class:`State`), and :meth:`CalibrationProblem.retract` applies a step.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..kinematics.model import RobotModel
from ..transforms import skew, so3_exp, so3_log

__all__ = ["Target", "CalibrationProblem", "State", "ProblemError"]


class ProblemError(ValueError):
    """A calibration problem is set up inconsistently (the message names what and where)."""


@dataclass(frozen=True)
class Target:
    """A point carried by an end effector: ``point`` (3,) [mm] in that end effector's frame."""

    name: str
    end_effector: object = None
    point: tuple = (0.0, 0.0, 0.0)
    free: bool = True


@dataclass(frozen=True)
class State:
    """Current estimate: parameter vector of the model (P,) [mm|rad], base transforms (G, 4, 4),
    target points (K, 3) [mm], plane parameters (L, 3) (normal azimuth, elevation [rad], offset [mm])."""

    params: np.ndarray
    bases: np.ndarray
    targets: np.ndarray
    planes: np.ndarray


def _plane_normal(pl):
    az, el = pl[..., 0], pl[..., 1]
    return np.stack([np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.sin(el)], axis=-1)


def _plane_normal_derivatives(pl):
    az, el = pl[..., 0], pl[..., 1]
    d_az = np.stack([-np.cos(el) * np.sin(az), np.cos(el) * np.cos(az), np.zeros_like(az)], axis=-1)
    d_el = np.stack([-np.sin(el) * np.cos(az), -np.sin(el) * np.sin(az), np.cos(el)], axis=-1)
    return d_az, d_el


def _so3_right_jacobian_inverse(phi):
    """Inverse right Jacobian of SO(3) at rotation vectors phi (N, 3): (N, 3, 3)."""
    th = np.linalg.norm(phi, axis=-1)[:, None, None]
    K = skew(phi)
    small = th < 1e-6
    ths = np.where(small, 1.0, th)
    c = np.where(small, 1.0 / 12.0, 1.0 / ths**2 - (1.0 + np.cos(ths)) / (2.0 * ths * np.sin(ths)))
    return np.eye(3) + 0.5 * K + c * (K @ K)


class CalibrationProblem:
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
    """

    def __init__(self, model: RobotModel, q, targets, points=None, *, free=None, stations=None,
                 estimate_base: bool = True, base_initial=None, point_sigma_mm: float | None = None,
                 rotations=None, rotation_end_effector=None, rotation_weight: float = 1000.0,
                 distances=None, on_plane=None, planes_initial=None):
        self.model = model
        q = np.asarray(q, dtype=float)
        if q.ndim != 2 or q.shape[1] != model.n_joints:
            raise ProblemError(f"joints: expected shape (N, {model.n_joints}) for {model.name}, got {q.shape}")
        if not np.all(np.isfinite(q)):
            r, c = np.argwhere(~np.isfinite(q))[0]
            raise ProblemError(f"joints: pose {r}, joint {model.controller_joints[c]} is not a finite number")
        self.q = q
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
        self.stations = np.zeros(N, dtype=int) if stations is None else np.asarray(stations, dtype=int)
        if self.stations.shape != (N,) or self.stations.min(initial=0) < 0:
            raise ProblemError(f"stations: expected (N,) = ({N},) non-negative integers")
        G = int(self.stations.max(initial=0)) + 1
        missing = sorted(set(range(G)) - set(self.stations.tolist()))
        if missing:
            raise ProblemError(f"stations: station(s) {missing} have no poses")
        self.n_stations = G
        self.estimate_base = estimate_base
        if points is not None and np.any(self.point_mask):
            self._check_scale(self._nominal_predictions())
        if isinstance(base_initial, str):
            if base_initial != "fit":
                raise ProblemError(f"base_initial: expected a (4, 4) transform, (G, 4, 4), 'fit' or None, got {base_initial!r}")
            if points is None:
                raise ProblemError("base_initial='fit' needs point measurements")
            self.base_initial = self._fit_bases(G)
        else:
            T0 = model.T_world_base if base_initial is None else np.asarray(base_initial, dtype=float)
            self.base_initial = np.broadcast_to(T0, (G, 4, 4)).copy()

        names = model.params.names
        if free is None:
            free = [n for n, f in zip(names, model.params.free) if f]
        free = list(free)
        for n in free:
            model.params.index(n)  # raises with a suggestion for unknown names
        self.free_params = tuple(free)
        self.free_index = np.array([names.index(n) for n in free], dtype=int)

        self.rotations = None if rotations is None else np.asarray(rotations, dtype=float)
        if self.rotations is not None and self.rotations.shape != (N, 3, 3):
            raise ProblemError(f"rotations: expected shape ({N}, 3, 3), got {self.rotations.shape}")
        self.rotation_ee = model.end_effector_index(rotation_end_effector)
        self.rotation_weight = float(rotation_weight)
        self.distances = [] if distances is None else [tuple(d) for d in distances]
        self.on_plane = [] if on_plane is None else [tuple(p) for p in on_plane]
        self.planes_initial = np.zeros((0, 3)) if planes_initial is None else np.asarray(planes_initial, float).reshape(-1, 3)
        for i, (a, b, k, d) in enumerate(self.distances):
            if not (0 <= a < N and 0 <= b < N and 0 <= k < K) or not np.isfinite(d):
                raise ProblemError(f"distances[{i}]: poses must be in 0..{N - 1}, target in 0..{K - 1}, distance finite")
        for i, (n, k, l) in enumerate(self.on_plane):
            if not (0 <= n < N and 0 <= k < K and 0 <= l < len(self.planes_initial)):
                raise ProblemError(f"on_plane[{i}]: pose, target or plane index out of range")
        self._build_layout()

    def _fit_bases(self, G):
        """Per-station rigid fit of the nominal model's predicted target positions to the measured ones."""
        from .initial import rigid_fit

        pred = self._nominal_predictions()
        out = np.empty((G, 4, 4))
        for g in range(G):
            sel = self.stations == g
            try:
                out[g] = rigid_fit(pred[sel].reshape(-1, 3), self.points[sel].reshape(-1, 3))
            except ValueError as exc:
                raise ProblemError(f"station {g}: cannot fit an initial base frame: {exc}") from None
        return out

    def _nominal_predictions(self):
        """Target positions (N, K, 3) in the robot base frame from the nominal model and initial targets."""
        pts0 = np.array([t.point for t in self.targets], dtype=float).reshape(-1, 3)
        T_all = self.model.replace(T_world_base=np.eye(4)).fk_all(self.q)
        pred = np.empty((len(self.q), len(self.targets), 3))
        for k, e in enumerate(self.ee_of_target):
            T = T_all[:, e]
            pred[:, k] = (T[:, :3, :3] @ pts0[k]) + T[:, :3, 3]
        return pred

    def _check_scale(self, pred):
        """Refuse point measurements whose spread is ~1000x off the model's (metres given as mm)."""
        meas = self.points[self.point_mask]
        if len(meas) < 3:
            return
        spread_meas = np.sqrt(np.mean(np.var(meas, axis=0)) * 3)
        spread_pred = np.sqrt(np.mean(np.var(pred[self.point_mask], axis=0)) * 3)
        if spread_pred <= 0 or spread_meas <= 0:
            return
        ratio = spread_meas / spread_pred
        if ratio < 0.02 or ratio > 50:
            hint = "metres given as millimetres?" if ratio < 0.02 else "millimetres given as metres?"
            raise ProblemError(
                f"points: the measured positions spread {spread_meas:.4g} mm but the robot model predicts "
                f"{spread_pred:.4g} mm over the same poses (ratio {ratio:.3g}); {hint} Points must be in mm.")

    # ------------------------------------------------------------------ layout of the state vector
    def _build_layout(self):
        cols, units, blocks = [], [], []
        for n in self.free_params:
            cols.append(n)
            units.append(self.model.params.units[self.model.params.index(n)])
            blocks.append("geometry")
        if self.estimate_base:
            for g in range(self.n_stations):
                pre = "base" if self.n_stations == 1 else f"base{g}"
                for c, u in zip(("rx", "ry", "rz", "x", "y", "z"), ("rad",) * 3 + ("mm",) * 3):
                    cols.append(f"{pre}.{c}")
                    units.append(u)
                    blocks.append("base")
        for t in self.targets:
            if t.free:
                for c in "xyz":
                    cols.append(f"{t.name}.{c}")
                    units.append("mm")
                    blocks.append("targets")
        for i in range(len(self.planes_initial)):
            for c, u in (("azimuth", "rad"), ("elevation", "rad"), ("offset", "mm")):
                cols.append(f"plane{i}.{c}")
                units.append(u)
                blocks.append("planes")
        self.names = tuple(cols)
        self.units = tuple(units)
        self.blocks = np.array(blocks)
        nf = len(self.free_params)
        self._sl_geom = slice(0, nf)
        nb = 6 * self.n_stations if self.estimate_base else 0
        self._sl_base = slice(nf, nf + nb)
        self._target_cols = {}
        c = nf + nb
        for k, t in enumerate(self.targets):
            if t.free:
                self._target_cols[k] = slice(c, c + 3)
                c += 3
        self._sl_planes = slice(c, c + 3 * len(self.planes_initial))
        self.n_variables = len(cols)

    @property
    def n_poses(self) -> int:
        return len(self.q)

    def initial_state(self) -> State:
        pts = np.array([t.point for t in self.targets], dtype=float).reshape(-1, 3)
        return State(self.model.params.values.copy(), self.base_initial.copy(), pts, self.planes_initial.copy())

    def retract(self, state: State, step) -> State:
        """Apply a step of the state vector: additive for parameters, targets and planes; a left
        rotation-vector/translation perturbation for the base frames."""
        step = np.asarray(step, dtype=float)
        params = state.params.copy()
        params[self.free_index] += step[self._sl_geom]
        bases = state.bases.copy()
        if self.estimate_base:
            d = step[self._sl_base].reshape(-1, 6)
            R = so3_exp(d[:, :3])
            bases[:, :3, :3] = R @ state.bases[:, :3, :3]
            bases[:, :3, 3] = (R @ state.bases[:, :3, 3, None])[..., 0] + d[:, 3:]
        targets = state.targets.copy()
        for k, sl in self._target_cols.items():
            targets[k] += step[sl]
        planes = state.planes.copy()
        if len(planes):
            planes += step[self._sl_planes].reshape(-1, 3)
        return State(params, bases, targets, planes)

    def model_at(self, state: State) -> RobotModel:
        """The robot model with the state's parameters (base of station 0 as its base)."""
        return self.model.with_params(state.params).replace(T_world_base=state.bases[0])

    # ------------------------------------------------------------------ prediction
    def predict_points(self, state: State, q=None, stations=None, jacobian: bool = False):
        """Predicted target positions (N, K, 3) in the instrument frame, and optionally their
        Jacobian (N, K, 3, n_variables). Without ``q`` the problem's poses and stations are used;
        with ``q`` the stations default to 0 (the first base frame)."""
        if q is None:
            q, stations = self.q, self.stations if stations is None else stations
        q = np.asarray(q, dtype=float)
        stations = np.zeros(len(q), dtype=int) if stations is None else np.asarray(stations, dtype=int)
        if stations.shape != (len(q),):
            raise ProblemError(f"stations: expected shape ({len(q)},), got {stations.shape}")
        N, K = len(q), len(self.targets)
        single = self.n_stations == 1
        if single:  # one base frame: the kernel works in the instrument frame directly
            pts, R_inst_ee, Jg = self.model.target_points(q, state.params, state.targets, self.ee_of_target,
                                                          self.free_index, jacobian, root=state.bases[0])
            if not jacobian:
                return pts
            J = np.zeros((N, K, 3, self.n_variables))
            J[..., self._sl_geom] = Jg
        else:
            p_base, R_base_ee, Jg = self.model.target_points(q, state.params, state.targets, self.ee_of_target,
                                                              self.free_index, jacobian)
            Rb = state.bases[stations, :3, :3]
            tb = state.bases[stations, :3, 3]
            pts = np.einsum("nij,nkj->nki", Rb, p_base) + tb[:, None]
            if not jacobian:
                return pts
            J = np.zeros((N, K, 3, self.n_variables))
            J[..., self._sl_geom] = np.einsum("nij,nkjf->nkif", Rb, Jg)
            R_inst_ee = np.einsum("nij,nkjl->nkil", Rb, R_base_ee)
        if self.estimate_base:
            # left perturbation of the base: d p = omega x p + v  ->  [-skew(p) | I]
            x, y, z = pts[..., 0], pts[..., 1], pts[..., 2]
            for g in range(self.n_stations):
                sel = slice(None) if single else np.flatnonzero(stations == g)
                c0 = self._sl_base.start + 6 * g
                Jb = J[sel, :, :, c0:c0 + 6]
                Jb[..., 0, 1], Jb[..., 0, 2] = z[sel], -y[sel]
                Jb[..., 1, 0], Jb[..., 1, 2] = -z[sel], x[sel]
                Jb[..., 2, 0], Jb[..., 2, 1] = y[sel], -x[sel]
                Jb[..., 0, 3] = Jb[..., 1, 4] = Jb[..., 2, 5] = 1.0
                if not single:
                    J[sel, :, :, c0:c0 + 6] = Jb
        if self._target_cols:
            for k, sl in self._target_cols.items():
                J[:, k, :, sl] = R_inst_ee[:, k]
        return (pts, J) if jacobian else pts

    # ------------------------------------------------------------------ residuals
    def evaluate(self, state: State, jacobian: bool = True):
        """Stacked, weighted residuals r (M,) = measured - predicted, and the Jacobian of the
        *prediction* side ``d(-r)/dx`` is returned as ``J`` with ``r(x + dx) ~ r - J dx``.

        Returns ``(r, J, labels)`` where ``labels`` (M, 2) gives (pose, kind code) per row; kind
        codes: 0 point, 1 rotation, 2 distance, 3 plane.
        """
        rows_r, rows_J, labels = [], [], []
        w = 1.0 if self.point_sigma is None else 1.0 / self.point_sigma
        need_pts = self.points is not None or self.distances or self.on_plane
        if need_pts:
            out = self.predict_points(state, jacobian=jacobian)
            pts, Jp = out if jacobian else (out, None)
        if self.points is not None:
            mask = self.point_mask
            if mask.all():
                rows_r.append(((self.points - pts) * w).ravel())
                if jacobian:
                    rows_J.append(Jp.reshape(-1, self.n_variables) * w)
            else:
                rows_r.append(((self.points - pts)[mask] * w).ravel())
                if jacobian:
                    rows_J.append(Jp[mask].reshape(-1, self.n_variables) * w)
            pose_idx = np.broadcast_to(np.arange(self.n_poses)[:, None], mask.shape)[mask]
            labels.append(np.stack([np.repeat(pose_idx, 3), np.zeros(3 * len(pose_idx), int)], axis=1))
        if self.rotations is not None:
            r, J = self._rotation_residuals(state, jacobian)
            rows_r.append(r * w)
            labels.append(np.stack([np.repeat(np.arange(self.n_poses), 3), np.ones(3 * self.n_poses, int)], axis=1))
            if jacobian:
                rows_J.append(J * w)
        if self.distances:
            a, b, k, d = (np.array(v) for v in zip(*self.distances))
            a, b, k = a.astype(int), b.astype(int), k.astype(int)
            diff = pts[a, k] - pts[b, k]
            dist = np.linalg.norm(diff, axis=1)
            rows_r.append((d - dist) * w)
            labels.append(np.stack([a, np.full(len(a), 2)], axis=1))
            if jacobian:
                u = diff / dist[:, None]
                rows_J.append(np.einsum("ni,nic->nc", u, Jp[a, k] - Jp[b, k]) * w)
        if self.on_plane:
            n_idx, k, l = (np.array(v, dtype=int) for v in zip(*self.on_plane))
            pl = state.planes[l]
            nrm = _plane_normal(pl)
            p = pts[n_idx, k]
            rows_r.append(-(np.einsum("ni,ni->n", nrm, p) - pl[:, 2]) * w)
            labels.append(np.stack([n_idx, np.full(len(n_idx), 3)], axis=1))
            if jacobian:
                Jr = np.einsum("ni,nic->nc", nrm, Jp[n_idx, k])
                d_az, d_el = _plane_normal_derivatives(pl)
                for i, li in enumerate(l):
                    c = self._sl_planes.start + 3 * li
                    Jr[i, c] += d_az[i] @ p[i]
                    Jr[i, c + 1] += d_el[i] @ p[i]
                    Jr[i, c + 2] -= 1.0
                rows_J.append(Jr * w)
        if not rows_r:
            raise ProblemError("the problem has no measurements")
        r = np.concatenate(rows_r)
        J = np.concatenate(rows_J, axis=0) if jacobian else None
        return r, J, np.concatenate(labels, axis=0)

    def _rotation_residuals(self, state, jacobian):
        T_all, ptw, _, masks = self.model.kinematics_with(self.q, state.params, np.eye(4), [self.rotation_ee])
        T = T_all[:, 0]
        Rb = state.bases[self.stations, :3, :3]
        R_pred = Rb @ T[:, :3, :3]
        err = so3_log(self.rotations @ np.swapaxes(R_pred, 1, 2))  # small rotation, instrument frame
        r = (err * self.rotation_weight).ravel()
        if not jacobian:
            return r, None
        # a rotation d of the prediction changes the error log(E exp(-d)) by -Jr^-1(err) d
        Jr_inv = _so3_right_jacobian_inverse(err)
        J = np.zeros((self.n_poses, 3, self.n_variables))
        if len(self.free_index):
            Jg = (ptw[:, :3] * masks[0])[..., self.free_index]
            J[..., self._sl_geom] = Rb @ Jg
        if self.estimate_base:
            for g in range(self.n_stations):
                sel = self.stations == g
                c0 = self._sl_base.start + 6 * g
                J[sel, :, c0:c0 + 3] = np.eye(3)
        J = Jr_inv @ J
        return r, (J * self.rotation_weight).reshape(-1, self.n_variables)
