"""ISO 9283:1998 performance characteristics, computed from attained and commanded poses.

Definitions in our own words (the standard's clause numbers in brackets):

* **Barycentre** of the ``n`` attained positions of one commanded pose: their mean
  ``(x̄, ȳ, z̄)`` [7.2.1].
* **Pose accuracy** ``AP_P``: the distance from the commanded position to the barycentre; its
  components ``AP_x = x̄ − x_c`` etc. Orientation: ``AP_a = ā − a_c`` (and ``b``, ``c``), the mean
  deviation of the attained orientation about the base x, y and z axes [7.2.1].
* **Pose repeatability** ``RP_l = l̄ + 3·S_l`` with ``l_j`` the distance of attained position ``j``
  from the barycentre, ``l̄`` their mean and ``S_l`` their standard deviation (``n − 1``).
  Orientation: ``RP_a = ±3·S_a`` (``S_a`` the standard deviation of the angle ``a``) [7.2.2].
* **Multi-directional pose accuracy variation** ``vAP_P``: the largest distance between the
  barycentres reached when the same pose is approached from different directions; ``vAP_a`` the
  largest difference of the mean angles [7.2.3].
* **Distance accuracy** ``AD_P = D̄ − D_c``: the mean attained distance between two poses minus the
  commanded one (``AD_x = D̄_x − D_cx`` with ``D_x = x_1 − x_2``); **distance repeatability**
  ``RD = ±3·S_D`` [7.3].
* **Drift** of the pose characteristics: ``dAP = |AP_t=1 − AP_t=T|`` and ``dRP = |RP_t=1 − RP_t=T|``
  between the first and the last measurement block of a long run [7.6].
* **Path accuracy** ``AT_P``: the largest distance, over the evaluation planes normal to the
  commanded path, between a commanded path point and the barycentre of the attained paths'
  crossings of that plane; **path repeatability** ``RT_P = max(l̄_i + 3·S_li)`` in the same planes [8.2, 8.3].

Orientation deviations are the rotation vector of ``R_attained · R_commandedᵀ`` expressed in the
base axes (``a`` about x, ``b`` about y, ``c`` about z), the small-angle reading of the standard's
angle differences that does not depend on an Euler convention.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..transforms import rotvec_from_matrix

__all__ = [
    "PoseCharacteristics", "PathCharacteristics", "pose_characteristics", "multidirectional_variation",
    "distance_characteristics", "drift_characteristics", "path_characteristics", "orientation_deviations_deg",
]


def _points(x, name: str) -> np.ndarray:
    a = np.asarray(x, dtype=float)
    if a.ndim != 2 or a.shape[1] != 3 or len(a) < 2:
        raise ValueError(f"{name} must have shape (n, 3) with n >= 2, got {a.shape}")
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{name} contains non-finite values")
    return a


def orientation_deviations_deg(R_attained, R_commanded) -> np.ndarray:
    """Orientation deviations (n, 3) [deg] about the base x, y, z axes (``a``, ``b``, ``c``).

    R_attained: (n, 3, 3) attained rotations; R_commanded: (3, 3) or (n, 3, 3) commanded ones.
    The deviation is the rotation vector of ``R_attained @ R_commanded.T``.
    """
    Ra = np.asarray(R_attained, dtype=float).reshape(-1, 3, 3)
    Rc = np.broadcast_to(np.asarray(R_commanded, dtype=float), Ra.shape)
    return np.degrees(rotvec_from_matrix(Ra @ np.swapaxes(Rc, -1, -2)))


@dataclass(frozen=True)
class PoseCharacteristics:
    """Pose accuracy and repeatability of one commanded pose (ISO 9283 7.2).

    Attributes
    ----------
    n : int
        Number of attained poses (cycles).
    barycentre_mm : ndarray, shape (3,)
        Mean attained position [mm].
    AP_mm : float
        Position accuracy ``AP_P`` [mm].
    AP_xyz_mm : ndarray, shape (3,)
        ``AP_x, AP_y, AP_z`` [mm].
    l_mean_mm, S_l_mm, RP_mm : float
        Mean distance from the barycentre, its standard deviation and ``RP_l = l̄ + 3 S_l`` [mm].
    AP_abc_deg, RP_abc_deg : ndarray, shape (3,) or None
        Orientation accuracy (mean deviation) and repeatability ``±3 S`` about x, y, z [deg];
        ``None`` when no orientation was measured.
    """

    n: int
    barycentre_mm: np.ndarray
    AP_mm: float
    AP_xyz_mm: np.ndarray
    l_mean_mm: float
    S_l_mm: float
    RP_mm: float
    AP_abc_deg: np.ndarray | None = None
    RP_abc_deg: np.ndarray | None = None

    def as_dict(self) -> dict:
        """JSON-ready values keyed by the standard's symbols."""
        d = {"n": self.n, "barycentre_mm": [float(v) for v in self.barycentre_mm], "AP_mm": float(self.AP_mm),
             "AP_x_mm": float(self.AP_xyz_mm[0]), "AP_y_mm": float(self.AP_xyz_mm[1]),
             "AP_z_mm": float(self.AP_xyz_mm[2]), "l_mean_mm": float(self.l_mean_mm), "S_l_mm": float(self.S_l_mm),
             "RP_mm": float(self.RP_mm)}
        if self.AP_abc_deg is not None:
            for k, s in enumerate("abc"):
                d[f"AP_{s}_deg"] = float(self.AP_abc_deg[k])
                d[f"RP_{s}_deg"] = float(self.RP_abc_deg[k])
        return d


def pose_characteristics(attained_mm, commanded_mm, R_attained=None, R_commanded=None) -> PoseCharacteristics:
    """AP and RP of one commanded pose from its ``n`` attained poses (ISO 9283 7.2.1, 7.2.2).

    Parameters
    ----------
    attained_mm : array_like, shape (n, 3)
        Attained positions [mm] in the base frame, one per cycle.
    commanded_mm : array_like, shape (3,)
        Commanded position [mm].
    R_attained : array_like, shape (n, 3, 3), optional
        Attained orientations; with ``R_commanded`` (3, 3) gives the orientation figures.

    Returns
    -------
    PoseCharacteristics
    """
    x = _points(attained_mm, "attained_mm")
    xc = np.asarray(commanded_mm, dtype=float).reshape(3)
    bary = x.mean(axis=0)
    ap_xyz = bary - xc
    l = np.linalg.norm(x - bary, axis=1)
    l_mean = float(l.mean())
    s_l = float(l.std(ddof=1))
    ap_abc = rp_abc = None
    if R_attained is not None:
        if R_commanded is None:
            raise ValueError("R_attained needs R_commanded")
        dev = orientation_deviations_deg(R_attained, R_commanded)
        if len(dev) != len(x):
            raise ValueError(f"R_attained has {len(dev)} rotations for {len(x)} positions")
        ap_abc = dev.mean(axis=0)
        rp_abc = 3.0 * dev.std(axis=0, ddof=1)
    return PoseCharacteristics(len(x), bary, float(np.linalg.norm(ap_xyz)), ap_xyz, l_mean, s_l,
                               l_mean + 3.0 * s_l, ap_abc, rp_abc)


def multidirectional_variation(attained_by_direction, R_by_direction=None, R_commanded=None) -> dict:
    """vAP of one pose approached from several directions (ISO 9283 7.2.3).

    Parameters
    ----------
    attained_by_direction : sequence of array_like, each shape (n_h, 3)
        Attained positions [mm] for each approach direction ``h``.
    R_by_direction : sequence of array_like, each (n_h, 3, 3), optional
        Attained orientations per direction (with ``R_commanded``) for ``vAP_a, vAP_b, vAP_c``.

    Returns
    -------
    dict
        ``vAP_mm`` (largest distance between the direction barycentres [mm]), ``barycentres_mm``
        (n_dir, 3) and, with orientations, ``vAP_a_deg``, ``vAP_b_deg``, ``vAP_c_deg``.
    """
    groups = [_points(g, f"attained_by_direction[{i}]") for i, g in enumerate(attained_by_direction)]
    if len(groups) < 2:
        raise ValueError("vAP needs at least two approach directions")
    bary = np.array([g.mean(axis=0) for g in groups])
    diff = np.linalg.norm(bary[:, None, :] - bary[None, :, :], axis=-1)
    out = {"vAP_mm": float(diff.max()), "barycentres_mm": bary.tolist()}
    if R_by_direction is not None:
        means = np.array([orientation_deviations_deg(R, R_commanded).mean(axis=0) for R in R_by_direction])
        span = means.max(axis=0) - means.min(axis=0)
        for k, s in enumerate("abc"):
            out[f"vAP_{s}_deg"] = float(span[k])
    return out


def distance_characteristics(attained_1_mm, attained_2_mm, commanded_1_mm, commanded_2_mm) -> dict:
    """Distance accuracy AD and repeatability RD between two poses (ISO 9283 7.3).

    Parameters
    ----------
    attained_1_mm, attained_2_mm : array_like, shape (n, 3)
        Attained positions [mm] of the two poses in the same ``n`` cycles.
    commanded_1_mm, commanded_2_mm : array_like, shape (3,)
        Commanded positions [mm].

    Returns
    -------
    dict
        ``D_c_mm``, ``D_mean_mm``, ``AD_mm`` (= D̄ − D_c), ``AD_x_mm``, ``AD_y_mm``, ``AD_z_mm``,
        ``S_D_mm`` and ``RD_mm`` (= 3·S_D, stated as ±).
    """
    a, b = _points(attained_1_mm, "attained_1_mm"), _points(attained_2_mm, "attained_2_mm")
    if a.shape != b.shape:
        raise ValueError(f"the two poses need the same cycles: {a.shape} vs {b.shape}")
    c1, c2 = np.asarray(commanded_1_mm, float).reshape(3), np.asarray(commanded_2_mm, float).reshape(3)
    dc = c1 - c2
    dj = a - b
    d = np.linalg.norm(dj, axis=1)
    ad_xyz = dj.mean(axis=0) - dc
    s_d = float(d.std(ddof=1))
    return {"D_c_mm": float(np.linalg.norm(dc)), "D_mean_mm": float(d.mean()),
            "AD_mm": float(d.mean() - np.linalg.norm(dc)), "AD_x_mm": float(ad_xyz[0]),
            "AD_y_mm": float(ad_xyz[1]), "AD_z_mm": float(ad_xyz[2]), "S_D_mm": s_d, "RD_mm": 3.0 * s_d}


def drift_characteristics(first: PoseCharacteristics, last: PoseCharacteristics) -> dict:
    """Drift of pose accuracy and repeatability between the first and the last block (ISO 9283 7.6).

    Returns ``dAP_mm = |AP_first − AP_last|`` (the distance between the two barycentres'
    accuracy vectors' lengths, as the standard states it on ``AP_P``) and ``dRP_mm``.
    """
    return {"dAP_mm": float(abs(first.AP_mm - last.AP_mm)), "dRP_mm": float(abs(first.RP_mm - last.RP_mm)),
            "barycentre_shift_mm": float(np.linalg.norm(first.barycentre_mm - last.barycentre_mm))}


@dataclass(frozen=True)
class PathCharacteristics:
    """Path accuracy and repeatability (ISO 9283 8.2, 8.3).

    Attributes
    ----------
    AT_mm : float
        Largest distance between a commanded path point and the barycentre of the attained
        crossings of its normal plane [mm].
    RT_mm : float
        Largest ``l̄_i + 3 S_li`` over the evaluation planes [mm].
    deviation_mm : ndarray, shape (m,)
        Barycentre deviation per evaluation plane [mm].
    repeatability_mm : ndarray, shape (m,)
        ``l̄_i + 3 S_li`` per plane [mm].
    n_cycles : int
    """

    AT_mm: float
    RT_mm: float
    deviation_mm: np.ndarray
    repeatability_mm: np.ndarray
    n_cycles: int

    def as_dict(self) -> dict:
        return {"AT_mm": float(self.AT_mm), "RT_mm": float(self.RT_mm), "n_cycles": self.n_cycles,
                "deviation_mm": [float(v) for v in self.deviation_mm],
                "repeatability_mm": [float(v) for v in self.repeatability_mm]}


def _plane_crossing(samples: np.ndarray, point: np.ndarray, normal: np.ndarray) -> np.ndarray | None:
    """Where a sampled path (k, 3) crosses the plane through ``point`` with unit ``normal``:
    the linear interpolation on the crossing segment nearest ``point`` (None if it never crosses)."""
    s = (samples - point) @ normal
    idx = np.flatnonzero((s[:-1] <= 0) & (s[1:] > 0) | (s[:-1] >= 0) & (s[1:] < 0))
    if idx.size == 0:
        return None
    t = s[idx] / (s[idx] - s[idx + 1])
    cand = samples[idx] + t[:, None] * (samples[idx + 1] - samples[idx])
    return cand[np.argmin(np.linalg.norm(cand - point, axis=1))]


def path_characteristics(commanded_points_mm, tangents, attained_paths_mm) -> PathCharacteristics:
    """AT and RT from continuously measured paths (ISO 9283 8.2, 8.3).

    Parameters
    ----------
    commanded_points_mm : array_like, shape (m, 3)
        Evaluation points on the commanded path [mm].
    tangents : array_like, shape (m, 3)
        Path direction at each point (the normal of its evaluation plane; normalised here).
    attained_paths_mm : sequence of array_like, each shape (k_j, 3)
        The samples of each cycle's attained path [mm], in time order.

    Returns
    -------
    PathCharacteristics

    Raises
    ------
    ValueError
        If an attained path does not cross an evaluation plane (the path was not measured there).
    """
    P = np.asarray(commanded_points_mm, float).reshape(-1, 3)
    Tn = np.asarray(tangents, float).reshape(-1, 3)
    Tn = Tn / np.linalg.norm(Tn, axis=1, keepdims=True)
    paths = [np.asarray(p, float).reshape(-1, 3) for p in attained_paths_mm]
    if len(paths) < 2:
        raise ValueError("path repeatability needs at least two cycles")
    dev = np.empty(len(P))
    rep = np.empty(len(P))
    for i, (p, n) in enumerate(zip(P, Tn)):
        xs = []
        for j, path in enumerate(paths):
            c = _plane_crossing(path, p, n)
            if c is None:
                raise ValueError(f"cycle {j + 1}'s attained path does not cross the evaluation plane at point "
                                 f"{i + 1} ({p[0]:.1f}, {p[1]:.1f}, {p[2]:.1f}) mm")
            xs.append(c)
        x = np.array(xs)
        bary = x.mean(axis=0)
        dev[i] = np.linalg.norm(bary - p)
        l = np.linalg.norm(x - bary, axis=1)
        rep[i] = l.mean() + 3.0 * l.std(ddof=1)
    return PathCharacteristics(float(dev.max()), float(rep.max()), dev, rep, len(paths))
