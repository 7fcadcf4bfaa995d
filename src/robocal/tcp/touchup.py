"""Touch-up tool calibration: the 4-point TCP and the 7-point tool frame (thesis 4.1.1).

Flange poses are ``T_base_flange`` (pose of the flange in the robot base frame, mm); the TCP
``t`` is in the flange frame (mm). See ``docs/tcp.md``.

4-point (any N >= 4 poses touching one fixed reference point ``P_ref``):

- sphere (4-1, 4-2): the flange origins ``p_i`` lie on a sphere around ``P_ref``; subtracting the
  mean of ``|p_i - c|^2 = R^2`` over all poses gives the linear system
  ``2 (p_i - mean p) . c = |p_i|^2 - mean |p|^2``, solved by least squares (the thesis subtracts
  pose 1 instead of the mean; same solution for exact data). Reported for reference only;
  undefined when the flange origins are coplanar.
- TCP (4-4): ``R_i t + p_i = P_ref`` for all poses, solved jointly for ``t`` and ``P_ref`` by
  least squares on the calibration core (:mod:`robocal.tcp.touchup_fit`: a tool-point block, a
  fixed-point block and a fixed-point residual block), which also gives their covariance and an
  identifiability report. Eliminating ``P_ref = mean(R) t + mean(p)`` leaves
  ``(R_i - mean R) t = mean p - p_i``; the smallest singular value ``s_min`` of the stacked
  ``R_i - mean R`` (3N x 3) is the conditioning: the TCP's standard deviation is at most
  ``sigma_pose / s_min``. ``orientation_spread_deg = 2 asin(s_min / sqrt(N))`` (for 2 poses it is
  their rotation angle; it is 0 when all orientations differ only by rotations about one axis,
  which leaves the TCP component along that axis undetermined). Below ``min_spread_deg`` (20 deg
  by default) :class:`DegenerateToolPosesError` is raised.
"""

from __future__ import annotations
from ..errors import NotIdentifiableError

import math
from dataclasses import dataclass, field

import numpy as np

from ..transforms import check_transforms, transform_from_pose

__all__ = [
    "DegenerateToolPosesError",
    "TouchUpResult",
    "SevenPointResult",
    "sphere_center",
    "four_point_tcp",
    "four_point_tcp_from_poses",
    "seven_point_tool_frame",
]

DEFAULT_MIN_SPREAD_DEG = 20.0


class DegenerateToolPosesError(NotIdentifiableError):
    """The flange orientations are too similar to determine the TCP (or the tool frame)."""


def _f3(v) -> str:
    return "(" + ", ".join(f"{float(x):.4g}" for x in np.ravel(v)) + ")"


def _as_poses(T, name: str, min_n: int) -> np.ndarray:
    T = check_transforms(T, name)
    if T.ndim != 3:
        raise ValueError(f"{name}: expected shape (N, 4, 4), got {T.shape}")
    if T.shape[0] < min_n:
        raise ValueError(f"{name}: need at least {min_n} poses, got {T.shape[0]}")
    R = T[:, :3, :3]
    err = np.abs(np.einsum("nji,njk->nik", R, R) - np.eye(3)).max(axis=(1, 2))
    bad = np.flatnonzero((err > 1e-6) | (np.linalg.det(R) < 0))
    if bad.size:
        raise ValueError(f"{name}[{int(bad[0])}]: rotation part is not a rotation matrix "
                         f"(|R^T R - I| = {err[bad[0]]:.2g})")
    return T


# ---------------------------------------------------------------------------------------------
# 4-point
# ---------------------------------------------------------------------------------------------


def sphere_center(points) -> tuple:
    """Least-squares sphere through ``points`` (N, 3) by the linear system (4-1, 4-2).

    Returns ``(center (3,), radius)`` or ``(None, None)`` when the points are (nearly) coplanar
    and the system has rank < 3.
    """
    p = np.asarray(points, dtype=float)
    if p.ndim != 2 or p.shape[1] != 3 or p.shape[0] < 4:
        raise ValueError(f"points: expected shape (N >= 4, 3), got {p.shape}")
    sq = np.einsum("ni,ni->n", p, p)
    A = 2.0 * (p - p.mean(axis=0))
    b = sq - sq.mean()
    s = np.linalg.svd(A, compute_uv=False)
    scale = max(float(np.ptp(p, axis=0).max()), 1e-12)
    if s[-1] <= 1e-9 * scale * math.sqrt(len(p)) or s[-1] <= 1e-6 * s[0]:
        return None, None
    c = np.linalg.lstsq(A, b, rcond=None)[0]
    return c, float(np.linalg.norm(p - c, axis=1).mean())


@dataclass(frozen=True, eq=False)
class TouchUpResult:
    """Result of :func:`four_point_tcp` (mm; TCP in the flange frame, the rest in the base frame)."""

    tcp_mm: np.ndarray                 # (3,) TCP in the flange frame
    reference_point_mm: np.ndarray     # (3,) P_ref in the base frame (joint least squares, 4-4)
    residual_vectors_mm: np.ndarray    # (N, 3) R_i t + p_i - P_ref, base frame
    residuals_mm: np.ndarray           # (N,) norms of the residual vectors
    rms_mm: float                      # sqrt(mean |r_i|^2)
    orientation_spread_deg: float      # 2 asin(s_min / sqrt(N)), see the module docstring
    singular_values: np.ndarray        # (3,) of the stacked R_i - mean R, descending
    weakest_direction_flange: np.ndarray  # (3,) TCP direction (flange frame) determined worst
    noise_gain: float                  # 1 / s_min: TCP std per unit of pose position noise (worst direction)
    tcp_std_mm: np.ndarray | None      # (3,) 1-sigma of the TCP from the residuals (None if N = ... no redundancy)
    sphere_center_mm: np.ndarray | None  # (3,) sphere fit (4-2), None if the flange origins are coplanar
    sphere_radius_mm: float | None
    labels: tuple = field(default=())
    covariance_mm2: np.ndarray | None = None  # (6, 6) of (tcp x, y, z, P_ref x, y, z), from the core's fit
    identifiability: object = None     # the core's IdentifiabilityReport of the fit
    fit: object = field(default=None, repr=False)  # the core's CalibrationResult

    @property
    def n_poses(self) -> int:
        return int(self.residuals_mm.shape[0])

    @property
    def T_flange_tool(self) -> np.ndarray:
        """The TCP as a transform with the flange's orientation (a 4-point calibration has none)."""
        T = np.eye(4)
        T[:3, 3] = self.tcp_mm
        return T

    def to_dict(self) -> dict:
        def lst(a):
            return None if a is None else [float(x) for x in np.ravel(a)]

        labels = self.labels or tuple(str(i + 1) for i in range(self.n_poses))
        return {
            "tcp_mm": lst(self.tcp_mm),
            "reference_point_mm": lst(self.reference_point_mm),
            "residuals_mm": {lab: float(r) for lab, r in zip(labels, self.residuals_mm)},
            "residual_vectors_mm": {lab: lst(r) for lab, r in zip(labels, self.residual_vectors_mm)},
            "rms_mm": float(self.rms_mm),
            "orientation_spread_deg": float(self.orientation_spread_deg),
            "singular_values": lst(self.singular_values),
            "weakest_direction_flange": lst(self.weakest_direction_flange),
            "noise_gain": float(self.noise_gain),
            "tcp_std_mm": lst(self.tcp_std_mm),
            "sphere_center_mm": lst(self.sphere_center_mm),
            "sphere_radius_mm": None if self.sphere_radius_mm is None else float(self.sphere_radius_mm),
            "n_poses": self.n_poses,
            "reference_point_std_mm": None if self.covariance_mm2 is None else
            [None if not np.isfinite(v) else float(math.sqrt(v)) for v in np.diag(self.covariance_mm2)[3:]],
            "not_identifiable": [] if self.identifiability is None else
            [{"name": d["name"], "why": d["why"]} for d in self.identifiability.dropped],
        }


def four_point_tcp(T_base_flange, min_spread_deg: float = DEFAULT_MIN_SPREAD_DEG, labels=None) -> TouchUpResult:
    """TCP (flange frame) from N >= 4 flange poses touching one reference point (4-1 ... 4-4).

    ``T_base_flange``: (N, 4, 4) flange poses [mm]. Solves ``R_i t + p_i = P_ref`` for ``t`` and
    ``P_ref`` jointly by least squares over all poses and reports the residual of every pose.
    Raises :class:`DegenerateToolPosesError` when the orientation spread (module docstring) is
    below ``min_spread_deg``: the TCP would be undetermined along ``weakest_direction_flange``.
    """
    T = _as_poses(T_base_flange, "T_base_flange", 4)
    n = T.shape[0]
    if labels is not None:
        labels = tuple(str(x) for x in labels)
        if len(labels) != n:
            raise ValueError(f"labels: expected {n}, got {len(labels)}")
    R, p = T[:, :3, :3], T[:, :3, 3]
    D = (R - R.mean(axis=0)).reshape(-1, 3)  # conditioning of (4-4) with P_ref eliminated (closed form)
    _, s, Vt = np.linalg.svd(D, full_matrices=False)
    s_min = float(s[-1])
    spread = math.degrees(2.0 * math.asin(min(1.0, s_min / math.sqrt(n))))
    weakest = Vt[-1] * (1.0 if Vt[-1][np.argmax(np.abs(Vt[-1]))] > 0 else -1.0)
    if not spread >= min_spread_deg:
        raise DegenerateToolPosesError(
            f"flange orientations too similar to determine the TCP: orientation spread "
            f"{spread:.3g} deg over {n} poses (2 asin(s_min/sqrt(N)), s_min = {s_min:.3g} of the stacked "
            f"R_i - mean R), TCP undetermined along {_f3(weakest)} in the flange frame; need "
            f">= {min_spread_deg:g} deg: touch the point from orientations tilted by >= {min_spread_deg:g} deg "
            f"about at least two different axes")
    from .touchup_fit import fit_touchup

    fit = fit_touchup(T)  # (4-4) on the calibration core: 3N residuals, 6 unknowns, 3N - 6 dof
    t, P = fit.value("tcp").copy(), fit.value("P_ref").copy()
    r = np.einsum("nij,j->ni", R, t) + p - P
    res = np.linalg.norm(r, axis=1)
    rms = float(math.sqrt(np.mean(res**2)))
    c, rad = sphere_center(p)
    return TouchUpResult(tcp_mm=t, reference_point_mm=P, residual_vectors_mm=r, residuals_mm=res, rms_mm=rms,
                         orientation_spread_deg=spread, singular_values=s, weakest_direction_flange=weakest,
                         noise_gain=1.0 / s_min, tcp_std_mm=fit.std[:3].copy(), sphere_center_mm=c,
                         sphere_radius_mm=rad, labels=labels or (), covariance_mm2=fit.covariance,
                         identifiability=fit.identifiability, fit=fit)


def leave_one_out_residuals(T_base_flange) -> tuple:
    """``(miss (N,), rms_others (N,))`` [mm]: each touch-up pose's miss of the reference point
    predicted by the other N - 1, ``|R_i t_(-i) + p_i - P_(-i)|`` with ``(t, P)`` the linear
    least-squares solution of (4-4) without pose i, and the RMS of that fit over the others (NaN
    for fewer than 5 poses). A pose touching another point stands out here while the joint fit
    spreads its error over every pose."""
    T = np.asarray(T_base_flange, dtype=float)
    n = len(T)
    miss, rms = np.full(n, np.nan), np.full(n, np.nan)
    if n < 5:
        return miss, rms
    R, p = T[:, :3, :3], T[:, :3, 3]
    A = np.concatenate([R, np.broadcast_to(-np.eye(3), (n, 3, 3))], axis=2)  # [R_i, -I] [t; P] = -p_i
    for i in range(n):
        keep = np.arange(n) != i
        x = np.linalg.lstsq(A[keep].reshape(-1, 6), -p[keep].reshape(-1), rcond=None)[0]
        r = np.einsum("nij,j->ni", R, x[:3]) + p - x[3:]
        miss[i] = float(np.linalg.norm(r[i]))
        rms[i] = float(np.sqrt(np.mean(np.sum(r[keep] ** 2, axis=1))))
    return miss, rms


def four_point_tcp_from_poses(values, convention: str, length_unit: str = "mm", angle_unit: str = "deg",
                              min_spread_deg: float = DEFAULT_MIN_SPREAD_DEG, labels=None) -> TouchUpResult:
    """:func:`four_point_tcp` from controller pose values (N, 6) or (N, 7) in a named convention.

    ``convention``: a name of ``robocal.transforms.POSE_CONVENTIONS`` (``kuka_abc``, ``fanuc_wpr``,
    ``zxz`` (the thesis's 4-3), ``quaternion``, ``rotvec``, ...); units as in
    ``robocal.transforms.transform_from_pose``. The TCP comes back in mm.
    """
    T = transform_from_pose(values, convention, length_unit, angle_unit)
    return four_point_tcp(T, min_spread_deg=min_spread_deg, labels=labels)


# ---------------------------------------------------------------------------------------------
# 7-point (4-5)
# ---------------------------------------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class SevenPointResult:
    """Result of :func:`seven_point_tool_frame` (mm, deg)."""

    T_flange_tool: np.ndarray          # (4, 4) tool frame in the flange frame, orthonormalized
    R_base_tool: np.ndarray            # (3, 3) tool axes in the base frame at the P5..P7 orientation
    tcp_points_mm: np.ndarray          # (3, 3) P8, P9, P10: TCP in the base frame at P5, P6, P7 (4-5)
    x_measured: np.ndarray             # (3,) unit P8 -> P9, base frame
    z_measured: np.ndarray             # (3,) unit P9 -> P10, base frame
    orthogonality_error_deg: float     # angle(x_measured, z_measured) - 90, before orthonormalization
    x_correction_deg: float            # angle between x_measured and the final X axis
    flange_orientation_change_deg: float  # largest rotation between the P5, P6, P7 flange orientations

    def to_dict(self) -> dict:
        return {
            "T_flange_tool": [[float(x) for x in row] for row in self.T_flange_tool],
            "tcp_mm": [float(x) for x in self.T_flange_tool[:3, 3]],
            "R_base_tool": [[float(x) for x in row] for row in self.R_base_tool],
            "tcp_points_mm": {k: [float(x) for x in v] for k, v in zip(("P8", "P9", "P10"), self.tcp_points_mm)},
            "orthogonality_error_deg": float(self.orthogonality_error_deg),
            "x_correction_deg": float(self.x_correction_deg),
            "flange_orientation_change_deg": float(self.flange_orientation_change_deg),
        }


def _rot_angle_deg(Ra, Rb) -> float:
    c = (np.trace(Ra.T @ Rb) - 1.0) / 2.0
    return math.degrees(math.acos(max(-1.0, min(1.0, c))))


def seven_point_tool_frame(T_flange_5_6_7, tcp, max_orientation_change_deg: float = 1.0,
                           min_move_mm: float = 1.0) -> SevenPointResult:
    """Tool orientation from the 7-point method's points 5, 6, 7 (thesis 4-5).

    ``T_flange_5_6_7``: (3, 4, 4) flange poses ``T_base_flange`` at P5 (start), P6 (after a move
    along the wanted tool X axis) and P7 (after a move along the wanted tool Z axis), all with
    the same flange orientation; ``tcp``: (3,) TCP in the flange frame (from :func:`four_point_tcp`).

    P8, P9, P10 = ``T_i @ [tcp, 1]`` (4-5); ``x = P8 -> P9``, ``z = P9 -> P10``; ``Y = Z x X``
    (right-handed: e_z x e_x = e_y; the thesis only says "cross product"); orthonormalized
    keeping Z (the tool axis): ``Z = z/|z|``, ``Y = Z x x / |.|``, ``X = Y x Z``. The tool
    orientation in the flange frame is ``R_flange_tool = R_base_flange^T [X Y Z]`` with the
    flange orientation averaged over the three poses (projected to SO(3)).
    Raises ``ValueError`` if the flange orientations differ by more than
    ``max_orientation_change_deg`` or a move is shorter than ``min_move_mm``, and
    :class:`DegenerateToolPosesError` if the two moves are (nearly) parallel.
    """
    T = _as_poses(T_flange_5_6_7, "T_flange_5_6_7", 3)
    if T.shape[0] != 3:
        raise ValueError(f"T_flange_5_6_7: expected 3 poses (P5, P6, P7), got {T.shape[0]}")
    t = np.asarray(tcp, dtype=float)
    if t.shape != (3,) or not np.all(np.isfinite(t)):
        raise ValueError(f"tcp: expected 3 finite coordinates, got {t!r}")
    R = T[:, :3, :3]
    change = max(_rot_angle_deg(R[i], R[j]) for i in range(3) for j in range(i + 1, 3))
    if change > max_orientation_change_deg:
        raise ValueError(f"P5, P6, P7 must keep the flange orientation: it changes by {change:.3g} deg "
                         f"(> {max_orientation_change_deg:g} deg)")
    P = np.einsum("nij,j->ni", R, t) + T[:, :3, 3]          # P8, P9, P10 (4-5)
    x = P[1] - P[0]
    z = P[2] - P[1]
    for name, v in (("P5 -> P6 (X)", x), ("P6 -> P7 (Z)", z)):
        if np.linalg.norm(v) < min_move_mm:
            raise ValueError(f"move {name} is {np.linalg.norm(v):.3g} mm; need >= {min_move_mm:g} mm")
    x = x / np.linalg.norm(x)
    z = z / np.linalg.norm(z)
    cosang = float(np.clip(x @ z, -1.0, 1.0))
    ortho = math.degrees(math.acos(cosang)) - 90.0
    if abs(cosang) > math.cos(math.radians(30.0)):
        raise DegenerateToolPosesError(
            f"the X move and the Z move are nearly parallel ({math.degrees(math.acos(abs(cosang))):.3g} deg "
            "apart); they should be about 90 deg apart")
    Z = z
    Y = np.cross(Z, x)
    Y /= np.linalg.norm(Y)
    X = np.cross(Y, Z)
    R_base_tool = np.column_stack([X, Y, Z])
    U, _, Vt = np.linalg.svd(R.sum(axis=0))
    R_mean = U @ np.diag([1.0, 1.0, np.linalg.det(U @ Vt)]) @ Vt
    T_ft = np.eye(4)
    T_ft[:3, :3] = R_mean.T @ R_base_tool
    T_ft[:3, 3] = t
    return SevenPointResult(T_flange_tool=T_ft, R_base_tool=R_base_tool, tcp_points_mm=P, x_measured=x,
                            z_measured=z, orthogonality_error_deg=ortho,
                            x_correction_deg=math.degrees(math.acos(float(np.clip(x @ X, -1.0, 1.0)))),
                            flange_orientation_change_deg=change)
