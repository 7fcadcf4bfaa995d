"""Online thermal compensation: correct a taught program for the warm robot (thesis 3.1 end, 5.1).

A taught program is a list of joint vectors ``q_taught`` recorded on the cold robot; the flange
(or tool) went to ``T_target = FK_cold(q_taught)``. After heating, the same joints put it at
``FK_warm(q_taught)``, off by the thermal drift. :func:`compensate_program` finds joints that put
the warm robot back on the taught poses by Newton iterations on the warm model::

    q <- q + J_warm(q)^+ (T_target (-) FK_warm(q))          (at most 3 iterations, batched)

with the 6-D pose error (position [mm], rotation vector [rad]) or the position only
(``position_only``: 3 equations, the minimum-norm joint correction). Drifts are 0.1-0.5 mm, so the
first step already leaves only a second-order error (~1e-5 mm); the second reaches rounding.

:func:`online_cycle` is what runs in the production gap: identify the screened deltas from ~6
sphere measurements (:func:`~robocal.thermal.drift.identify_drift`) and correct the program.

:class:`RemeasureRule` decides when the next sphere measurement is due (see its docstring).
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from ..kinematics.model import RobotModel
from ..transforms import so3_log
from .drift import DriftResult, identify_drift, joint_rows

__all__ = ["CompensationResult", "OnlineCycle", "CycleRecord", "RemeasureDecision", "RemeasureRule",
           "compensate_program", "online_cycle", "predicted_drift"]


@dataclass
class CompensationResult:
    """Corrected joints of a program and how well they reach the taught poses on the warm model.

    q (n, n_joints): corrected joints [rad]; q_taught (n, n_joints): the input.
    position_error_mm (n,), rotation_error_rad (n,): warm-model error left at ``q`` (rotation 0 in
    position-only mode, where it is not controlled); drift_before_mm (n,): the warm model's
    position error at the taught joints (the uncompensated drift); iterations (n,) steps taken per
    point; converged (n,) bool (within ``tol_mm`` / ``tol_rad``); within_limits (n,) bool.
    """

    q: np.ndarray
    q_taught: np.ndarray
    position_error_mm: np.ndarray
    rotation_error_rad: np.ndarray
    drift_before_mm: np.ndarray
    rotation_drift_before_rad: np.ndarray
    iterations: np.ndarray
    converged: np.ndarray
    within_limits: np.ndarray
    position_only: bool = False

    @property
    def correction(self) -> np.ndarray:
        """Joint corrections ``q - q_taught`` (n, n_joints) [rad] -- what is sent to the controller."""
        return self.q - self.q_taught

    @property
    def all_converged(self) -> bool:
        return bool(np.all(self.converged))

    def summary(self) -> str:
        n = len(self.q)
        return (f"program of {n} points: drift before max {self.drift_before_mm.max(initial=0):.4f} mm, after max "
                f"{self.position_error_mm.max(initial=0):.2e} mm / {self.rotation_error_rad.max(initial=0):.2e} rad; "
                f"{int(self.converged.sum())}/{n} converged in <= {int(self.iterations.max(initial=0))} iterations"
                + ("" if self.within_limits.all() else
                   f"; {int((~self.within_limits).sum())} corrected point(s) outside the joint limits"))


def _flange_kinematics(model, q, params, T_flange_tool, jmask, want_jacobian=True):
    """Tool poses (n, 4, 4) in the model's world frame and the geometric Jacobian (n, 6, n_ctrl)
    (rows: tool-point velocity [mm], angular velocity) for a parameter vector -- one kernel call."""
    T, _, jtw, _ = model.kinematics_with(q, params, None, _FIRST)
    T = T[:, 0]
    if T_flange_tool is not None:
        T = T @ T_flange_tool
    if not want_jacobian:
        return T, None
    p = T[:, :3, 3, None]
    w, v = jtw[:, :3] * jmask, jtw[:, 3:] * jmask
    J6 = np.empty((len(q), 6, w.shape[2]))
    J6[:, 0] = w[:, 1] * p[:, 2] - w[:, 2] * p[:, 1] + v[:, 0]     # omega x p + v
    J6[:, 1] = w[:, 2] * p[:, 0] - w[:, 0] * p[:, 2] + v[:, 1]
    J6[:, 2] = w[:, 0] * p[:, 1] - w[:, 1] * p[:, 0] + v[:, 2]
    J6[:, 3:] = w
    return T, J6 @ model.coupling


_FIRST = [0]
_MASKS: dict = {}


def _joint_mask(model):
    """(1, 1, n_model): 1 for the model joints that move the first end effector (cached per model)."""
    key = id(model)
    hit = _MASKS.get(key)
    if hit is not None and hit[0] is model:
        return hit[1]
    _, _, _, masks = model.kinematics_with(np.zeros((1, model.n_joints)), None, None, _FIRST)
    link_of = model.params.link_of
    jm = np.array([masks[0][link_of == k].any() for k in model.moving], dtype=float)[None, None, :]
    if len(_MASKS) > 16:
        _MASKS.clear()
    _MASKS[key] = (model, jm)
    return jm


def _pose_error(T, T_target):
    """Position error (n, 3) [mm] and rotation error vector (n, 3) [rad] (world frame), target - actual.

    The rotation vector comes from the skew part of ``E = R_target R^T``: ``vee(E - E^T) / 2 =
    sin(angle) axis``, rescaled by ``asin``; exact below 90 deg (errors here are < 1e-2 rad) and
    much cheaper than a general logarithm."""
    dp = T_target[:, :3, 3] - T[:, :3, 3]
    E = T_target[:, :3, :3] @ np.swapaxes(T[:, :3, :3], 1, 2)
    v = 0.5 * np.stack([E[:, 2, 1] - E[:, 1, 2], E[:, 0, 2] - E[:, 2, 0], E[:, 1, 0] - E[:, 0, 1]], axis=1)
    sn = np.linalg.norm(v, axis=1)
    big = sn > 1e-8
    f = np.ones_like(sn)
    f[big] = np.arcsin(np.minimum(sn[big], 1.0)) / sn[big]
    if np.any(np.einsum("nii->n", E) < 1.0):        # some angle above 90 deg: use the general logarithm
        return dp, so3_log(E)
    return dp, v * f[:, None]


def compensate_program(model: RobotModel, warm, q_taught, *, position_only: bool = False, max_iterations: int = 3,
                       tol_mm: float = 1e-5, tol_rad: float = 1e-8, rotation_scale_mm: float = 1000.0,
                       T_flange_tool=None, cold_params=None, damping: float = 1e-12) -> CompensationResult:
    """Correct the joints of a taught program so the warm robot reaches the taught (cold) poses.

    model: the cold robot model. warm: the warm parameter vector (P,) [mm | rad], or a
        :class:`~robocal.thermal.drift.DriftResult` (its deltas are added to the model's values).
    q_taught: (n, n_joints) taught joints [rad]. Targets: ``FK_cold(q_taught)`` with ``cold_params``
        (default the model's).
    position_only: match the tool position only (3 equations, minimum-norm correction) instead of
        the full 6-D pose.
    max_iterations: Newton steps (the thesis: at most 3). tol_mm / tol_rad: a point whose error is
        within both stops early (its iteration count shows it).
    T_flange_tool: optional (4, 4) tool frame on the flange: the tool pose (position) is matched.
    damping: Tikhonov damping relative to the mean squared singular value (keeps a step finite
        at a wrist singularity; negligible elsewhere). Rotation rows are weighted
        ``rotation_scale_mm`` mm per rad.
    All points are processed together: one batched FK+Jacobian kernel call and one batched solve
    per iteration.
    """
    q0 = joint_rows(model, q_taught, "q_taught", "n", "point(s)", ValueError)
    warm_params = _warm_parameters(model, warm)
    cold = model.params.values if cold_params is None else np.asarray(cold_params, dtype=float)
    Tft = None if T_flange_tool is None else np.asarray(T_flange_tool, dtype=float).reshape(4, 4)
    jmask = _joint_mask(model)
    rows = slice(0, 3) if position_only else slice(0, 6)
    wrow = np.array([1.0, 1.0, 1.0] + [rotation_scale_mm] * 3)[rows]

    if cold_params is None and Tft is None:
        T_target = model.fk(q0)
    else:
        T_target, _ = _flange_kinematics(model, q0, cold, Tft, jmask, want_jacobian=False)
    q = q0.copy()
    n = len(q)
    iters = np.zeros(n, dtype=int)
    T, J = _flange_kinematics(model, q, warm_params, Tft, jmask)
    dp, dr = _pose_error(T, T_target)
    dp0, dr0 = dp, dr
    for _ in range(max_iterations):
        done = _within(dp, dr, tol_mm, tol_rad, position_only)
        if done.all():
            break
        dq = _newton_step(J[:, rows], np.concatenate([dp, dr], axis=1)[:, rows], wrow, damping)
        dq[done] = 0.0
        iters += ~done
        q = q + dq
        T, J = _flange_kinematics(model, q, warm_params, Tft, jmask)
        dp, dr = _pose_error(T, T_target)
    pos = np.linalg.norm(dp, axis=1)
    rot = np.zeros(n) if position_only else np.linalg.norm(dr, axis=1)
    conv = _within(dp, dr, tol_mm, tol_rad, position_only)
    return CompensationResult(q, q0, pos, rot, np.linalg.norm(dp0, axis=1), np.linalg.norm(dr0, axis=1), iters, conv,
                              model.within_limits(q), position_only)


def _warm_parameters(model, warm) -> np.ndarray:
    """The warm parameter vector (P,) from a vector or a :class:`DriftResult`."""
    warm_params = warm.warm_params(model) if isinstance(warm, DriftResult) else np.asarray(warm, dtype=float)
    if warm_params.shape != model.params.values.shape:
        raise ValueError(f"warm parameters: expected shape {model.params.values.shape}, got {warm_params.shape}")
    return warm_params


def _within(dp, dr, tol_mm: float, tol_rad: float, position_only: bool) -> np.ndarray:
    """(n,) bool: position error within ``tol_mm`` (and rotation within ``tol_rad``)."""
    ok = np.linalg.norm(dp, axis=1) <= tol_mm
    if not position_only:
        ok &= np.linalg.norm(dr, axis=1) <= tol_rad
    return ok


def _newton_step(J, r, wrow, damping: float) -> np.ndarray:
    """Damped Gauss-Newton joint steps (n, n_joints) for Jacobians ``J`` (n, rows, n_joints) and
    pose errors ``r`` (n, rows), rows weighted by ``wrow``; Tikhonov damping relative to the mean
    squared singular value."""
    r = r * wrow
    Jw = J * wrow[:, None]
    JJt = Jw @ np.swapaxes(Jw, 1, 2)
    lam = damping * np.trace(JJt, axis1=1, axis2=2) / JJt.shape[1]
    A = JJt + lam[:, None, None] * np.eye(JJt.shape[1])
    return (np.swapaxes(Jw, 1, 2) @ np.linalg.solve(A, r[..., None]))[..., 0]


def predicted_drift(model: RobotModel, delta_full, q, *, T_flange_tool=None) -> np.ndarray:
    """First-order drift (n, 3) [mm, model world frame] of the flange (or tool) point at joints ``q``
    caused by parameter deltas ``delta_full`` (P,): ``J_X(q) . dX``."""
    pt = None if T_flange_tool is None else np.asarray(T_flange_tool, float)[:3, 3]
    J = model.identification_jacobian(q, points=(0.0, 0.0, 0.0) if pt is None else pt)
    return J @ np.asarray(delta_full, dtype=float)


# ---------------------------------------------------------------------------------------------- the cycle
@dataclass
class OnlineCycle:
    """One online compensation cycle: the drift identification, the corrected program, and timing."""

    drift: DriftResult
    compensation: CompensationResult
    elapsed_s: float

    @property
    def q(self) -> np.ndarray:
        """The corrected program joints (n, n_joints) [rad]."""
        return self.compensation.q

    def summary(self) -> str:
        return (self.drift.summary() + "\n" + self.compensation.summary()
                + f"\ncycle computed in {self.elapsed_s * 1e3:.2f} ms")


def online_cycle(model: RobotModel, T_sensor_base, P_e, q_sphere, P_sphere, subset, q_program, *, P_cold=None,
                 position_only: bool = False, max_iterations: int = 3, T_flange_tool=None,
                 on_rank_deficient: str = "raise", point_sigma_mm: float | None = None) -> OnlineCycle:
    """Identify the screened deltas from the sphere measurements and correct a taught program.

    model: the cold robot model; T_sensor_base (4, 4), P_e (3,): the system calibration.
    q_sphere (m, n), P_sphere (m, 3): this cycle's sphere poses and measured centres (sensor frame,
        [mm]; ~6 poses); P_cold (m, 3): the cold reference at those poses (default: predicted).
    subset: the screened parameter names (e.g. 8 of them). q_program (n_points, n): taught joints.
    Returns an :class:`OnlineCycle` (the drift result, the corrected program, the time it took).
    """
    t0 = time.perf_counter()
    drift = identify_drift(model, T_sensor_base, P_e, q_sphere, P_sphere, P_cold, subset,
                           on_rank_deficient=on_rank_deficient, point_sigma_mm=point_sigma_mm)
    comp = compensate_program(model, drift.warm_params(model), q_program, position_only=position_only,
                              max_iterations=max_iterations, T_flange_tool=T_flange_tool)
    return OnlineCycle(drift, comp, time.perf_counter() - t0)


# ---------------------------------------------------------------------------------------------- when to measure
@dataclass(frozen=True)
class CycleRecord:
    """What the re-measurement rule needs from a past cycle: its time [s], identified deltas on the
    full parameter vector (P,) [mm | rad], the fit RMS [mm] and optionally a temperature [K or degC]."""

    time_s: float
    delta_full: np.ndarray
    rms_mm: float = 0.0
    temperature: float | None = None

    @classmethod
    def from_cycle(cls, time_s: float, cycle, temperature: float | None = None) -> "CycleRecord":
        """From an :class:`OnlineCycle` or a :class:`~robocal.thermal.drift.DriftResult`."""
        d = cycle.drift if isinstance(cycle, OnlineCycle) else cycle
        return cls(float(time_s), np.asarray(d.delta_full, float).copy(), d.rms_after_mm, temperature)


@dataclass(frozen=True)
class RemeasureDecision:
    """remeasure: measure the sphere now; reason: why (or why not); predicted_error_mm: the
    largest predicted error of the current correction at the monitored points (NaN when it
    cannot be predicted yet); next_due_s: the time at which the rule expects to need a
    measurement (absolute, same clock as the records)."""

    remeasure: bool
    reason: str
    predicted_error_mm: float
    next_due_s: float


@dataclass(frozen=True)
class RemeasureRule:
    """When to measure the sphere again.

    The correction in force is the one identified at the last cycle k (time ``t_k``, deltas
    ``dX_k``). The robot keeps heating or cooling, so the error of that correction grows. The
    rule extrapolates the parameter drift linearly from the last two cycles,
    ``dX(t) ~ dX_k + (t - t_k) / (t_k - t_{k-1}) (dX_k - dX_{k-1})``, and predicts the error the
    stale correction leaves at the monitored points (the taught program, or the monitored
    workpiece points), ``e_j(t) = |J_X(q_j) (dX(t) - dX_k)|`` (first-order flange drift). Measure
    again when any of these holds (checked in this order):

    1. there is no previous cycle;
    2. the last identification did not fit (``rms_mm > max_fit_rms_mm``): the deltas do not
       explain the sphere movement (collision, loose sphere, a parameter outside the screened set);
    3. ``t - t_k >= max_interval_s`` (a safety net, also covers the case of a single cycle, where
       no rate is known yet);
    4. a temperature is given and has changed by ``>= max_temperature_change`` since cycle k;
    5. ``max_j e_j(t) >= threshold_mm`` (default 0.05 mm: half of the 0.1 mm tolerance of the
       thesis's lambda metric, so the correction is refreshed well before points leave it).

    ``next_due_s`` is when (5) is expected to trigger (linear growth of e), capped by (3).
    """

    threshold_mm: float = 0.05
    max_interval_s: float = 1800.0
    max_temperature_change: float = 2.0
    max_fit_rms_mm: float = 0.05

    def decide(self, now_s: float, records, model: RobotModel | None = None, q_monitor=None, *,
               temperature: float | None = None, T_flange_tool=None) -> RemeasureDecision:
        """Apply the rule at time ``now_s`` given past cycles ``records`` (sequence of
        :class:`CycleRecord`, any order) and the monitored joints ``q_monitor`` (n, n_joints) of
        ``model`` (needed for the drift prediction, rule 5)."""
        recs = sorted(records, key=lambda r: r.time_s)
        if not recs:
            return RemeasureDecision(True, "no previous compensation cycle", float("nan"), now_s)
        last = recs[-1]
        cap = last.time_s + self.max_interval_s
        if last.rms_mm > self.max_fit_rms_mm:
            return RemeasureDecision(True, f"the last identification left {last.rms_mm:.3f} mm RMS "
                                           f"(> {self.max_fit_rms_mm} mm): the screened deltas did not explain the "
                                           f"sphere movement", float("nan"), now_s)
        elapsed = now_s - last.time_s
        if elapsed >= self.max_interval_s:
            return RemeasureDecision(True, f"{elapsed:.0f} s since the last cycle (limit {self.max_interval_s:.0f} s)",
                                     float("nan"), now_s)
        if temperature is not None and last.temperature is not None and \
                abs(temperature - last.temperature) >= self.max_temperature_change:
            return RemeasureDecision(True, f"temperature changed by {temperature - last.temperature:+.2f} since the "
                                           f"last cycle (limit {self.max_temperature_change})", float("nan"), now_s)
        if len(recs) < 2 or model is None or q_monitor is None:
            why = "only one cycle so far (no drift rate yet)" if len(recs) < 2 else "no monitored points given"
            return RemeasureDecision(False, f"{why}; next measurement by the interval limit", float("nan"), cap)
        prev = recs[-2]
        dt = last.time_s - prev.time_s
        if dt <= 0:
            raise ValueError("two cycle records have the same time")
        rate = (np.asarray(last.delta_full) - np.asarray(prev.delta_full)) / dt        # per second
        e_rate = np.linalg.norm(predicted_drift(model, rate, q_monitor, T_flange_tool=T_flange_tool), axis=1).max()
        err = float(e_rate * elapsed)
        due = min(cap, last.time_s + self.threshold_mm / e_rate) if e_rate > 0 else cap
        if err >= self.threshold_mm:
            return RemeasureDecision(True, f"predicted error of the current correction {err:.3f} mm >= "
                                           f"{self.threshold_mm} mm at the monitored points", err, now_s)
        return RemeasureDecision(False, f"predicted error {err:.3f} mm < {self.threshold_mm} mm", err, due)
