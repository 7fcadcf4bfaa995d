"""Calibration of the cross-laser sensor and the beta (non-orthogonal beams) correction.

Thesis 4.3.1 (4-15 ... 4-27) and 4.3.2 (4-28 ... 4-30); see ``docs/tcp.md``. All lengths in mm
in the robot base frame, angles in radians unless a name ends in ``_deg``.

Sensor frame (``T_base_sensor``, columns ``[n o p M]``, thesis 4-27):

- origin ``M``: midpoint of the common perpendicular ``PQ`` of the two beam lines (4-19 ... 4-22),
  ``P`` on the X beam (line AB), ``Q`` on the Y beam (line CD);
- ``n`` = X_s: unit vector along A -> B, the X beam (4-23);
- ``m``: unit vector along C -> D, the *measured* Y beam (4-24), generally not orthogonal to ``n``;
- ``p`` = Z_s = n x m / |n x m| (4-25);
- ``o`` = Y_s' = p x n (4-26): in the beam plane, orthogonal to X_s, on the side of the Y beam;
- ``beta``: angle from X_s to the measured Y beam ``m`` about Z_s, in (0, 180) deg; 90 deg for
  orthogonal beams;
- ``gap``: length |PQ| of the common perpendicular (0 when the beams intersect).

Coordinates in the beam plane (section "beta correction" of ``docs/tcp.md``): with the Y beam
along ``(cos beta, sin beta)`` in the orthogonal frame (X_s, Y_s'),

- *oblique* (skew) coordinates ``(u, v)`` of a point are its parallel-projection coordinates along
  the two beams: ``point = u * X_s + v * m`` (the thesis's (x1, y1), 4-28);
- *beam distances* ``(d_x, d_y)`` are signed perpendicular distances of the point to the X beam
  (positive on the +Y_s' side) and to the Y beam (positive on the +X_s side, i.e. the side the
  X beam's positive half lies on); this is what the cross-laser method measures (4-9);
- *orthogonal* coordinates ``(x, y)`` are in (X_s, Y_s') (the thesis's (x2, y2), 4-29).

``d_x = y``, ``d_y = x sin(beta) - y cos(beta)``; hence ``x = d_y / sin(beta) + d_x / tan(beta)``,
``y = d_x`` (4-29) and ``u = d_y / sin(beta)``, ``v = d_x / sin(beta)`` (4-28).
"""

from __future__ import annotations
from ..errors import InputError

import math
from dataclasses import dataclass, field

import numpy as np

__all__ = [
    "SENSOR_POINT_LABELS",
    "SensorCalibrationError",
    "SensorCalibration",
    "beam_point",
    "common_perpendicular",
    "calibrate_sensor",
    "skew_to_orthogonal",
    "orthogonal_to_skew",
    "center_from_beam_distances",
    "beam_distances_from_center",
    "beta_error_mm",
    "beta_error_threshold_deg",
]

BEAM_POINTS = ("A", "B", "C", "D")
SENSOR_POINT_LABELS = tuple(f"{P}{i}" for P in BEAM_POINTS for i in (1, 2, 3, 4))


class SensorCalibrationError(InputError):
    """The recorded points cannot define the sensor frame (coincident points, parallel beams...)."""


def _vec3(x, name: str) -> np.ndarray:
    a = np.asarray(x, dtype=float)
    if a.shape != (3,):
        raise ValueError(f"{name}: expected 3 coordinates (x, y, z), got shape {a.shape}")
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{name}: contains NaN or infinite values")
    return a


def _fmt(v) -> str:
    return "(" + ", ".join(f"{float(x):.4f}" for x in np.ravel(v)) + ")"


# ---------------------------------------------------------------------------------------------
# beam points (4-15, 4-16)
# ---------------------------------------------------------------------------------------------


def beam_point(p1, p2, p3, p4, direction=None, name: str = "beam point") -> np.ndarray:
    """A point on a beam from the four recorded positions (4-15, 4-16).

    ``p1``/``p2``: positions of the pin axis (flange origin, when the pin is coaxial with the
    flange Z axis) where the beam becomes blocked / unblocked while the **vertical** pin moves
    **horizontally** across the beam. The midpoint ``h = (p1 + p2) / 2`` is where the pin axis is
    centred on the beam: block and unblock happen at the same distance (the pin radius) on
    either side, so the radius and the beam width cancel, and ``h``'s x and y lie on the beam's
    vertical projection.

    ``p3``/``p4``: positions where the beam becomes blocked / unblocked while the pin, now
    **horizontal** and pointing along the 1 -> 2 motion (perpendicular to the beam, thesis
    "Z_e along Y_b" for the X beam), moves **down** through the beam. The midpoint
    ``v = (p3 + p4) / 2`` has the pin axis centred on the beam in height, so ``v_z`` is the
    beam's height where the pin crosses it (radius cancels again).

    The thesis takes ``(h_x, h_y, v_z)`` (4-16), exact when 3/4 are recorded straight above
    ``h``. If ``direction`` (the beam direction, from a first estimate) is given, the height is
    moved from where the pin crossed in 3/4 to the beam point above ``h`` (``v_z - t d_z`` with the
    beam offset ``t`` solved in the horizontal plane), which removes the slope error of a beam
    that is not level when 3/4 were recorded away from ``h``.
    """
    p1, p2, p3, p4 = (_vec3(p, f"{name}{i}") for i, p in enumerate((p1, p2, p3, p4), 1))
    h = 0.5 * (p1 + p2)
    v = 0.5 * (p3 + p4)
    z = v[2]
    if direction is not None:
        d = np.asarray(direction, dtype=float)
        d = d / np.linalg.norm(d)
        u = (p2 - p1)[:2]
        nu = np.linalg.norm(u)
        dxy = np.linalg.norm(d[:2])
        if nu > 1e-9 and dxy > 1e-9:
            u = u / nu
            # t d_xy - s u = v_xy - h_xy  (beam point above h, moved by t along the beam, meets
            # the horizontal pin line v + s u)
            M = np.array([[d[0], -u[0]], [d[1], -u[1]]])
            det = np.linalg.det(M)
            if abs(det) > 0.2 * dxy:  # pin not nearly parallel to the beam
                t, _ = np.linalg.solve(M, (v - h)[:2])
                z = v[2] - t * d[2]
    return np.array([h[0], h[1], z])


def common_perpendicular(a, b, c, d):
    """Feet ``P`` (on line AB) and ``Q`` (on line CD) of the common perpendicular (4-19 ... 4-21).

    Returns ``(P, Q, t_P, s_Q)`` with ``P = A + t_P (B - A)``, ``Q = C + s_Q (D - C)``.
    Raises ``SensorCalibrationError`` for (nearly) parallel lines.
    """
    A, B, C, D = (_vec3(x, n) for x, n in zip((a, b, c, d), "ABCD"))
    d1, d2, w = B - A, D - C, A - C
    k1, k2, k3 = d1 @ d1, d2 @ d2, d1 @ d2
    k4, k5 = w @ d1, w @ d2
    den = k3 * k3 - k1 * k2
    if k1 <= 0 or k2 <= 0 or abs(den) <= 1e-12 * k1 * k2:
        raise SensorCalibrationError(
            "the two beam lines are parallel (or a beam's two points coincide): "
            f"angle between AB and CD = {math.degrees(math.acos(min(1.0, abs(k3) / math.sqrt(max(k1 * k2, 1e-300))))):.3g} deg")
    t_p = (k2 * k4 - k3 * k5) / den
    s_q = (k3 * k4 - k1 * k5) / den
    return A + t_p * d1, C + s_q * d2, float(t_p), float(s_q)


# ---------------------------------------------------------------------------------------------
# the calibration result
# ---------------------------------------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class SensorCalibration:
    """The cross-laser sensor frame in the robot base frame (mm), thesis (4-27).

    ``origin_mm`` M; ``x_axis`` n (X beam, A -> B); ``y_axis`` m (measured Y beam, C -> D, unit,
    not necessarily orthogonal to n); ``y_axis_orthogonal`` o = p x n; ``z_axis`` p = n x m / |.|;
    ``T_base_sensor`` = [n o p M]; ``beta_deg`` angle from X_s to m about Z_s; ``gap_mm`` length of
    the common perpendicular; ``points``: the input points (A1 ... D4) and the derived points A, B,
    C, D (on the beams) and P, Q (feet of the common perpendicular on the X and Y beam).
    """

    origin_mm: np.ndarray
    x_axis: np.ndarray
    y_axis: np.ndarray
    y_axis_orthogonal: np.ndarray
    z_axis: np.ndarray
    T_base_sensor: np.ndarray
    beta_deg: float
    gap_mm: float
    points: dict = field(default_factory=dict)

    @property
    def beta_rad(self) -> float:
        return math.radians(self.beta_deg)

    @property
    def T_sensor_base(self) -> np.ndarray:
        from ..transforms import invert_transforms

        return invert_transforms(self.T_base_sensor)

    def to_dict(self) -> dict:
        """JSON-ready dict (lists and floats) with the keys of the CLI's ``--json`` output."""
        return {
            "origin_mm": [float(x) for x in self.origin_mm],
            "x_axis": [float(x) for x in self.x_axis],
            "y_axis": [float(x) for x in self.y_axis],
            "y_axis_orthogonal": [float(x) for x in self.y_axis_orthogonal],
            "z_axis": [float(x) for x in self.z_axis],
            "T_base_sensor": [[float(x) for x in row] for row in self.T_base_sensor],
            "beta_deg": float(self.beta_deg),
            "gap_mm": float(self.gap_mm),
            "points": {k: [float(x) for x in v] for k, v in self.points.items()},
        }


def calibrate_sensor(points: dict, refine_height: bool = True) -> SensorCalibration:
    """Calibrate the cross-laser sensor from the 16 recorded positions (thesis 4.3.1).

    ``points``: label -> (x, y, z) [mm, base frame] for A1..A4, B1..B4 (two points A, B on the
    X beam), C1..C4, D1..D4 (two points C, D on the Y beam); 1/2 = pin-axis (flange) position
    where the beam becomes blocked/unblocked while the vertical pin moves horizontally across
    it, 3/4 = the same while the horizontal pin moves down through it (see :func:`beam_point`).
    Labels are case-insensitive; other labels raise ``ValueError``.

    ``refine_height``: correct the height of each beam point for the beam's slope when 3/4 were
    not recorded straight above the 1/2 midpoint (see :func:`beam_point`); with 3/4 above the
    midpoint this changes nothing and the result is the thesis's (4-16).
    """
    if not isinstance(points, dict):
        raise ValueError(f"points: expected a dict label -> (x, y, z), got {type(points).__name__}")
    pts = {}
    for k, v in points.items():
        key = str(k).strip().upper()
        if key not in SENSOR_POINT_LABELS:
            raise ValueError(f"points: unknown label {k!r}; expected {', '.join(SENSOR_POINT_LABELS)}")
        if key in pts:
            raise ValueError(f"points: label {key!r} given twice")
        pts[key] = _vec3(v, f"points[{k!r}]")
    missing = [lab for lab in SENSOR_POINT_LABELS if lab not in pts]
    if missing:
        raise ValueError(f"points: missing labels {', '.join(missing)}")

    def four(P):
        return [pts[f"{P}{i}"] for i in (1, 2, 3, 4)]

    beam = {P: beam_point(*four(P), name=P) for P in BEAM_POINTS}
    for first, second in (("A", "B"), ("C", "D")):
        if np.linalg.norm(beam[second] - beam[first]) < 1e-6:
            raise SensorCalibrationError(
                f"beam points {first} and {second} coincide at {_fmt(beam[first])} mm: "
                "record two points well apart on each beam")
    if refine_height:
        for _ in range(20):
            dx = beam["B"] - beam["A"]
            dy = beam["D"] - beam["C"]
            new = {P: beam_point(*four(P), direction=dx if P in "AB" else dy, name=P) for P in BEAM_POINTS}
            change = max(float(np.abs(new[P] - beam[P]).max()) for P in BEAM_POINTS)
            beam = new
            if change < 1e-12:
                break
    A, B, C, D = (beam[P] for P in BEAM_POINTS)
    P, Q, _, _ = common_perpendicular(A, B, C, D)
    M = 0.5 * (P + Q)                                   # (4-22)
    n = (B - A) / np.linalg.norm(B - A)                 # (4-23)
    m = (D - C) / np.linalg.norm(D - C)                 # (4-24)
    nm = np.cross(n, m)
    p = nm / np.linalg.norm(nm)                         # (4-25)
    o = np.cross(p, n)                                  # (4-26)
    T = np.eye(4)
    T[:3, 0], T[:3, 1], T[:3, 2], T[:3, 3] = n, o, p, M  # (4-27)
    beta = math.degrees(math.atan2(float(m @ o), float(m @ n)))
    out_points = {k: pts[k].copy() for k in SENSOR_POINT_LABELS}
    out_points.update({"A": A, "B": B, "C": C, "D": D, "P": P, "Q": Q})
    return SensorCalibration(origin_mm=M, x_axis=n, y_axis=m, y_axis_orthogonal=o, z_axis=p,
                             T_base_sensor=T, beta_deg=beta, gap_mm=float(np.linalg.norm(Q - P)),
                             points=out_points)


# ---------------------------------------------------------------------------------------------
# beta correction (4-28 ... 4-30)
# ---------------------------------------------------------------------------------------------


def _check_beta(beta_rad):
    b = np.asarray(beta_rad, dtype=float)
    s = np.sin(b)
    if np.any(np.abs(s) < 1e-9):
        raise ValueError(f"beta_rad: the beams are parallel (beta = {np.degrees(b)} deg)")
    return b, s


def skew_to_orthogonal(u, v, beta_rad):
    """Oblique coordinates ``(u, v)`` along X_s and the real Y beam -> orthogonal ``(x, y)``.

    ``point = u X_s + v (cos beta, sin beta)``, so ``x = u + v cos(beta)``, ``y = v sin(beta)``
    (the step from the thesis's (x1, y1) (4-28) to (x2, y2) (4-29)). Broadcasts over arrays.
    """
    b, s = _check_beta(beta_rad)
    u = np.asarray(u, dtype=float)
    v = np.asarray(v, dtype=float)
    return u + v * np.cos(b), v * s


def orthogonal_to_skew(x, y, beta_rad):
    """Orthogonal ``(x, y)`` in (X_s, Y_s') -> oblique ``(u, v)``; inverse of :func:`skew_to_orthogonal`."""
    b, s = _check_beta(beta_rad)
    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    v = y / s
    return x - v * np.cos(b), v


def center_from_beam_distances(d_to_x_beam, d_to_y_beam, beta_rad):
    """Orthogonal sensor coordinates ``(x, y)`` of a point from its signed beam distances (4-29).

    ``d_to_x_beam`` (the thesis's d_x): signed perpendicular distance to the X beam, positive on
    the +Y_s' side; ``d_to_y_beam`` (d_y): signed perpendicular distance to the Y beam, positive on
    the +X_s side. ``x = d_y / sin(beta) + d_x / tan(beta)``, ``y = d_x``. For beta = 90 deg this
    is the thesis's uncorrected ``(d_y, d_x)``. Broadcasts over arrays.
    """
    b, s = _check_beta(beta_rad)
    dx = np.asarray(d_to_x_beam, dtype=float)
    dy = np.asarray(d_to_y_beam, dtype=float)
    return dy / s + dx * np.cos(b) / s, dx


def beam_distances_from_center(x, y, beta_rad):
    """Signed distances ``(d_x, d_y)`` of the point ``(x, y)`` to the X and Y beams (inverse of
    :func:`center_from_beam_distances`): ``d_x = y``, ``d_y = x sin(beta) - y cos(beta)``."""
    b = np.asarray(beta_rad, dtype=float)
    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    return y, x * np.sin(b) - y * np.cos(b)


def beta_error_mm(d, beta_rad, d_to_y_beam=None):
    """Error (4-30) of the x coordinate when beta is ignored, ``dE = d_y - x2``.

    ``d``: distance to the X beam (d_x); ``d_to_y_beam``: distance to the Y beam (d_y), default
    ``d`` (the thesis's figure 4-17 uses d_x = d_y = 5 mm). ``dE = d_y - d_y / sin(beta) -
    d_x / tan(beta)``; the y coordinate (= d_x) has no error.
    """
    b, s = _check_beta(beta_rad)
    dx = np.asarray(d, dtype=float)
    dy = dx if d_to_y_beam is None else np.asarray(d_to_y_beam, dtype=float)
    return dy - dy / s - dx * np.cos(b) / s


def beta_error_threshold_deg(limit_mm: float = 0.1, d: float = 5.0, d_to_y_beam=None) -> tuple:
    """Smallest ``|beta - 90 deg|`` (negative and positive side) where ``|beta_error_mm| = limit_mm``.

    Returns ``(below, above)`` in degrees: the deviations ``beta = 90 - below`` and
    ``beta = 90 + above`` at which the uncorrected error first reaches ``limit_mm``.
    """
    from scipy.optimize import brentq

    def f(delta_deg):
        return abs(float(beta_error_mm(d, math.radians(90.0 + delta_deg), d_to_y_beam))) - limit_mm

    out = []
    for sign in (-1.0, 1.0):
        hi = 1e-6
        while f(sign * hi) < 0:
            hi *= 1.5
            if hi > 89:
                raise ValueError(f"the error never reaches {limit_mm} mm at d = {d} mm")
        out.append(brentq(lambda x, sign=sign: f(sign * x), 0.0, hi, xtol=1e-12))
    return tuple(out)
