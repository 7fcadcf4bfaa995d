"""Quick verification of a calibrated robot: is it still what its calibration promised?

A handful of poses is measured and compared with the calibrated model's prediction. Under the
hypothesis "nothing changed", the residual ``r = measured − predicted`` (3N,) is normal with zero
mean and covariance ``Σ = J_p·C_p·J_pᵀ + σ²·I`` — the calibration's own uncertainty propagated to
the poses plus the instrument noise. The statistic ``T = rᵀ Σ⁻¹ r`` then follows a χ² law with
``3N`` degrees of freedom (``3N − 6`` when the instrument frame is re-registered on the same
points), so ``T > χ²_{1−α}`` raises a false alarm with probability ``α`` exactly (in the linear
approximation).

When the test fails, each joint's offset is tried as the one cause: the weighted least-squares fit
of a single offset ``δ_j`` along the joint's column of the position Jacobian. If one joint's
offset explains the residual (the remaining statistic passes its own χ² test with one degree of
freedom fewer, and the reduction is significant) the decision is **mechanical fault suspected**,
naming the joint and the size of the jump; otherwise **recalibrate**.

When the approach direction of every joint is known per pose (``s_ij = +1`` when joint j arrived
at pose i moving in its positive direction, −1 in its negative one), each joint's **backlash** is
a candidate too: a joint with backlash ``b`` stops ``b/2`` short of where it was sent, so the
residual it leaves is ``−J_ij · s_ij · b/2`` (the sign follows the approach). Its column is fitted
like an offset's; a joint approached from one side only at every pose cannot be told from an
offset and gets no backlash candidate. The best candidate of all (offsets and backlashes) decides,
and the result names the cause (``offset`` or ``backlash``).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.stats import chi2

__all__ = ["VerificationResult", "verify_positions", "DECISIONS"]

#: the three decisions, in order of severity
DECISIONS = ("ok", "recalibrate", "mechanical fault suspected")


@dataclass(frozen=True)
class VerificationResult:
    """The outcome of :func:`verify_positions`.

    Attributes
    ----------
    decision : str
        One of :data:`DECISIONS`.
    statistic : float
        ``T = rᵀ Σ⁻¹ r`` (dimensionless).
    dof : int
        Degrees of freedom of its χ² law.
    threshold : float
        ``χ²_{1−α}(dof)``.
    false_alarm_rate : float
        ``α``.
    p_value : float
    rms_mm, max_mm : float
        Position residual statistics [mm].
    suspect_joint : str or None
        The joint whose offset (or backlash) alone explains the residual (decision "mechanical
        fault suspected").
    suspect_cause : str or None
        ``"offset"`` or ``"backlash"``.
    suspect_offset : float or None
        Its fitted offset, or the full backlash ``b`` [rad | mm].
    suspect_offset_sigma : float or None
    joint_statistics : dict
        Remaining statistic after each joint's single-offset fit.
    reasons : list of str
    """

    decision: str
    statistic: float
    dof: int
    threshold: float
    false_alarm_rate: float
    p_value: float
    rms_mm: float
    max_mm: float
    suspect_joint: str | None = None
    suspect_cause: str | None = None
    suspect_offset: float | None = None
    suspect_offset_sigma: float | None = None
    joint_statistics: dict = field(default_factory=dict)
    reasons: list = field(default_factory=list)


def _rigid_columns(predicted: np.ndarray) -> np.ndarray:
    """(3N, 6): the linearised effect of a small frame translation and rotation on each point."""
    N = len(predicted)
    A = np.zeros((N, 3, 6))
    A[:, :, :3] = np.eye(3)
    p = predicted
    # d(R p)/d(omega) = -[p]x
    A[:, 0, 4], A[:, 0, 5] = p[:, 2], -p[:, 1]
    A[:, 1, 3], A[:, 1, 5] = -p[:, 2], p[:, 0]
    A[:, 2, 3], A[:, 2, 4] = p[:, 1], -p[:, 0]
    return A.reshape(3 * N, 6)


def _whiten(cov: np.ndarray) -> np.ndarray:
    """A matrix ``L⁻¹`` with ``L Lᵀ = cov`` (Cholesky), so that ``L⁻¹ r`` is white."""
    L = np.linalg.cholesky(cov)
    return np.linalg.inv(L)


def _remaining(Wr: np.ndarray, WA: np.ndarray | None) -> float:
    """``|Wr|² − |projection of Wr on the columns WA|²`` (the least-squares remainder)."""
    if WA is None or WA.shape[1] == 0:
        return float(Wr @ Wr)
    coef, *_ = np.linalg.lstsq(WA, Wr, rcond=None)
    e = Wr - WA @ coef
    return float(e @ e)


def verify_positions(measured_mm, predicted_mm, *, instrument_sigma_mm: float, prediction_covariance_mm2=None,
                     joint_jacobian=None, joint_names=None, false_alarm_rate: float = 0.01,
                     register_frame: bool = False, approach_signs=None) -> VerificationResult:
    """The χ² verification of measured against predicted positions, and the fault diagnosis.

    Parameters
    ----------
    measured_mm, predicted_mm : array_like, shape (N, 3)
        Measured and model-predicted positions [mm], in the same frame.
    instrument_sigma_mm : float
        Standard deviation of one measured coordinate [mm] (> 0).
    prediction_covariance_mm2 : array_like, shape (3N, 3N) or (N, 3, 3), optional
        Covariance of the predictions from the calibration [mm²] (full, with the correlation
        between poses, or per pose). Omitted: the model is taken as exact.
    joint_jacobian : array_like, shape (N, 3, n_joints), optional
        ``∂p/∂q`` at each pose [mm per rad | mm per mm], for the single-joint diagnosis.
    joint_names : sequence of str, optional
    false_alarm_rate : float
        ``α`` in (0, 0.5): the probability that a healthy robot is flagged.
    register_frame : bool
        Re-fit the instrument frame (6 DoF) on the same points: use when the instrument was moved
        since the calibration. Base-like errors (including a J1 offset) are then not checked.
    approach_signs : array_like, shape (N, n_joints), optional
        +1 / −1: the direction each joint moved in when it arrived at each pose (0: unknown). With
        it, each joint's backlash is a candidate of the diagnosis as well.

    Returns
    -------
    VerificationResult
    """
    from ..errors import InputError

    m = np.asarray(measured_mm, float).reshape(-1, 3)
    p = np.asarray(predicted_mm, float).reshape(-1, 3)
    if m.shape != p.shape:
        raise InputError(f"measured {m.shape} and predicted {p.shape} positions differ in shape")
    N = len(m)
    n_free = 6 if register_frame else 0
    if 3 * N - n_free < 3:
        raise InputError(f"verification needs more poses: {N} given" + (" with frame registration" if n_free else ""))
    if not (instrument_sigma_mm > 0 and np.isfinite(instrument_sigma_mm)):
        raise InputError(f"instrument noise must be > 0 mm, got {instrument_sigma_mm}")
    if not 0 < false_alarm_rate < 0.5:
        raise InputError(f"false-alarm rate must be in (0, 0.5), got {false_alarm_rate}")
    if approach_signs is not None:
        S = np.asarray(approach_signs, float)
        n_q = None if joint_jacobian is None else np.shape(joint_jacobian)[-1]
        if S.ndim != 2 or S.shape[0] != N or (n_q is not None and S.shape[1] != n_q):
            raise InputError(f"approach signs must have shape ({N}, {n_q or 'n_joints'}), got {S.shape}")
        if not np.all(np.isin(S, (-1.0, 0.0, 1.0))):
            raise InputError("approach signs must be +1, -1 or 0 (unknown)")
    cov = np.eye(3 * N) * instrument_sigma_mm ** 2
    if prediction_covariance_mm2 is not None:
        C = np.asarray(prediction_covariance_mm2, float)
        if C.shape == (N, 3, 3):
            for i in range(N):
                cov[3 * i:3 * i + 3, 3 * i:3 * i + 3] += C[i]
        elif C.shape == (3 * N, 3 * N):
            cov += C
        else:
            raise InputError(f"prediction covariance must have shape ({3 * N}, {3 * N}) or ({N}, 3, 3), got {C.shape}")
    W = _whiten(cov)
    r = (m - p).reshape(-1)
    Wr = W @ r
    A = _rigid_columns(p) if register_frame else np.zeros((3 * N, 0))
    WA = W @ A
    T = _remaining(Wr, WA)
    dof = 3 * N - n_free
    thr = float(chi2.ppf(1 - false_alarm_rate, dof))
    dist = np.linalg.norm(m - p, axis=1)
    common = dict(statistic=T, dof=dof, threshold=thr, false_alarm_rate=false_alarm_rate,
                  p_value=float(chi2.sf(T, dof)), rms_mm=float(np.sqrt(np.mean(dist ** 2))), max_mm=float(dist.max()))
    if T <= thr:
        return VerificationResult("ok", reasons=[f"T = {T:.1f} <= {thr:.1f} = chi2_(1-{false_alarm_rate:g})({dof})"],
                                  **common)
    reasons = [f"T = {T:.1f} > {thr:.1f} = chi2_(1-{false_alarm_rate:g})({dof}): the robot is not what its "
               "calibration predicts"]
    if joint_jacobian is None or dof < 2:
        return VerificationResult("recalibrate", reasons=reasons, **common)
    J = np.asarray(joint_jacobian, float)
    n = J.shape[-1]
    names = list(joint_names) if joint_names is not None else [f"J{k + 1}" for k in range(n)]
    candidates = [(names[k], "offset", J[:, :, k]) for k in range(n)]
    if approach_signs is not None:
        S = np.asarray(approach_signs, float)
        for k in range(n):
            if len(np.unique(S[:, k][S[:, k] != 0])) == 2:     # both sides: backlash differs from an offset
                candidates.append((names[k], "backlash", -0.5 * J[:, :, k] * S[:, k:k + 1]))
    stats = {}
    fits = {}
    for name, cause, colk in candidates:
        col = colk.reshape(-1, 1)
        if np.linalg.norm(col) < 1e-9:
            continue
        WAk = np.hstack([WA, W @ col])
        Tk = _remaining(Wr, WAk)
        key = name if cause == "offset" else f"{name} backlash"
        stats[key] = Tk
        coef, *_ = np.linalg.lstsq(WAk, Wr, rcond=None)
        cov_k = np.linalg.pinv(WAk.T @ WAk)
        fits[key] = (name, cause, float(coef[-1]), float(np.sqrt(max(cov_k[-1, -1], 0.0))))
    if not stats:
        return VerificationResult("recalibrate", reasons=reasons, joint_statistics=stats, **common)
    best = min(stats, key=stats.get)
    T_best = stats[best]
    thr1 = float(chi2.ppf(1 - false_alarm_rate, dof - 1))
    lr_thr = float(chi2.ppf(1 - false_alarm_rate, 1))
    if T_best <= thr1 and T - T_best > lr_thr:
        joint, cause, delta, sd = fits[best]
        reasons.append(f"one {cause} of {joint} explains it: remaining T = {T_best:.1f} <= {thr1:.1f}")
        others = [k for k, v in stats.items() if k != best and v <= thr1]
        if others:
            reasons.append(f"also consistent with {', '.join(o if ' ' in o else o + ' offset' for o in others)} "
                           "(less likely)")
        return VerificationResult("mechanical fault suspected", suspect_joint=joint, suspect_cause=cause,
                                  suspect_offset=delta, suspect_offset_sigma=sd, joint_statistics=stats,
                                  reasons=reasons, **common)
    reasons.append(f"no single joint offset{' or backlash' if approach_signs is not None else ''} explains it "
                   f"(best {best}: remaining T = {T_best:.1f} > {thr1:.1f})")
    return VerificationResult("recalibrate", joint_statistics=stats, reasons=reasons, **common)
