"""The ISO 9283 test cube and the test poses P1–P5 (ISO 9283:1998, 6.8).

The standard places a cube with edges parallel to the base axes in the part of the working space
the robot uses most, as large as the working space allows. The test poses lie on one of the cube's
diagonal planes (the plane through two opposite edges): **P1** at the cube's centre, **P2–P5** on
the plane's diagonals, each at 10 % of the diagonal's length from a corner. All poses share one
orientation (the tool pointing down for a floor-mounted robot by default).

:func:`largest_iso_cube` searches cube centres in front of the robot and, for each, the largest
edge whose test points (corners, edge mid-points, face centres and P1–P5) are all reachable on one
arm configuration, inside the joint ranges, with every link frame above the mounting plane.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..kinematics.ik import ik_numeric
from ..kinematics.ik_analytic import ik_analytic, is_analytic

__all__ = ["IsoCube", "iso_cube_points", "iso_test_poses", "largest_iso_cube", "reachable_on_one_branch"]

#: the plane's corners (signs of x, y, z relative to the centre): through the edge at x-, z- (along y)
#: and the opposite edge at x+, z+; P2..P5 lie near these corners in this order
_PLANE_CORNERS = np.array([[-1, -1, -1], [-1, 1, -1], [1, 1, 1], [1, -1, 1]], dtype=float)


@dataclass(frozen=True)
class IsoCube:
    """The test cube: centre [mm] and edge [mm] in the robot's base frame, and the test orientation.

    Attributes
    ----------
    centre_mm : ndarray, shape (3,)
    edge_mm : float
    R_base_tool : ndarray, shape (3, 3)
        Orientation of every test pose (of the flange or of the declared tool).
    branch : int
        Arm configuration (closed-form branch index) on which every test point is reachable,
        or -1 when found by the numerical IK.
    """

    centre_mm: np.ndarray
    edge_mm: float
    R_base_tool: np.ndarray
    branch: int = -1

    def corners(self) -> np.ndarray:
        """C1–C8 (8, 3) [mm]."""
        s = np.array([[x, y, z] for z in (-1, 1) for y in (-1, 1) for x in (-1, 1)], dtype=float)
        return self.centre_mm + 0.5 * self.edge_mm * s


def iso_test_poses(centre_mm, edge_mm: float) -> np.ndarray:
    """P1–P5 (5, 3) [mm]: P1 the centre, P2–P5 at 10 % of the diagonal from the plane's corners."""
    c = np.asarray(centre_mm, float).reshape(3)
    corners = c + 0.5 * float(edge_mm) * _PLANE_CORNERS
    # 10 % of the diagonal from a corner = 20 % of the half diagonal, towards the centre
    p = c + 0.8 * (corners - c)
    return np.vstack([c, p])


def iso_cube_points(centre_mm, edge_mm: float) -> np.ndarray:
    """Points (32, 3) [mm] whose reachability stands for the cube's: 8 corners, 12 edge mid-points,
    6 face centres, the centre and P2–P5."""
    c = np.asarray(centre_mm, float).reshape(3)
    h = 0.5 * float(edge_mm)
    pts = []
    for sx in (-1, 0, 1):
        for sy in (-1, 0, 1):
            for sz in (-1, 0, 1):
                nz = (sx != 0) + (sy != 0) + (sz != 0)
                if nz >= 1 or (sx, sy, sz) == (0, 0, 0):
                    if nz in (1, 2, 3) or nz == 0:
                        pts.append(c + h * np.array([sx, sy, sz], float))
    pts = np.array(pts)                      # 27 points: the 3x3x3 grid
    return np.vstack([pts, iso_test_poses(c, edge_mm)[1:]])


def reachable_on_one_branch(model, points_mm, R_base_tool, T_flange_tool=None, *, q_seed=None,
                            min_link_z_mm: float | None = 0.0, multi_start: bool = True, feasible=None):
    """Joints reaching every point with one orientation on one arm configuration, or None.

    Parameters
    ----------
    model : RobotModel
    points_mm : array_like, shape (M, 3)
        Tool positions [mm] in the robot's base frame.
    R_base_tool : array_like, shape (3, 3)
    T_flange_tool : array_like, shape (4, 4), optional
        The tool; the flange is ``T_base_tool @ inv(T_flange_tool)``.
    q_seed : array_like, shape (n_joints,), optional
        Start of the numerical IK (robots without a closed form).
    multi_start : bool
        Numerical IK: also try a few deterministic starts across the ranges of J2 and J3.
    feasible : callable, optional
        ``feasible(q) -> (M,) bool``: the cell's checks (obstacles, self-collision, the user's
        joint ranges; :func:`robocal.calib.cell.feasible`). Every pose must pass.
    min_link_z_mm : float or None
        Every link frame's z in the base frame must be at least this (None: not checked).

    Returns
    -------
    (q, branch) : ((M, n_joints) [rad | mm], int) or None
    """
    P = np.asarray(points_mm, float).reshape(-1, 3)
    M = len(P)
    T = np.broadcast_to(np.eye(4), (M, 4, 4)).copy()
    T[:, :3, :3] = R_base_tool
    T[:, :3, 3] = P
    if T_flange_tool is not None:
        T = T @ np.linalg.inv(np.asarray(T_flange_tool, float))
    T_world = model.T_world_base @ T
    inv_base = np.linalg.inv(model.T_world_base)

    def links_ok(q):
        if feasible is not None and not bool(np.all(feasible(q))):
            return False
        if min_link_z_mm is None:
            return True
        frames = inv_base @ model.link_frames(q)
        return bool(np.all(frames[..., 2, 3] >= min_link_z_mm))

    if is_analytic(model):
        q8, valid = ik_analytic(model, T_world, within_limits=True)
        for b in np.flatnonzero(valid.all(axis=0)):
            q = q8[:, b, :]
            if links_ok(q):
                return q, int(b)
        return None
    # one configuration for every point: solve the first point (the cube's centre) from a few
    # deterministic starts, then every point from that solution
    lo, hi = model.limits[:, 0], model.limits[:, 1]
    starts = [model.limits.mean(axis=1) if q_seed is None else np.asarray(q_seed, float)]
    grid = np.linspace(0.25, 0.75, 3) if multi_start else []
    for a in grid:
        for b in grid:
            q = lo + 0.5 * (hi - lo)
            q[1] = lo[1] + a * (hi[1] - lo[1])
            if model.n_joints > 2:
                q[2] = lo[2] + b * (hi[2] - lo[2])
            starts.append(q)
    for q0 in starts:
        r0 = ik_numeric(model, T_world[:1], q0)
        if not np.all(r0.converged) or not links_ok(r0.q[:1]):
            continue
        res = ik_numeric(model, T_world, r0.q[0])
        if np.all(res.converged) and links_ok(res.q):
            return res.q, -1
    return None


def largest_iso_cube(model, R_base_tool=None, T_flange_tool=None, *, min_height_mm: float = 100.0,
                     n_radial: int = 12, n_height: int = 10, q_seed=None, feasible=None) -> IsoCube:
    """The largest ISO cube in front of the robot (centre on the base x axis, y = 0).

    Parameters
    ----------
    model : RobotModel
    R_base_tool : array_like, shape (3, 3), optional
        Test orientation; default the tool z axis pointing down (``diag(1, -1, -1)``).
    T_flange_tool : array_like, shape (4, 4), optional
    min_height_mm : float
        The cube's lowest face and every link frame stay at least this high above the mounting
        plane (z = 0 of the base) [mm].
    n_radial, n_height : int
        Grid of candidate centres.
    feasible : callable, optional
        The cell's pose checks (see :func:`reachable_on_one_branch`).

    Returns
    -------
    IsoCube

    Raises
    ------
    robocal.errors.NotIdentifiableError
        If no cube of at least 10 mm fits.
    """
    from ..errors import NotIdentifiableError

    R = np.diag([1.0, -1.0, -1.0]) if R_base_tool is None else np.asarray(R_base_tool, float)
    # reach scale: the flange distance at the middle of the joint ranges and at zero
    q_mid = model.limits.mean(axis=1)
    reach = max(np.linalg.norm((np.linalg.inv(model.T_world_base) @ model.fk(q))[:3, 3])
                for q in (q_mid, np.zeros(model.n_joints)))
    best = None
    for r in np.linspace(0.2, 0.9, n_radial) * reach:
        for z in np.linspace(-0.2, 0.9, n_height) * reach:
            c = np.array([r, 0.0, z])

            if c[2] < min_height_mm:
                continue
            found = reachable_on_one_branch(model, c[None], R, T_flange_tool, q_seed=q_seed, min_link_z_mm=0.0,
                                            feasible=feasible)
            if found is None:
                continue
            q_c = found[0][0]

            def fits(edge, c=c, q_c=q_c):
                if c[2] - edge / 2 < min_height_mm:
                    return None
                return reachable_on_one_branch(model, iso_cube_points(c, edge), R, T_flange_tool,
                                               q_seed=q_c, min_link_z_mm=0.0, multi_start=False, feasible=feasible)

            lo, hi = 0.0, 2.0 * reach
            if best is not None and fits(best.edge_mm) is None:
                continue
            if best is not None:
                lo = best.edge_mm
            for _ in range(14):
                mid = 0.5 * (lo + hi)
                if fits(mid) is not None:
                    lo = mid
                else:
                    hi = mid
            if lo >= 10.0 and (best is None or lo > best.edge_mm):
                q_b = fits(lo)
                if q_b is not None:
                    best = IsoCube(c, float(lo), R, q_b[1])
    if best is None:
        raise NotIdentifiableError(f"{model.name}: no ISO cube of 10 mm or more is reachable with the test "
                                   "orientation above the mounting plane")
    # a round edge (whole 10 mm, as test plans state it)
    edge = np.floor(best.edge_mm / 10.0) * 10.0 if best.edge_mm >= 20 else best.edge_mm
    q_b = reachable_on_one_branch(model, iso_cube_points(best.centre_mm, edge), R, T_flange_tool, q_seed=q_seed,
                                  min_link_z_mm=0.0, feasible=feasible)
    return IsoCube(best.centre_mm, float(edge), R, q_b[1] if q_b else best.branch)
