"""System calibration of the thermal cell: the sensor frame and the sphere on the flange (thesis 3.3).

A fixed sensor measures the centre of a sphere carried on the flange. With our naming
(``T_a_b`` = pose of frame b in frame a, docs/conventions.md) the measurement model is (3-1)::

    P_s = T_sensor_base . T_base_flange(q) . P_e              (homogeneous points)
        = R_s (R P_e + t) + t_s                                 (3-12)

where ``R_s, t_s`` are the rotation and translation of ``T_sensor_base`` (the thesis's ``T_b^s``,
the robot base seen from the sensor) and ``R, t`` those of ``T_base_flange(q)`` (``T_e^b``, from
the robot model). Unknowns: ``T_sensor_base`` (6) and ``P_e`` (3, mm, flange frame).

Two solutions over the same data:

* :func:`calibrate_system_thesis` -- the thesis's method. Subtracting pose i from pose 1::

      P_s1 - P_si = R_s (R_1 - R_i) P_e + R_s (t_1 - t_i)
      R_s^T (P_s1 - P_si) - (R_1 - R_i) P_e = t_1 - t_i                      (3-14)

  (multiply by ``R_s^T = R_s^-1`` on the left). So the matrix the thesis solves for is
  ``R_s^T``, the rotation of ``T_base_sensor`` (not of ``T_sensor_base``). Eq. (3-14) is linear in
  the 12 unknowns ``k = [row-major entries of R_s^T, P_e]``; per pose pair
  ``B_i = [I_3 (x) dP_i^T, -(R_1 - R_i)]`` (3 x 12) and ``b_i = t_1 - t_i`` (3-15; the printed B
  in the thesis shifts the dP entries like a Toeplitz matrix and drops the minus sign of the P_e
  block -- both are extraction slips, this is what (3-14) says). Stacking n = N - 1 pairs gives
  (3-16); the 6 orthonormality conditions of ``R_s^T`` (3-17) enter as a penalty ``M sum f_j^2``
  (3-18), minimised by Levenberg-Marquardt (``scipy.optimize.least_squares(method="lm")``) from
  the unconstrained linear least-squares solution; then ``t_si = P_si - R_s (R_i P_e + t_i)`` and
  ``t_s`` is their mean (3-19). The penalty leaves ``R_s^T`` only approximately orthonormal; the
  returned frame uses its nearest rotation (SVD projection) and the raw matrix and its
  orthonormality error are reported. Weaknesses, visible in the comparison: every equation
  contains pose 1's measurement noise (correlated, weighted as if independent), the noise sits in
  ``B`` rather than ``b`` (errors in variables), and the algebraic residual is not the
  measurement error.
* :func:`calibrate_system` -- the proper solution on the calibration core: a
  :class:`~robocal.calib.CalibrationProblem` with the robot geometry held fixed (``free=[]``), the
  base frame (= ``T_sensor_base``, a minimal always-valid parametrisation) and one free target
  (the sphere centre) estimated by Levenberg-Marquardt on the measurement residuals themselves,
  with standard deviations.

:func:`compare_system_calibrations` runs both on the same data. :func:`check_system_poses` raises
:class:`SystemCalibrationError` for fewer than 5 poses or pose sets that cannot determine the
unknowns (e.g. all flange orientations equal: ``P_e`` is then inseparable from ``t_s``).
"""

from __future__ import annotations
from ..errors import InputError

import math
from dataclasses import dataclass, field

import numpy as np

from ..calib import CalibrationProblem, Target, solve
from ..kinematics.model import RobotModel
from ..transforms import invert_transforms, so3_exp, so3_log
from .drift import predict_sphere

__all__ = ["SystemCalibration", "SystemCalibrationComparison", "SystemCalibrationError", "calibrate_system",
           "calibrate_system_thesis", "check_system_poses", "compare_system_calibrations", "design_sphere_poses",
           "frame_errors", "thesis_linear_system", "MIN_SYSTEM_POSES"]

#: (3-16) has 12 unknowns and 3 equations per pose pair: 3 (N - 1) >= 12, so N >= 5.
MIN_SYSTEM_POSES = 5


class SystemCalibrationError(InputError):
    """The poses or measurements cannot determine the sensor frame and the sphere centre."""


@dataclass
class SystemCalibration:
    """Result of a system calibration.

    method: ``"thesis-penalty"`` or ``"least-squares"``.
    T_sensor_base (4, 4): the robot base in the sensor frame [mm] (thesis ``T_b^s``).
    P_e (3,): the sphere centre in the flange frame [mm].
    residuals_mm (N, 3): measured minus predicted sphere centres, sensor frame [mm].
    std_rotation_rad (3,), std_translation_mm (3,), std_P_e_mm (3,): one-sigma uncertainties
        (rotation as a small rotation vector of ``T_sensor_base`` in the sensor frame); NaN for
        the thesis method, which has no statistical model.
    covariance (9, 9): over ``names`` (NaN for the thesis method).
    orthonormality_error: ``|R R^T - I|_F`` of the raw rotation matrix the method produced (0
        for the least-squares method, whose rotation is valid by construction).
    R_raw (3, 3): the thesis method's raw ``R_s^T`` (rotation of ``T_base_sensor``) before projection.
    converged, message, iterations: solver outcome. details: the solver's own result object.
    """

    method: str
    T_sensor_base: np.ndarray
    P_e: np.ndarray
    residuals_mm: np.ndarray
    converged: bool
    message: str
    iterations: int
    std_rotation_rad: np.ndarray
    std_translation_mm: np.ndarray
    std_P_e_mm: np.ndarray
    covariance: np.ndarray
    names: tuple = ("base.rx", "base.ry", "base.rz", "base.x", "base.y", "base.z", "sphere.x", "sphere.y", "sphere.z")
    orthonormality_error: float = 0.0
    R_raw: np.ndarray | None = None
    details: object = field(default=None, repr=False)

    @property
    def n_poses(self) -> int:
        return len(self.residuals_mm)

    @property
    def T_base_sensor(self) -> np.ndarray:
        """The sensor frame in the robot base frame (thesis ``T_s^b``)."""
        return invert_transforms(self.T_sensor_base)

    @property
    def rms_mm(self) -> float:
        """RMS of the 3-D residual distances [mm]."""
        return float(np.sqrt(np.mean(np.sum(self.residuals_mm**2, axis=1))))

    def predict(self, model: RobotModel, q) -> np.ndarray:
        """Sphere centres (N, 3) in the sensor frame predicted for joints ``q`` (N, n) [mm]."""
        return predict_sphere(model, self.T_sensor_base, self.P_e, q)

    def summary(self) -> str:
        t = self.T_sensor_base[:3, 3]
        lines = [f"system calibration ({self.method}): {self.n_poses} poses, residual RMS {self.rms_mm:.4f} mm, "
                 f"{'converged' if self.converged else 'NOT converged'} ({self.message})",
                 f"  T_sensor_base translation [mm]: {t[0]:.4f} {t[1]:.4f} {t[2]:.4f}",
                 f"  P_e (sphere in flange) [mm]:    {self.P_e[0]:.4f} {self.P_e[1]:.4f} {self.P_e[2]:.4f}"]
        if np.all(np.isfinite(self.std_P_e_mm)):
            lines.append(f"  std: rotation {np.degrees(self.std_rotation_rad).round(5).tolist()} deg, translation "
                         f"{self.std_translation_mm.round(4).tolist()} mm, P_e {self.std_P_e_mm.round(4).tolist()} mm")
        if self.R_raw is not None:
            lines.append(f"  raw rotation orthonormality error |R R^T - I|_F = {self.orthonormality_error:.3g}")
        return "\n".join(lines)


# ---------------------------------------------------------------------------------------------- helpers
def _base_flange(model: RobotModel, q) -> np.ndarray:
    q = np.atleast_2d(np.asarray(q, dtype=float))
    T = model.fk(q)
    if not np.allclose(model.T_world_base, np.eye(4)):
        T = invert_transforms(model.T_world_base) @ T
    return T


def _check_inputs(model: RobotModel, q, P_s):
    q = np.asarray(q, dtype=float)
    P_s = np.asarray(P_s, dtype=float)
    if q.ndim != 2 or q.shape[1] != model.n_joints:
        raise SystemCalibrationError(f"joints: expected shape (N, {model.n_joints}), got {q.shape}")
    if P_s.shape != (len(q), 3):
        raise SystemCalibrationError(f"sphere centres: expected shape ({len(q)}, 3) (one per pose), got {P_s.shape}")
    bad = ~(np.all(np.isfinite(q), axis=1) & np.all(np.isfinite(P_s), axis=1))
    if bad.any():
        raise SystemCalibrationError(f"pose(s) {np.flatnonzero(bad).tolist()}: joints or sphere centre not finite")
    if len(q) < MIN_SYSTEM_POSES:
        raise SystemCalibrationError(
            f"system calibration needs at least {MIN_SYSTEM_POSES} poses (12 unknowns in (3-16), 3 equations per "
            f"pose pair), got {len(q)}")
    return q, P_s


def check_system_poses(model: RobotModel, q, P_s, *, tol: float = 1e-6) -> None:
    """Raise :class:`SystemCalibrationError` unless the poses can determine ``T_sensor_base`` and ``P_e``.

    Checks: at least 5 poses, finite values, and two observability conditions that do not depend
    on the unknowns:

    * ``P_e``: the stacked differences of flange rotations ``[R_1 - R_i]`` (3(N-1) x 3) must have
      rank 3. A direction ``u`` (flange frame) in their null space is a component of ``P_e`` that
      moves every sphere centre by the same vector, indistinguishable from a shift of ``t_s``:
      all orientations equal (nothing about ``P_e`` observable) or all rotations about one common
      axis ``u`` (its component along ``u`` unobservable).
    * rotation: the measured sphere centres must not be collinear (a rotation of the sensor frame
      about their line would be undetermined).

    ``tol`` is relative to the largest singular value.
    """
    q, P_s = _check_inputs(model, q, P_s)
    T = _base_flange(model, q)
    R = T[:, :3, :3]
    D = (R[0] - R[1:]).reshape(-1, 3)
    _, s, Vt = np.linalg.svd(D)
    if s[0] <= 1e-9:
        raise SystemCalibrationError(
            f"all {len(q)} flange orientations are equal: the sphere centre P_e cannot be separated from the sensor "
            f"translation (every pose shifts it the same way); vary the flange orientation about at least two axes")
    if s[-1] <= tol * s[0] or s[-1] < 1e-4:
        u = Vt[-1] * np.sign(Vt[-1][np.argmax(np.abs(Vt[-1]))])
        raise SystemCalibrationError(
            f"the flange orientations differ only by rotations about one axis (flange frame direction "
            f"{np.round(u, 4).tolist()}): the component of P_e along it cannot be separated from the sensor "
            f"translation; tilt the flange about a second axis (singular values of [R_1 - R_i]: {np.round(s, 6).tolist()})")
    c = P_s - P_s.mean(axis=0)
    sp = np.linalg.svd(c, compute_uv=False)
    if sp[1] <= max(tol * sp[0], 1e-9):
        raise SystemCalibrationError(
            "the measured sphere centres are collinear: the sensor frame's rotation about their line is undetermined; "
            "spread the sphere positions in at least two directions")


def frame_errors(T_est, T_true, P_e_est=None, P_e_true=None, at_base=None) -> dict:
    """Errors of an estimated ``T_sensor_base`` (and ``P_e``) against the truth.

    Returns ``rotation_deg`` (angle of ``R_est R_true^T``), ``translation_mm`` (of ``T_sensor_base``:
    the base origin in the sensor frame, typically 1-3 m from where the data are, so it carries
    the rotation error times that lever arm), ``sensor_origin_mm`` (of ``T_base_sensor``: the sensor
    origin in the base frame), ``P_e_mm`` when given, and with ``at_base`` (3,) [mm, base frame]
    ``at_point_mm``: ``|T_est p - T_true p|``, the frame's position error where it is used (e.g. the
    centre of the measurement volume).
    """
    T_est, T_true = np.asarray(T_est, float), np.asarray(T_true, float)
    out = {"rotation_deg": float(np.degrees(np.linalg.norm(so3_log(T_est[:3, :3] @ T_true[:3, :3].T)))),
           "translation_mm": float(np.linalg.norm(T_est[:3, 3] - T_true[:3, 3])),
           "sensor_origin_mm": float(np.linalg.norm(invert_transforms(T_est)[:3, 3] - invert_transforms(T_true)[:3, 3]))}
    if P_e_est is not None and P_e_true is not None:
        out["P_e_mm"] = float(np.linalg.norm(np.asarray(P_e_est, float) - np.asarray(P_e_true, float)))
    if at_base is not None:
        p = np.asarray(at_base, float).reshape(3)
        out["at_point_mm"] = float(np.linalg.norm((T_est[:3, :3] - T_true[:3, :3]) @ p + T_est[:3, 3] - T_true[:3, 3]))
    return out


def _nearest_rotation(A) -> np.ndarray:
    U, _, Vt = np.linalg.svd(A)
    D = np.diag([1.0, 1.0, np.sign(np.linalg.det(U @ Vt)) or 1.0])
    return U @ D @ Vt


# ---------------------------------------------------------------------------------------------- the thesis
def thesis_linear_system(model: RobotModel, q, P_s):
    """(3-15), (3-16): ``B'`` (3(N-1), 12) and ``b'`` (3(N-1),) for ``k = [vec_row(R_s^T), P_e]``.

    Row block i (pose pair 1, i+1): ``[I_3 (x) (P_s1 - P_s,i+1)^T, -(R_1 - R_{i+1})]``, right side
    ``t_1 - t_{i+1}``.
    """
    q = np.asarray(q, float)
    P_s = np.asarray(P_s, float)
    T = _base_flange(model, q)
    R, t = T[:, :3, :3], T[:, :3, 3]
    dP = P_s[0] - P_s[1:]                                    # (n, 3)
    n = len(dP)
    B = np.zeros((n, 3, 12))
    for j in range(3):
        B[:, j, 3 * j:3 * j + 3] = dP
    B[:, :, 9:] = -(R[0] - R[1:])
    b = t[0] - t[1:]
    return B.reshape(3 * n, 12), b.reshape(3 * n)


def _orthonormality(k):
    Rt = k[:9].reshape(3, 3)
    G = Rt @ Rt.T
    return np.array([G[0, 0] - 1.0, G[1, 1] - 1.0, G[2, 2] - 1.0, G[0, 1], G[0, 2], G[1, 2]])  # f1..f6 (3-17)


def _orthonormality_jac(k):
    Rt = k[:9].reshape(3, 3)
    J = np.zeros((6, 12))
    pairs = [(0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2)]
    for m, (a, c) in enumerate(pairs):
        # d(row_a . row_c)/d row_a = row_c, d/d row_c = row_a
        J[m, 3 * a:3 * a + 3] += Rt[c]
        J[m, 3 * c:3 * c + 3] += Rt[a]
    return J


def calibrate_system_thesis(model: RobotModel, q, P_s, *, penalty: float = 1e8, check: bool = True) -> SystemCalibration:
    """The thesis's system calibration (3-14 ... 3-19); see the module docstring.

    model: the robot (its geometry is taken as exact). q (N, n) joints [rad]; P_s (N, 3) measured
    sphere centres in the sensor frame [mm]; N >= 5.
    penalty: the penalty factor ``M`` of (3-18) [mm^2 per unit of f_j^2]; the thesis gives no value.
        It must dominate the linear rows (whose rotation columns scale with the pose spread, ~100-1000
        mm): 1e8 (i.e. 1e4 mm per unit orthonormality error) keeps ``|R R^T - I|`` ~ 1e-8.
    """
    from scipy.optimize import least_squares

    q, P_s = _check_inputs(model, q, P_s)
    if check:
        check_system_poses(model, q, P_s)
    B, b = thesis_linear_system(model, q, P_s)
    k0, *_ = np.linalg.lstsq(B, b, rcond=None)              # unconstrained (3-16)
    sq = math.sqrt(penalty)

    def fun(k):
        return np.concatenate([B @ k - b, sq * _orthonormality(k)])

    def jac(k):
        return np.vstack([B, sq * _orthonormality_jac(k)])

    sol = least_squares(fun, k0, jac=jac, method="lm", xtol=1e-15, ftol=1e-15, gtol=1e-15, max_nfev=2000)
    k = sol.x
    Rt_raw = k[:9].reshape(3, 3)                            # R_s^T = rotation of T_base_sensor
    P_e = k[9:].copy()
    ortho = float(np.linalg.norm(Rt_raw @ Rt_raw.T - np.eye(3)))
    R_s = _nearest_rotation(Rt_raw).T                       # rotation of T_sensor_base
    T = _base_flange(model, q)
    p_base = T[:, :3, :3] @ P_e + T[:, :3, 3]
    t_si = P_s - p_base @ R_s.T                             # (3-12) solved for t_s at every pose
    t_s = t_si.mean(axis=0)                                 # (3-19)
    T_sb = np.eye(4)
    T_sb[:3, :3] = R_s
    T_sb[:3, 3] = t_s
    res = P_s - predict_sphere(model, T_sb, P_e, q)
    nan3 = np.full(3, np.nan)
    return SystemCalibration("thesis-penalty", T_sb, P_e, res, bool(sol.success), str(sol.message), int(sol.nfev),
                             nan3, nan3.copy(), nan3.copy(), np.full((9, 9), np.nan), orthonormality_error=ortho,
                             R_raw=Rt_raw, details=sol)


# ---------------------------------------------------------------------------------------------- proper
def calibrate_system(model: RobotModel, q, P_s, *, point_sigma_mm: float | None = None, initial="linear",
                     P_e_initial=None, max_iterations: int = 50) -> SystemCalibration:
    """``T_sensor_base`` and ``P_e`` by nonlinear least squares on the calibration core.

    A :class:`~robocal.calib.CalibrationProblem` with the robot geometry fixed (``free=[]``), the
    base frame estimated (here the base frame *is* ``T_sensor_base``: the problem's instrument is
    the sensor) and one free target, the sphere centre; solved by LM with the analytic Jacobian.

    q (N, n) joints [rad]; P_s (N, 3) measured centres, sensor frame [mm]; N >= 5.
    point_sigma_mm: measurement noise per coordinate [mm]; if given the standard deviations use it,
        otherwise they are scaled by the fitted residual (a posteriori sigma).
    initial: ``"linear"`` (default: the unconstrained linear solution of (3-16), projected to a
        rotation, with ``t_s`` from (3-19) -- closed form, no guess needed), ``"fit"`` (rigid fit of
        the flange points with ``P_e_initial``), or a (4, 4) ``T_sensor_base`` guess.
    P_e_initial: (3,) starting sphere centre [mm] for ``"fit"`` or a given frame (default zeros,
        or the linear solution's with ``"linear"``).

    Raises :class:`SystemCalibrationError` for too few or degenerate poses, or when the solved
    problem is still rank deficient.
    """
    q, P_s = _check_inputs(model, q, P_s)
    check_system_poses(model, q, P_s)
    geom = model.replace(T_world_base=np.eye(4)) if not np.allclose(model.T_world_base, np.eye(4)) else model
    P0 = np.zeros(3) if P_e_initial is None else np.asarray(P_e_initial, float).reshape(3)
    if isinstance(initial, str) and initial == "linear":
        T0, P0 = _linear_initial(geom, q, P_s)
    elif isinstance(initial, str) and initial == "fit":
        T0 = "fit"
    elif isinstance(initial, str):
        raise ValueError(f"initial must be 'linear', 'fit' or a (4, 4) transform, got {initial!r}")
    else:
        T0 = np.asarray(initial, float).reshape(4, 4)
    prob = CalibrationProblem(geom, q, [Target("sphere", None, tuple(P0), True)], P_s[:, None, :], free=[],
                              estimate_base=True, base_initial=T0, point_sigma_mm=point_sigma_mm)
    res = solve(prob, max_iterations=max_iterations)
    if res.identifiability.dropped:
        raise SystemCalibrationError("the poses cannot determine the sensor frame and sphere centre:\n"
                                     + res.identifiability.explain())
    T_sb = res.state.bases[0].copy()
    P_e = res.state.targets[0].copy()
    resid = P_s - predict_sphere(geom, T_sb, P_e, q)
    std = res.std
    return SystemCalibration("least-squares", T_sb, P_e, resid, bool(res.converged), res.reason, int(res.iterations),
                             std[0:3].copy(), std[3:6].copy(), std[6:9].copy(), res.covariance.copy(),
                             names=tuple(res.names), details=res)


def _linear_initial(model, q, P_s):
    B, b = thesis_linear_system(model, q, P_s)
    k, *_ = np.linalg.lstsq(B, b, rcond=None)
    R_s = _nearest_rotation(k[:9].reshape(3, 3)).T
    P_e = k[9:]
    T = _base_flange(model, q)
    t_s = (P_s - (T[:, :3, :3] @ P_e + T[:, :3, 3]) @ R_s.T).mean(axis=0)
    T0 = np.eye(4)
    T0[:3, :3] = R_s
    T0[:3, 3] = t_s
    return T0, P_e


# ---------------------------------------------------------------------------------------------- comparison
@dataclass
class SystemCalibrationComparison:
    """Both methods on the same data. ``errors``: per method, :func:`frame_errors` against the truth
    (empty without a truth); ``difference``: :func:`frame_errors` of the thesis result against the
    least-squares one."""

    thesis: SystemCalibration
    least_squares: SystemCalibration
    difference: dict
    errors: dict = field(default_factory=dict)

    def table(self) -> list[dict]:
        rows = []
        for key, r in (("thesis-penalty", self.thesis), ("least-squares", self.least_squares)):
            row = {"method": key, "rms_mm": r.rms_mm, "orthonormality_error": r.orthonormality_error}
            row.update(self.errors.get(key, {}))
            rows.append(row)
        return rows

    def summary(self) -> str:
        lines = [f"{'method':16s} {'RMS mm':>9s} {'rot deg':>9s} {'t_sb mm':>9s} {'sensor mm':>9s} {'volume mm':>9s} "
                 f"{'P_e mm':>9s}"]
        for row in self.table():
            f = [row.get(k, float("nan")) for k in ("rms_mm", "rotation_deg", "translation_mm", "sensor_origin_mm",
                                                    "at_point_mm", "P_e_mm")]
            lines.append(f"{row['method']:16s} " + " ".join(f"{v:9.5f}" for v in f))
        d = self.difference
        lines.append(f"thesis vs least squares: rotation {d['rotation_deg']:.5f} deg, translation "
                     f"{d['translation_mm']:.4f} mm, P_e {d['P_e_mm']:.4f} mm")
        return "\n".join(lines)


def compare_system_calibrations(model: RobotModel, q, P_s, *, T_sensor_base_true=None, P_e_true=None,
                                point_sigma_mm: float | None = None, penalty: float = 1e8) -> SystemCalibrationComparison:
    """Run :func:`calibrate_system_thesis` and :func:`calibrate_system` on the same data and compare.

    With the truth (simulation) each method's errors are reported (:func:`frame_errors`, with
    ``at_point_mm`` at the centroid of the measured sphere positions).
    """
    th = calibrate_system_thesis(model, q, P_s, penalty=penalty)
    ls = calibrate_system(model, q, P_s, point_sigma_mm=point_sigma_mm)
    diff = frame_errors(th.T_sensor_base, ls.T_sensor_base, th.P_e, ls.P_e)
    errors = {}
    if T_sensor_base_true is not None:
        T = _base_flange(model, q)
        P_ref = ls.P_e if P_e_true is None else np.asarray(P_e_true, float)
        centre = (T[:, :3, :3] @ P_ref + T[:, :3, 3]).mean(axis=0)   # centre of the measured volume, base frame
        for key, r in (("thesis-penalty", th), ("least-squares", ls)):
            errors[key] = frame_errors(r.T_sensor_base, T_sensor_base_true, r.P_e, P_e_true, at_base=centre)
    return SystemCalibrationComparison(th, ls, diff, errors)


def design_sphere_poses(model: RobotModel, centre_base, P_e, n: int, rng, *, spread_mm=150.0,
                        tilt_deg: float = 30.0, layout: str = "box", R_base_flange_mean=None,
                        max_tries: int = 50) -> np.ndarray:
    """Joint configurations (n, n_joints) that put the sphere near ``centre_base`` (base frame, [mm])
    with varied flange orientations -- a pose set for system calibration or drift measurement.

    spread_mm: half-size of the measurement box around ``centre_base`` [mm], a scalar or (3,) per
        base axis (keep it inside the sensor's field of view).
    layout: ``"box"`` puts the first 8 sphere centres at the box corners, the 9th at the centre and
        the rest uniformly inside (the widest spread, hence the best-determined rotation);
        ``"random"`` draws all uniformly in the box.
    tilt_deg: flange orientations are ``R_base_flange_mean`` (default: flange z axis pointing down)
        tilted by a random rotation of 40-100 % of ``tilt_deg`` about a random axis.
    Joints come from the closed-form IK when the model allows it (the branch closest to the
    previous pose, within the joint limits), else from numerical IK. An unreachable draw is
    redrawn (new orientation, same corner). ``rng``: seed or Generator.
    """
    from ..kinematics import ik_analytic, ik_numeric, is_analytic

    if layout not in ("box", "random"):
        raise ValueError(f"layout must be 'box' or 'random', got {layout!r}")
    if not isinstance(rng, np.random.Generator):
        if rng is None or isinstance(rng, bool) or not isinstance(rng, (int, np.integer)):
            raise TypeError(f"rng: expected a numpy.random.Generator or an integer seed, got {rng!r}")
        rng = np.random.default_rng(int(rng))
    c0 = np.asarray(centre_base, float).reshape(3)
    half = np.broadcast_to(np.asarray(spread_mm, float), (3,))
    P_e = np.asarray(P_e, float).reshape(3)
    Rm = np.diag([1.0, -1.0, -1.0]) if R_base_flange_mean is None else np.asarray(R_base_flange_mean, float)
    corners = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)], float)
    corners = np.vstack([corners, np.zeros((1, 3))])
    analytic = is_analytic(model)
    out, prev = [], None
    for i in range(n):
        for _ in range(max_tries):
            if layout == "box" and i < len(corners):
                c = c0 + corners[i] * half
            else:
                c = c0 + rng.uniform(-1.0, 1.0, 3) * half
            axis = rng.normal(size=3)
            axis /= np.linalg.norm(axis)
            R = so3_exp(axis * math.radians(tilt_deg) * rng.uniform(0.4, 1.0)) @ Rm
            T = np.eye(4)
            T[:3, :3] = R
            T[:3, 3] = c - R @ P_e
            T = model.T_world_base @ T
            if analytic:
                qs, ok = ik_analytic(model, T, within_limits=True)
                if not ok.any():
                    continue
                cand = qs[ok]
                ref = model.limits.mean(axis=1) if prev is None else prev
                qq = cand[np.argmin(np.sum((cand - ref) ** 2, axis=1))]
            else:
                q0 = model.limits.mean(axis=1) if prev is None else prev
                r = ik_numeric(model, T[None], q0[None])
                if not r.converged[0]:
                    continue
                qq = r.q[0]
            out.append(qq)
            prev = qq
            break
        else:
            raise SystemCalibrationError(f"pose {i}: no reachable flange pose found near {c.tolist()} mm "
                                         f"after {max_tries} orientations")
    return np.array(out)
