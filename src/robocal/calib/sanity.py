"""Sanity gates on results: is a fitted answer physically believable?

A least-squares solver always returns *something*. These gates turn the silent wrong answer (a file
with swapped joint columns, x and z exchanged, radians declared as degrees, 500 mm of noise, random
points) into a **failed** result with reasons that name the likely cause. They compare

* the residuals with the declared instrument noise (or, without one, an absolute bound),
* the result with the uncalibrated error (held-out error must not get worse; the nominal model
  must fit the data roughly, or the data do not describe this robot),
* the parameter changes with physical plausibility (a link length or an angle offset a real robot
  cannot have drifted by).

Every bound is a module constant, stated in docs/reliability.md. The gates take numbers only
(millimetres, radians); the workflows put the :class:`Verdict` into ``result.json`` (``status``,
``reasons``), the report (a banner) and the exit code of the command line.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

__all__ = [
    "Verdict", "NOISE_FACTOR", "RESIDUAL_LIMIT_MM", "NOMINAL_MISFIT_MM", "HOLDOUT_WORSE_FACTOR",
    "LENGTH_CHANGE_MM", "LENGTH_CHANGE_FRACTION", "ANGLE_CHANGE_DEG", "TOOL_LENGTH_LIMIT_MM",
    "residual_reasons", "holdout_reasons", "nominal_misfit_reasons", "parameter_reasons",
    "calibration_verdict", "touchup_verdict", "sensor_verdict", "tool_length_reasons", "leave_one_out_reasons",
    "seven_point_reasons", "seven_point_verdict", "barriers_verdict", "LOO_MIN_MM", "LOO_FACTOR", "SEVEN_POINT_ORTHOGONALITY_DEG", "TOOL_AXIS_BACK_DEG", "BEAM_ANGLE_TOLERANCE_DEG", "BEAM_GAP_LIMIT_MM",
    "NEGATIVE_COMPLIANCE_SIGMAS", "COMPLIANCE_SIGNIFICANCE_SIGMAS", "elastic_reasons",
]

#: Residual RMS (3-D point error) above this multiple of the noise's expected RMS
#: (sqrt(3) * sigma per coordinate) fails.
NOISE_FACTOR = 10.0
#: Without declared noise: a calibrated residual RMS above this [mm] fails.
RESIDUAL_LIMIT_MM = 5.0
#: The nominal robot with its best-fit instrument frame missing the data by more than this RMS [mm]:
#: the data do not describe this robot (industrial robots are off by 1-10 mm before calibration).
NOMINAL_MISFIT_MM = 50.0
#: Held-out RMS after calibration above this multiple of the one before fails ("got worse").
HOLDOUT_WORSE_FACTOR = 1.1
#: A length parameter may change by at most max(LENGTH_CHANGE_MM, LENGTH_CHANGE_FRACTION * |nominal|).
LENGTH_CHANGE_MM = 25.0
LENGTH_CHANGE_FRACTION = 0.05
#: An angle parameter (offset, twist) may change by at most this [deg].
ANGLE_CHANGE_DEG = 5.0
#: A touch-up TCP farther than this from the flange [mm] is no tool a robot carries.
TOOL_LENGTH_LIMIT_MM = 2000.0
#: Touch-up leave-one-out: a pose missing the point the others define by more than
#: max(LOO_MIN_MM, LOO_FACTOR x the RMS of the others' fit) fails.
LOO_MIN_MM = 1.0
LOO_FACTOR = 5.0
#: 7-point: the X and Z moves within this of 90 deg [deg]; the tool Z axis within this of the TCP vector [deg].
SEVEN_POINT_ORTHOGONALITY_DEG = 15.0
TOOL_AXIS_BACK_DEG = 120.0
#: A cross-laser sensor's beams cross within this of 90 deg [deg] and pass closer than this [mm].
#: thermal drift of an arm: a length delta beyond this [mm] or an angle delta beyond
#: ``DRIFT_ANGLE_DEG`` is not heat (the thesis's arm drifts 0.1-0.5 mm at the TCP over 3 h)
DRIFT_LENGTH_MM = 5.0
DRIFT_ANGLE_DEG = 0.5
BEAM_ANGLE_TOLERANCE_DEG = 10.0
BEAM_GAP_LIMIT_MM = 20.0
#: An identified compliance below minus this many standard deviations is physically impossible (a
#: joint that deflects against the load): the elastic model does not describe the data.
NEGATIVE_COMPLIANCE_SIGMAS = 2.0

_CAUSE_DATA = ("likely swapped joint or x/y/z columns, angles or lengths in another unit than declared, or the "
               "measurements of another robot")


@dataclass(frozen=True)
class Verdict:
    """Outcome of the sanity gates: ``status`` ``"ok"`` or ``"failed"`` and the ``reasons`` of a
    failure (one sentence each, naming the likely cause); ``checks`` records every gate tried
    (name -> dict of value, limit, passed)."""

    reasons: tuple = ()
    checks: dict = field(default_factory=dict)

    @property
    def ok(self) -> bool:
        return not self.reasons

    @property
    def status(self) -> str:
        return "ok" if self.ok else "failed"

    def to_dict(self) -> dict:
        return {"status": self.status, "reasons": list(self.reasons), "checks": dict(self.checks)}

    def __add__(self, other: "Verdict") -> "Verdict":
        return Verdict(self.reasons + other.reasons, {**self.checks, **other.checks})


def _check(checks: dict, name: str, value: float, limit: float, unit: str) -> bool:
    passed = bool(math.isfinite(value) and value <= limit)
    checks[name] = {"value": float(value), "limit": float(limit), "unit": unit, "passed": passed}
    return passed


def residual_reasons(rms_mm: float, sigma_mm: float | None, checks: dict, what: str = "residual") -> list:
    """The residual RMS [mm] (3-D point errors) against ``NOISE_FACTOR`` x the expected noise RMS
    (``sqrt(3) sigma_mm``), or against ``RESIDUAL_LIMIT_MM`` when no noise is declared."""
    if sigma_mm:
        expected = math.sqrt(3.0) * sigma_mm
        if _check(checks, f"{what}_vs_noise", rms_mm, NOISE_FACTOR * expected, "mm"):
            return []
        return [f"{what} RMS {rms_mm:.4g} mm is {rms_mm / expected:.0f} x the declared instrument noise "
                f"(sigma {sigma_mm:g} mm per coordinate, {expected:.3g} mm expected; limit {NOISE_FACTOR:g} x): "
                "likely noise far above the declared value, outlier poses, or a wrong robot model"]
    if _check(checks, f"{what}_absolute", rms_mm, RESIDUAL_LIMIT_MM, "mm"):
        return []
    return [f"{what} RMS {rms_mm:.4g} mm exceeds {RESIDUAL_LIMIT_MM:g} mm (no instrument noise declared): "
            f"{_CAUSE_DATA}, or a very noisy instrument"]


def nominal_misfit_reasons(rms_before_mm: float, robot: str, checks: dict) -> list:
    """The nominal model's RMS [mm] with its best-fit instrument frame against ``NOMINAL_MISFIT_MM``."""
    if _check(checks, "nominal_misfit", rms_before_mm, NOMINAL_MISFIT_MM, "mm"):
        return []
    return [f"the nominal {robot} misses the measurements by {rms_before_mm:.4g} mm RMS even with the best-fit "
            f"instrument frame (limit {NOMINAL_MISFIT_MM:g} mm): the data do not describe this robot; {_CAUSE_DATA}"]


def holdout_reasons(before_mm: float, after_mm: float, checks: dict) -> list:
    """Held-out RMS [mm] after calibration against ``HOLDOUT_WORSE_FACTOR`` x the one before."""
    if _check(checks, "holdout_worse", after_mm, HOLDOUT_WORSE_FACTOR * before_mm, "mm"):
        return []
    return [f"held-out error got worse: {before_mm:.4g} -> {after_mm:.4g} mm RMS (limit {HOLDOUT_WORSE_FACTOR:g} x "
            f"before): the calibration does not generalise; {_CAUSE_DATA}, duplicate or mislabelled poses"]


def parameter_reasons(names, units, nominal, calibrated, checks: dict) -> list:
    """Parameter changes beyond physical plausibility, as one reason naming the worst three:
    lengths (unit ``mm``) by more than max(``LENGTH_CHANGE_MM``, ``LENGTH_CHANGE_FRACTION``
    |nominal|), angles (unit ``rad``) by more than ``ANGLE_CHANGE_DEG``. Other units are not judged."""
    bad, worst = [], 0.0
    for name, unit, v0, v1 in zip(names, units, nominal, calibrated):
        d = float(v1) - float(v0)
        if unit == "mm":
            ratio, text = abs(d) / max(LENGTH_CHANGE_MM, LENGTH_CHANGE_FRACTION * abs(float(v0))), f"{d:+.4g} mm"
        elif unit == "rad":
            ratio, text = abs(math.degrees(d)) / ANGLE_CHANGE_DEG, f"{math.degrees(d):+.4g} deg"
        else:
            continue
        worst = max(worst, ratio)
        if ratio > 1.0:
            bad.append((ratio, f"{name} {text}"))
    checks["parameter_change"] = {"value": worst, "limit": 1.0, "unit": "fraction of the bound", "passed": not bad}
    if not bad:
        return []
    bad.sort(reverse=True)
    shown = ", ".join(t for _, t in bad[:3]) + (f" and {len(bad) - 3} more" if len(bad) > 3 else "")
    return [f"{len(bad)} parameter(s) changed beyond physical plausibility ({shown}; limits: lengths "
            f"max({LENGTH_CHANGE_MM:g} mm, {LENGTH_CHANGE_FRACTION:.0%} of nominal), angles {ANGLE_CHANGE_DEG:g} deg): "
            "not a real robot's deviation; likely swapped joint columns, wrong units or the wrong robot model"]


def calibration_verdict(*, robot: str, rms_before_mm: float, rms_after_mm: float, sigma_mm: float | None = None,
                        holdout_before_mm: float | None = None, holdout_after_mm: float | None = None,
                        parameters=None) -> Verdict:
    """The gates of a geometric calibration.

    rms_before_mm: RMS point error of the nominal model with the best-fit instrument frame and
    targets; rms_after_mm: of the calibrated model (calibration poses). holdout_*: held-out RMS
    before/after (omit without held-out poses). parameters: ``(names, units, nominal, calibrated)``
    of the kinematic parameters (mm / rad).
    """
    checks: dict = {}
    reasons = nominal_misfit_reasons(rms_before_mm, robot, checks)
    reasons += residual_reasons(rms_after_mm, sigma_mm, checks)
    if holdout_before_mm is not None and holdout_after_mm is not None:
        reasons += holdout_reasons(holdout_before_mm, holdout_after_mm, checks)
    if parameters is not None:
        reasons += parameter_reasons(*parameters, checks)
    return Verdict(tuple(reasons), checks)


def tool_length_reasons(length_mm: float, checks: dict, what: str) -> list:
    """A tool (or point on the flange) farther than ``TOOL_LENGTH_LIMIT_MM`` from the flange."""
    if _check(checks, "tool_length", length_mm, TOOL_LENGTH_LIMIT_MM, "mm"):
        return []
    return [f"{what}: {length_mm:.4g} mm from the flange (limit {TOOL_LENGTH_LIMIT_MM:g} mm): no tool a robot "
            "carries; likely lengths in another unit than declared (millimetres declared as metres?)"]


def leave_one_out_reasons(loo, labels, checks: dict) -> list:
    """Touch-up poses whose leave-one-out miss exceeds max(``LOO_MIN_MM``, ``LOO_FACTOR`` x the
    RMS of the fit over the others): named as poses that touched another point. loo: ``(miss (N,),
    rms_others (N,))`` [mm] of :func:`robocal.tcp.touchup.leave_one_out_residuals`."""
    miss, rms_others = (np.asarray(v, dtype=float) for v in loo)
    if not np.isfinite(miss).any():
        return []
    limits = np.maximum(LOO_MIN_MM, LOO_FACTOR * rms_others)
    ratio = miss / limits
    worst = int(np.nanargmax(ratio))
    if _check(checks, "leave_one_out", float(ratio[worst]), 1.0, "fraction of the limit"):
        return []
    bad = [i for i in np.argsort(-ratio) if ratio[i] > 1.0]
    names = ", ".join(f"{labels[i] if labels is not None and len(labels) > i else i} misses by {miss[i]:.3g} mm "
                      f"(the others fit to {rms_others[i]:.3g} mm RMS)" for i in bad[:5])
    return [f"{len(bad)} touch-up pose(s) miss the point the others define (limit max({LOO_MIN_MM:g} mm, "
            f"{LOO_FACTOR:g} x the others' RMS); leave-one-out: {names}: likely a pose that touched another spot, or "
            "a typo; retake it"]


def seven_point_reasons(orthogonality_error_deg: float, T_flange_tool, checks: dict) -> list:
    """The 7-point method's moves: X (P5 -> P6) and Z (P6 -> P7) about 90 deg apart (within
    ``SEVEN_POINT_ORTHOGONALITY_DEG``), and the tool Z axis not pointing back at the flange (more
    than ``TOOL_AXIS_BACK_DEG`` from the TCP vector, for a TCP beyond 20 mm)."""
    reasons = []
    if not _check(checks, "seven_point_orthogonality", abs(orthogonality_error_deg), SEVEN_POINT_ORTHOGONALITY_DEG,
                  "deg"):
        reasons.append(f"the X move (P5 -> P6) and the Z move (P6 -> P7) are {90 + orthogonality_error_deg:.3g} deg "
                       f"apart, not 90 (limit {SEVEN_POINT_ORTHOGONALITY_DEG:g} deg): likely P6 and P7 swapped, or a "
                       "move not along the tool's axes")
    T = np.asarray(T_flange_tool, dtype=float)
    t = T[:3, 3]
    if np.linalg.norm(t) > 20.0:
        angle = math.degrees(math.acos(float(np.clip(T[:3, 2] @ t / np.linalg.norm(t), -1.0, 1.0))))
        if not _check(checks, "tool_axis_direction", angle, TOOL_AXIS_BACK_DEG, "deg"):
            reasons.append(f"the tool Z axis is {angle:.3g} deg from the TCP vector (limit {TOOL_AXIS_BACK_DEG:g} "
                           "deg): it points back at the flange; likely P6 and P7 swapped or the Z move reversed")
    return reasons


def touchup_verdict(rms_mm: float, tcp_mm, sigma_mm: float | None = None, what: str = "touch-up",
                    loo_mm=None, labels=None) -> Verdict:
    """The gates of a point on the flange fitted from poses (a touch-up TCP, the sphere centre
    ``P_e`` of a thermal system calibration): the residual RMS [mm] (:func:`residual_reasons`) and
    the point's distance from the flange ``|tcp_mm|`` against ``TOOL_LENGTH_LIMIT_MM``. (Metres
    read as mm give a tool of a few mm and tiny residuals; the readers' unit checker catches that.)
    loo_mm: ``(miss, rms_others)`` of :func:`robocal.tcp.touchup.leave_one_out_residuals`, judged by
    :func:`leave_one_out_reasons` (labels name the poses)."""
    checks: dict = {}
    reasons = residual_reasons(rms_mm, sigma_mm, checks, what=f"{what} residual")
    if loo_mm is not None:
        reasons += leave_one_out_reasons(loo_mm, labels, checks)
    length = math.sqrt(sum(float(v) ** 2 for v in tcp_mm))
    if not _check(checks, "tool_length", length, TOOL_LENGTH_LIMIT_MM, "mm"):
        reasons.append(f"{what}: the fitted point is {length:.4g} mm from the flange (limit {TOOL_LENGTH_LIMIT_MM:g} "
                       "mm): likely lengths in another unit than declared or poses that do not touch one point")
    return Verdict(tuple(reasons), checks)


def seven_point_verdict(orthogonality_error_deg: float, T_flange_tool, touch: Verdict | None = None) -> Verdict:
    """The gates of a 7-point tool frame: the touch-up's verdict (when the TCP came from touch-up
    poses), :func:`seven_point_reasons` and the tool length."""
    checks: dict = dict(touch.checks) if touch is not None else {}
    reasons = list(touch.reasons) if touch is not None else []
    reasons += seven_point_reasons(orthogonality_error_deg, T_flange_tool, checks)
    if "tool_length" not in checks:
        reasons += tool_length_reasons(float(np.linalg.norm(np.asarray(T_flange_tool)[:3, 3])), checks, "the TCP")
    return Verdict(tuple(reasons), checks)


def barriers_verdict(tcp_mm=None, length_mm: float | None = None) -> Verdict:
    """The gates of a parallel-barrier tool: its length D and TCP against ``TOOL_LENGTH_LIMIT_MM``."""
    checks: dict = {}
    reasons = []
    if length_mm is not None:
        reasons += tool_length_reasons(abs(float(length_mm)), checks, "the tool length D")
    elif tcp_mm is not None:
        reasons += tool_length_reasons(float(np.linalg.norm(tcp_mm)), checks, "the TCP")
    return Verdict(tuple(reasons), checks)


def sensor_verdict(beta_deg: float, gap_mm: float) -> Verdict:
    """The gates of a cross-laser sensor calibration: the angle between the beams within
    ``BEAM_ANGLE_TOLERANCE_DEG`` of 90 deg and the gap between them below ``BEAM_GAP_LIMIT_MM``
    (a mounted sensor's beams cross nearly at right angles; swapped labels or units do not)."""
    checks: dict = {}
    reasons = []
    if not _check(checks, "beam_angle", abs(beta_deg - 90.0), BEAM_ANGLE_TOLERANCE_DEG, "deg"):
        reasons.append(f"the beams cross at {beta_deg:.4g} deg, {beta_deg - 90.0:+.3g} deg from 90 (limit "
                       f"{BEAM_ANGLE_TOLERANCE_DEG:g} deg): likely swapped point labels (A-D) or points of another "
                       "sensor")
    if not _check(checks, "beam_gap", gap_mm, BEAM_GAP_LIMIT_MM, "mm"):
        reasons.append(f"the beams pass {gap_mm:.4g} mm apart (limit {BEAM_GAP_LIMIT_MM:g} mm): likely swapped point "
                       "labels or lengths in another unit than declared")
    return Verdict(tuple(reasons), checks)


def drift_verdict(names, units, delta, residual_rms_mm: float, sigma_mm: float | None = None) -> Verdict:
    """Gates on an online thermal identification (thesis (3-8)-(3-10)): the sphere residual left by
    the identified deltas against the noise (:func:`residual_reasons`), and every delta within what
    heat can do (``DRIFT_LENGTH_MM``, ``DRIFT_ANGLE_DEG``). names, units ("mm" | "rad"), delta (k,)."""
    checks: dict = {}
    reasons = residual_reasons(residual_rms_mm, sigma_mm, checks, what="drift fit residual")
    worst = []
    for n, u, d in zip(names, units, np.asarray(delta, float)):
        limit, value = (DRIFT_LENGTH_MM, abs(d)) if u == "mm" else (DRIFT_ANGLE_DEG, abs(math.degrees(d)))
        if not _check(checks, f"drift_{n}", value, limit, "mm" if u == "mm" else "deg"):
            worst.append(f"{n} {value:.4g} {'mm' if u == 'mm' else 'deg'}")
    if worst:
        reasons.append(f"identified thermal deltas beyond what heat does to an arm (limits {DRIFT_LENGTH_MM:g} mm, "
                       f"{DRIFT_ANGLE_DEG:g} deg): {', '.join(worst)}: {_CAUSE_DATA}, a sensor that moved, "
                       "or sphere poses that do not match the cold reference")
    return Verdict(tuple(reasons), checks)


#: a compliance counts as identified only when it exceeds this many standard deviations: one-sided
#: 2 sigma, so that a rigid joint passes for an elastic one about one time in 40 (with six joints a
#: 1 sigma rule would "identify" one of a rigid robot's compliances more often than not)
COMPLIANCE_SIGNIFICANCE_SIGMAS = 2.0


def elastic_reasons(rows, checks: dict | None = None) -> tuple:
    """The plausibility gate of an elastic calibration (docs/elastic.md, docs/reliability.md).

    rows: dicts ``name``, ``value``, ``std`` (None when not identifiable), ``unit``, ``identifiable``
    of every compliance (``compliance.*``, ``lateral.*``: mrad/kNm or mm/kN) and mass parameter
    (``gravity.*``: kg, kg m) of the fit. A quantity whose standard deviation is at least its
    magnitude, a compliance below zero or below ``COMPLIANCE_SIGNIFICANCE_SIGMAS`` (2) sigma, is
    **not identified** (the data cannot tell it from zero, or it has no physical meaning); a compliance below ``-NEGATIVE_COMPLIANCE_SIGMAS`` sigma, or a
    fit in which no compliance is identified (a rigid robot: nothing to model), fails.

    Returns ``(reasons, not_identified)``: failure sentences, and ``[{name, value, std, unit, why}]``.
    """
    checks = {} if checks is None else checks
    reasons, not_identified = [], []
    identified_compliances, negative = [], []
    for r in rows:
        name, v, sd = r["name"], float(r["value"]), r.get("std")
        if not r.get("identifiable", True) or sd is None or not math.isfinite(sd):
            continue
        is_compliance = name.startswith(("compliance.", "lateral."))
        why = None
        if is_compliance and v < -NEGATIVE_COMPLIANCE_SIGMAS * sd:
            negative.append(f"{name} = {v:.4g} +- {sd:.2g} {r['unit']}")
            why = f"negative ({v:.4g} +- {sd:.2g} {r['unit']}): a joint cannot deflect against its load"
        elif is_compliance and v < 0:
            why = f"negative but within {NEGATIVE_COMPLIANCE_SIGMAS:g} sigma of zero ({v:.4g} +- {sd:.2g} {r['unit']})"
        elif is_compliance and v < COMPLIANCE_SIGNIFICANCE_SIGMAS * sd:
            why = (f"{v:.4g} +- {sd:.2g} {r['unit']}: within {COMPLIANCE_SIGNIFICANCE_SIGMAS:g} sigma of zero "
                   "(a rigid joint would show this one time in ~40)")
        elif sd >= abs(v):
            why = f"sigma {sd:.3g} >= |value| {abs(v):.3g} {r['unit']}: not distinguishable from zero"
        if why is None:
            if is_compliance:
                identified_compliances.append(name)
            continue
        not_identified.append({"name": name, "value": v, "std": float(sd), "unit": r["unit"], "why": why})
    n_comp = sum(r["name"].startswith(("compliance.", "lateral.")) for r in rows)
    n_held = sum(r["name"].startswith(("compliance.", "lateral.")) and not r.get("identifiable", True) for r in rows)
    checks["elastic_compliances_identified"] = {"value": len(identified_compliances), "limit": 1,
                                                "passed": bool(identified_compliances), "unit": "count"}
    checks["elastic_negative_compliances"] = {"value": len(negative), "limit": 0, "passed": not negative,
                                              "unit": "count"}
    if negative:
        reasons.append("elastic: negative compliance beyond its uncertainty (" + "; ".join(negative) + "): the "
                       "deflection model does not describe these data (a rigid robot, a missing payload or another "
                       "error absorbed by the compliances); calibrate without --elastic or check the payload")
    if n_comp and not identified_compliances:
        reasons.append(f"elastic: none of the {n_comp} compliances is identified ({n_held} not identifiable, the "
                       "others negative or within their standard deviation of zero): the data show no elastic "
                       "deflection; calibrate without --elastic")
    return reasons, not_identified
