"""The differential thermal drift model (thesis (3-1), (3-5) ... (3-10)).

The sphere centre seen by the fixed sensor, cold and warm (3-3, 3-4)::

    P_cold = T_sensor_base . T_base_flange(q; X)      . P_e
    P_warm = T_sensor_base . T_base_flange(q; X + dX) . P_e

To first order (3-5, 3-6)::

    P_warm - P_cold = T_sensor_base . dT_base_flange . P_e = M(q) dX            (3-7)
    dT_base_flange  = sum_i sum_p T_base_i . A_pi . T_i_flange . dp_i,   A_pi = T_{i-1,i}^-1 dT_{i-1,i}/dp_i

so column ``k_pi`` of ``M(q)`` (3 x P) is ``R_sensor_base`` times the derivative of the flange
point ``P_e``'s base-frame coordinates with respect to parameter ``p_i`` -- exactly the
identification Jacobian of the point ``P_e`` (the fourth row of (3-7) is identically 0, so only
3 equations per pose; only the rotation of ``T_sensor_base`` enters). Stacking m poses gives
``Y = A dX`` (3-8), solved by SVD (3-9, 3-10) for any chosen subset of the parameters.

Before solving, the chosen subset is checked against the pose set: a subset whose columns are
(numerically) dependent cannot be identified, and :func:`identify_drift` says which parameters and
why (:func:`robocal.calib.analyse_identifiability`) instead of returning noise -- or, with
``on_rank_deficient="drop"``, holds them at zero and solves the rest.

Rank, condition number and singular values are those of ``A`` with unit-norm columns (so mm and
rad columns compare; the raw condition number of a mixed-unit matrix means nothing).
"""

from __future__ import annotations
from ..errors import NotIdentifiableError

from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np

from ..calib import IdentifiabilityReport, analyse_identifiability
from ..kinematics.model import RobotModel

__all__ = ["DriftResult", "DriftIdentificationError", "RankDeficientError", "drift_coefficients", "identify_drift",
           "predict_sphere", "resolve_subset"]


class DriftIdentificationError(NotIdentifiableError):
    """The drift identification cannot be set up (shapes, too few equations, unknown names)."""


class RankDeficientError(DriftIdentificationError):
    """The chosen parameter subset is not identifiable from the pose set.

    ``report``: the :class:`~robocal.calib.IdentifiabilityReport`; ``names``: the parameters that
    cannot be identified (each explained in the message).
    """

    def __init__(self, message, report: IdentifiabilityReport):
        super().__init__(message)
        self.report = report
        self.names = report.dropped_names


@dataclass
class DriftResult:
    """Identified thermal parameter deltas.

    names (k,): the identified subset; delta (k,) [mm | rad]; std (k,) one-sigma (from
    ``point_sigma_mm`` if given, else from the residual; NaN with no redundancy).
    all_names (P,), delta_full (P,): the same on the whole parameter vector (0 elsewhere).
    rank, condition_number, singular_values: of the column-normalised stacked matrix ``A``.
    residuals_before_mm (m, 3): ``Y = P_warm - P_cold``; residuals_after_mm (m, 3): what the
    identified deltas leave unexplained (``Y - (f(X + dX) - f(X))``, the model's own prediction).
    identifiability: the report on the subset; dropped: names held at 0 (``on_rank_deficient="drop"``).
    iterations: linearisations used (1 = the thesis's single SVD solve). units (k,): "mm" or "rad".
    """

    names: tuple
    delta: np.ndarray
    std: np.ndarray
    all_names: tuple
    delta_full: np.ndarray
    rank: int
    condition_number: float
    singular_values: np.ndarray
    residuals_before_mm: np.ndarray
    residuals_after_mm: np.ndarray
    identifiability: IdentifiabilityReport
    dropped: list = field(default_factory=list)
    iterations: int = 1
    units: tuple = ()

    @property
    def n_poses(self) -> int:
        return len(self.residuals_before_mm)

    @property
    def rms_before_mm(self) -> float:
        return float(np.sqrt(np.mean(np.sum(self.residuals_before_mm**2, axis=1))))

    @property
    def rms_after_mm(self) -> float:
        return float(np.sqrt(np.mean(np.sum(self.residuals_after_mm**2, axis=1))))

    def as_dict(self) -> dict:
        """Identified deltas by name [mm | rad]."""
        return dict(zip(self.names, self.delta.tolist()))

    def warm_params(self, model: RobotModel) -> np.ndarray:
        """The warm parameter vector (P,): ``model.params.values + delta_full``."""
        return model.params.values + self.delta_full

    def warm_model(self, model: RobotModel) -> RobotModel:
        """A new model with the warm parameters (building a model takes ~1 ms; the compensation
        uses the parameter vector directly)."""
        return model.with_params(self.warm_params(model))

    def table(self) -> list[dict]:
        """One dict per identified parameter: name, unit, delta, std."""
        units = self.units or ("",) * len(self.names)
        return [{"name": n, "unit": u, "delta": float(d), "std": float(s)}
                for n, u, d, s in zip(self.names, units, self.delta, self.std)]

    def summary(self) -> str:
        lines = [f"drift identification: {len(self.names)} parameters from {self.n_poses} poses "
                 f"({3 * self.n_poses} equations), rank {self.rank}, condition {self.condition_number:.3g}; "
                 f"RMS {self.rms_before_mm:.4f} -> {self.rms_after_mm:.4f} mm"]
        for row in self.table():
            lines.append(f"  {row['name']:8s} {row['delta']:+.6g} {row['unit']} (std {row['std']:.3g})")
        if self.dropped:
            lines.append("held at 0 (not identifiable from these poses):")
            lines += [f"  {d['name']}: {d['why']}" for d in self.identifiability.dropped]
        return "\n".join(lines)


# ---------------------------------------------------------------------------------------------- model
def resolve_subset(model: RobotModel, subset=None) -> np.ndarray:
    """Indices (k,) of ``subset`` (names) in the model's parameter vector; ``None`` = the model's
    free parameters. Unknown names raise ``KeyError`` with suggestions; duplicates are refused."""
    names = model.params.names
    if subset is None:
        return np.flatnonzero(model.params.free)
    subset = [subset] if isinstance(subset, str) else list(subset)
    idx = np.array([model.params.index(n) for n in subset], dtype=np.int64)
    if len(set(idx.tolist())) != len(idx):
        dup = sorted({n for n in subset if subset.count(n) > 1})
        raise DriftIdentificationError(f"subset names a parameter twice: {dup}")
    if len(idx) == 0:
        raise DriftIdentificationError(f"empty parameter subset; choose from {list(names)}")
    return idx


def _sphere_and_jacobian(model, T_sensor_base, P_e, q, params, index, jacobian=True):
    """Sphere centres (m, 3) in the sensor frame and their derivatives (m, 3, len(index))."""
    T = np.asarray(T_sensor_base, dtype=float)
    p, _, J = model.target_points(q, params, np.asarray(P_e, float).reshape(1, 3), [0], index, jacobian)
    R = T[:3, :3]
    P = p[:, 0] @ R.T + T[:3, 3]
    if not jacobian:
        return P, None
    return P, np.einsum("ij,njk->nik", R, J[:, 0])


def joint_rows(model, q, what: str = "joints", rows: str = "m", items: str = "pose(s)",
               error=DriftIdentificationError) -> np.ndarray:
    """``q`` as a contiguous (rows, n_joints) float array (one vector: one row); a wrong shape or
    non-finite rows raise ``error`` naming ``what`` and the ``items`` concerned."""
    q = np.asarray(q, dtype=float)
    if q.ndim == 1:
        q = q[None]
    if q.ndim != 2 or q.shape[1] != model.n_joints:
        raise error(f"{what}: expected shape ({rows}, {model.n_joints}), got {q.shape}")
    if not np.all(np.isfinite(q)):
        raise error(f"{what}: {items} {np.flatnonzero(~np.all(np.isfinite(q), 1)).tolist()} not finite")
    return np.ascontiguousarray(q)


def drift_coefficients(model: RobotModel, T_sensor_base, P_e, q, *, params=None, subset=None) -> np.ndarray:
    """The coefficient matrices ``M(q)`` of (3-7): (m, 3, P) (or (m, 3, k) for ``subset``).

    ``M(q) = R_sensor_base . dP_base/dX``: column ``k_pi`` is how the sphere centre in the sensor
    frame moves per unit change of parameter ``p_i`` [mm per mm | mm per rad], for all P
    parameters of the model (names ``model.params.names``; fixed ones included -- their columns
    are what a change of them would do). The model's ``T_world_base`` is not used: ``T_sensor_base``
    places the base in the sensor frame.
    q: (m, n) joints [rad]; P_e (3,) sphere centre in the flange frame [mm]; params: the
    parameter vector to linearise at (default the model's, the cold state).
    """
    q = joint_rows(model, q)
    params = model.params.values if params is None else np.asarray(params, float)
    index = np.arange(len(model.params)) if subset is None else resolve_subset(model, subset)
    return _sphere_and_jacobian(model, T_sensor_base, P_e, q, params, index)[1]


def predict_sphere(model: RobotModel, T_sensor_base, P_e, q, *, params=None) -> np.ndarray:
    """Sphere centres (m, 3) in the sensor frame, (3-1), with the model's (or given) parameters."""
    q = joint_rows(model, q)
    params = model.params.values if params is None else np.asarray(params, float)
    return _sphere_and_jacobian(model, T_sensor_base, P_e, q, params, np.zeros(0, np.int64), False)[0]


# ---------------------------------------------------------------------------------------------- solve
def identify_drift(model: RobotModel, T_sensor_base, P_e, q, P_warm, P_cold=None, subset=None, *,
                   iterations: int = 1, rcond: float = 1e-10, tol: float = 1e-6, point_sigma_mm: float | None = None,
                   on_rank_deficient: str = "raise") -> DriftResult:
    """Identify the thermal parameter deltas ``dX`` of ``subset`` from sphere measurements ((3-8)-(3-10)).

    model: the cold robot model (its parameters are ``X``).
    T_sensor_base (4, 4), P_e (3,): from the system calibration.
    q (m, n): joints of the measurement poses [rad]; P_warm (m, 3): measured sphere centres now
        (sensor frame, [mm]); P_cold (m, 3): the cold reference at the same joints (measured in
        the cold state), or ``None`` to predict it from the cold model, (3-3).
    subset: parameter names to identify (default: the model's free parameters).
    iterations: 1 = the thesis's single linear solve; more re-linearise at ``X + dX`` (Gauss-Newton
        on ``P_warm - P_cold = f(X + dX) - f(X)``), which removes the second-order error (~1e-5 mm
        for thermal drifts; only worth it for checks).
    rcond: singular values below ``rcond * s_max`` are dropped in (3-10) (a safeguard; a rank
        deficiency is caught before by ``tol``).
    tol: identifiability threshold of :func:`~robocal.calib.analyse_identifiability` (relative
        independent part of a unit-norm column).
    point_sigma_mm: measurement noise per coordinate for the standard deviations.
    on_rank_deficient: ``"raise"`` (:class:`RankDeficientError` naming the parameters and the ones
        they trade off with) or ``"drop"`` (hold them at 0, solve the rest, list them in ``dropped``).
    """
    if on_rank_deficient not in ("raise", "drop"):
        raise ValueError(f"on_rank_deficient must be 'raise' or 'drop', got {on_rank_deficient!r}")
    if iterations < 1:
        raise ValueError(f"iterations must be >= 1, got {iterations}")
    q = joint_rows(model, q)
    m = len(q)
    P_warm = np.asarray(P_warm, dtype=float)
    if P_warm.shape != (m, 3):
        raise DriftIdentificationError(f"P_warm: expected shape ({m}, 3) (one sphere centre per pose), got {P_warm.shape}")
    index = resolve_subset(model, subset)
    names = tuple(model.params.names[i] for i in index)
    k = len(index)
    if 3 * m < k:
        raise DriftIdentificationError(
            f"{k} parameters cannot be identified from {m} poses ({3 * m} equations); measure at least "
            f"{-(-k // 3)} poses or choose fewer parameters (the thesis uses 2-3 equations per parameter)")
    X = model.params.values
    P0, A = _sphere_and_jacobian(model, T_sensor_base, P_e, q, X, index)
    Y = P_warm - _cold_reference(P_cold, P0, P_warm)          # (m, 3), (3-8) left side
    A2 = A.reshape(3 * m, k)
    ident, active = _identifiable_columns(A2, names, m, tol, on_rank_deficient)
    ia = np.flatnonzero(active)

    def relinearise(delta, jacobian=True):
        return _sphere_and_jacobian(model, T_sensor_base, P_e, q, X + _full(len(X), index, delta), index, jacobian)

    delta, resid, svd = _solve(relinearise, Y, P0, A2, ia, iterations, rcond)
    rank, cond, std = _statistics(svd, resid, k, ia, point_sigma_mm)
    full = _full(len(X), index, delta)
    dropped = [n for n, a in zip(names, active) if not a]
    units = tuple(model.params.units[i] for i in index)
    return DriftResult(names, delta, std, model.params.names, full, rank, cond, svd.s, Y, resid, ident, dropped,
                       iterations, units)


def _cold_reference(P_cold, P0, P_warm) -> np.ndarray:
    """The cold sphere centres (m, 3): measured ``P_cold`` or, if None, the model's ``P0``;
    checked for shape and (with ``P_warm``) for finite values."""
    m = len(P0)
    if P_cold is None:
        P_cold = P0
    else:
        P_cold = np.asarray(P_cold, dtype=float)
        if P_cold.shape != (m, 3):
            raise DriftIdentificationError(f"P_cold: expected shape ({m}, 3), got {P_cold.shape}")
    if not (np.all(np.isfinite(P_warm)) and np.all(np.isfinite(P_cold))):
        raise DriftIdentificationError("sphere centres contain NaN or infinite values")
    return P_cold


def _identifiable_columns(A2, names, m: int, tol: float, on_rank_deficient: str):
    """The identifiability report of ``A2`` (3m, k) and the mask (k,) of the columns to solve;
    non-identifiable ones raise :class:`RankDeficientError` or (``"drop"``) are masked out."""
    k = len(names)
    ident = analyse_identifiability(A2, names, tol=tol)
    active = np.ones(k, dtype=bool)
    if ident.dropped:
        if on_rank_deficient == "raise":
            raise RankDeficientError(
                f"the parameter subset is not identifiable from these {m} poses (rank {ident.rank} of {k}):\n"
                + ident.explain() + "\nchoose other parameters or add poses that separate them", ident)
        active = np.array([n not in set(ident.dropped_names) for n in names])
    return ident, active


class _SVD(NamedTuple):
    """The last (3-9) decomposition: singular values ``s``, ``Vt``, the kept mask, column scales."""

    s: np.ndarray
    Vt: np.ndarray
    keep: np.ndarray
    scale: np.ndarray


def _svd_step(Aa, r, rcond: float):
    """(3-9), (3-10) on unit-norm columns of ``Aa`` (3m, ka): the step (ka,) for residual ``r``
    (3m,), singular values below ``rcond * s_max`` dropped."""
    scale = np.linalg.norm(Aa, axis=0)
    scale[scale == 0] = 1.0
    U, s, Vt = np.linalg.svd(Aa / scale, full_matrices=False)     # (3-9)
    keep = s > rcond * s[0]
    step = Vt.T @ np.where(keep, (U.T @ r) / np.where(keep, s, 1.0), 0.0)   # (3-10)
    return step / scale, _SVD(s, Vt, keep, scale)


def _solve(relinearise, Y, P0, A2, ia, iterations: int, rcond: float):
    """``iterations`` linear solves of ``Y = A dX`` over the columns ``ia`` (the first at the cold
    parameters, the others re-linearised by ``relinearise(delta)``). Returns ``(delta (k,),
    residuals (m, 3) [mm], the last SVD)``."""
    n_eq, k = A2.shape
    delta = np.zeros(k)
    y = Y.reshape(-1)
    r = y
    for it in range(iterations):
        if it > 0:
            Pw, A = relinearise(delta)
            A2 = A.reshape(n_eq, k)
            r = y - (Pw - P0).reshape(-1)
        step, svd = _svd_step(A2[:, ia], r, rcond)
        delta[ia] += step
    if iterations > 1:
        Pw = relinearise(delta, False)[0]
        resid = Y - (Pw - P0)
    else:
        resid = (y - A2 @ delta).reshape(-1, 3)
    return delta, resid, svd


def _statistics(svd: _SVD, resid, k: int, ia, point_sigma_mm):
    """Rank, condition number (unit-norm columns) and standard deviations (k,) of the solution
    (NaN for columns not solved); the noise is ``point_sigma_mm`` or estimated from ``resid``."""
    s, Vt, keep, scale = svd
    rank = int(keep.sum())
    cond = float(s[0] / s[rank - 1]) if rank else float("inf")
    dof = resid.size - rank
    sigma = point_sigma_mm if point_sigma_mm is not None else (
        float(np.sqrt(np.sum(resid**2) / dof)) if dof > 0 else float("nan"))
    inv = np.where(keep, 1.0 / np.where(keep, s, 1.0) ** 2, 0.0)
    var = ((Vt.T**2) @ inv) / scale**2 * sigma**2
    std = np.full(k, np.nan)
    std[ia] = np.sqrt(var)
    return rank, cond, std


def _full(P, index, delta):
    out = np.zeros(P)
    out[index] = delta
    return out
