"""The virtual closed kinematic chain on the calibration core (METHODS.md section 3).

A laser pointer on the flange is held on fixed marks ("spots") of a plate from several
configurations; the joints are the only measurement. :class:`ClosedChainProblem` is a
:class:`~robocal.calib.core.Problem` of four parameter blocks and one or two residual blocks:

* ``geometry`` -- the robot's kinematic parameters (:class:`~robocal.calib.blocks.RobotGeometry`);
* ``base`` -- the robot base, fixed: it *is* the reference frame (nothing outside the robot is
  measured, so the base frame cannot be identified);
* ``laser`` -- the mount errors theta_x, theta_y, px, py of eq. 3 (:class:`~robocal.calib.blocks.LaserMount`);
* ``spots`` -- every spot's position (S, 3) [mm] in the base frame, unknown;
* residuals: :class:`~robocal.calib.residuals.RaySpotResidual` (eq. 5, two in-plate rows per held
  spot) and, with a known target spacing, :class:`~robocal.calib.residuals.PointSpacingResidual`.

Gauge freedoms, stated rather than hidden (docs/closed-chain.md): rotating the whole arm about the
first joint axis or shifting it along it moves every spot the same way, so those parameters trade
off against the spots and the identifiability report holds them; and with no known distance every
length can grow by one factor (:func:`length_scale_check`), in which case one length parameter is
held at its nominal value to fix the scale (:attr:`ClosedChainProblem.scale_held`).
"""

from __future__ import annotations

import numpy as np

from .blocks import LaserMount, RobotGeometry, VectorBlock
from .core import Problem
from .errors import ProblemError
from .identifiability import analyse_identifiability
from .residuals import PointSpacingResidual, RaySpotResidual, laser_chain
from .residuals.base import Evaluation
from .residuals.ray_spot import BEAM_LENGTH_MM

__all__ = ["ClosedChainError", "ClosedChainProblem", "spot_index", "triangulate_spots", "length_scale_check",
           "practically_unidentifiable", "classify_unidentified", "e_op"]


class ClosedChainError(ProblemError):
    """The held spots cannot close a chain (a spot held once only, rays that never cross, ...)."""


def spot_index(plate, target):
    """``(spot_of_row (H,), spots [(plate, target), ...], plate_of_spot (S,))`` in order of first appearance."""
    keys, index = [], {}
    rows = []
    for p, t in zip(plate, target):
        k = (str(p), str(t))
        if k not in index:
            index[k] = len(keys)
            keys.append(k)
        rows.append(index[k])
    plates = sorted({p for p, _ in keys}, key=[p for p, _ in keys].index)
    return np.array(rows, dtype=int), keys, np.array([plates.index(p) for p, _ in keys], dtype=int)


def triangulate_spots(origins, directions, spot_of_row, n_spots: int, labels=None) -> np.ndarray:
    """Least-squares point (S, 3) [mm] closest to the rays held on each spot.

    origins, directions (H, 3): ray origins [mm] and unit directions. A spot held fewer than twice,
    or whose rays are (nearly) parallel, raises :class:`ClosedChainError` naming it.
    """
    labels = labels or [str(s) for s in range(n_spots)]
    counts = np.bincount(spot_of_row, minlength=n_spots)
    single = [labels[s] for s in np.flatnonzero(counts < 2)]
    if single:
        raise ClosedChainError(f"spot(s) {', '.join(single[:8])}{' ...' if len(single) > 8 else ''} held in only one "
                               "configuration: a chain closes only when the same spot is held from two or more "
                               "configurations")
    Pm = np.eye(3) - np.einsum("hi,hj->hij", directions, directions)  # projections across each ray
    A = np.zeros((n_spots, 3, 3))
    b = np.zeros((n_spots, 3))
    np.add.at(A, spot_of_row, Pm)
    np.add.at(b, spot_of_row, np.einsum("hij,hj->hi", Pm, origins))
    ev = np.linalg.eigvalsh(A)
    bad = np.flatnonzero(ev[:, 0] < 1e-4 * counts)
    if bad.size:
        raise ClosedChainError(f"spot {labels[bad[0]]}: its rays are (nearly) parallel, so they do not fix the spot; "
                               "hold it from configurations whose beams cross at an angle (10 deg or more)")
    return np.linalg.solve(A, b[..., None])[..., 0]


def _plate_normals(P, plate_of_spot, directions, spot_of_row) -> np.ndarray:
    """(S, 3) unit normals, one per plate: the plane through its spots when they span one, else
    the mean beam direction of its held spots (the plate faces the laser)."""
    normals = np.zeros((len(P), 3))
    for g in np.unique(plate_of_spot):
        on = plate_of_spot == g
        beams = directions[np.isin(spot_of_row, np.flatnonzero(on))]
        toward = -beams.mean(axis=0)
        n = toward / np.linalg.norm(toward)
        if on.sum() >= 3:
            X = P[on] - P[on].mean(axis=0)
            _, s, Vt = np.linalg.svd(X, full_matrices=False)
            if s[1] > 0.1 * s[0] and s[2] < 0.05 * s[1]:
                n = Vt[2] * np.sign(Vt[2] @ toward)
        normals[on] = n
    return normals


class ClosedChainProblem(Problem):
    """The closed-chain calibration of ``model`` from held spots.

    q (H, n_ctrl) [rad | mm]: the joints of every held spot; plate, target (H,): their labels;
    free: geometry parameter names to identify (default the model's free ones; ``[]`` holds the
    geometry, the "before" fit); sigma_mm: in-plate spread of a held spot per axis [mm];
    spacing_mm: the known distance between consecutive targets of a plate (in order of first
    appearance), or ``None``; spacing_sigma_mm: its uncertainty; laser_T0 (4, 4): nominal mount;
    laser_initial (4,): start of the mount errors; hold: geometry names held fixed in addition
    (e.g. practically unidentifiable ones); end_effector: the end effector carrying the laser;
    spots_initial (S, 3): start of the spots (default: triangulated from the nominal rays);
    fix_scale: hold one length when the scale is free; check_closure: refuse held spots of which
    none repeats (off to evaluate single rows against known spots).

    Attributes: ``geometry``, ``frames``, ``laser``, ``spots``, ``ray`` (the residual), ``spacing``
    (or ``None``), ``spot_labels`` [(plate, target)], ``plate_of_spot``, ``spot_of_row``,
    ``scale_held`` (the length parameter whose nominal value fixes the scale when no known distance
    does: a length not estimated, else the largest free one, then held; or ``None``), ``held`` (names held
    by ``hold``), ``model``.
    """

    def __init__(self, model, q, plate, target, *, free=None, sigma_mm: float = 0.05, spacing_mm=None,
                 spacing_sigma_mm: float = 0.02, laser_T0=None, laser_initial=(0.0, 0.0, 0.0, 0.0), hold=(),
                 end_effector=None, spots_initial=None, fix_scale: bool = True, check_closure: bool = True):
        self.model = model
        q = np.asarray(q, dtype=float)
        self.spot_of_row, self.spot_labels, self.plate_of_spot = spot_index(plate, target)
        S = len(self.spot_labels)
        if check_closure and S == len(q):
            raise ClosedChainError(f"no chain closes: all {len(q)} held spots are on different (plate, target) "
                                   "pairs; hold each target from two or more configurations (at least 4 are needed "
                                   "for a useful calibration)")
        names = [n for n, f in zip(model.params.names, model.params.free) if f] if free is None else list(free)
        self.held = [n for n in names if n in set(hold)]
        names = [n for n in names if n not in set(hold)]
        self.geometry = RobotGeometry(model, names) if names else RobotGeometry(model, [], free=False)
        self.laser = LaserMount(laser_initial, T0=laser_T0)
        chain = laser_chain(model, q, self.geometry, end_effector=end_effector)
        self.frames = chain.frames
        labels = [f"{p}.{t}" for p, t in self.spot_labels]
        spot_names = [f"{lab}.{c}" for lab in labels for c in "xyz"]
        pts_f, _ = self.laser.beam_points(self.laser.initial, BEAM_LENGTH_MM)
        pts = chain.predict(self.geometry.initial, self.frames.initial, pts_f, chain.q, chain.stations).points
        u = (pts[:, 1] - pts[:, 0]) / BEAM_LENGTH_MM
        P0 = (triangulate_spots(pts[:, 0], u, self.spot_of_row, S, labels) if spots_initial is None
              else np.asarray(spots_initial, dtype=float).reshape(S, 3))
        self.spots = VectorBlock("spots", spot_names, ["mm"] * (3 * S), P0, group="targets")
        normals = _plate_normals(P0, self.plate_of_spot, u, self.spot_of_row)
        self.ray = RaySpotResidual(chain, self.laser, self.spots, self.spot_of_row, normals, sigma=sigma_mm)
        self.spacing = None
        if spacing_mm is not None:
            pairs = [(a, a + 1) for a in range(S - 1) if self.plate_of_spot[a] == self.plate_of_spot[a + 1]]
            if not pairs:
                raise ClosedChainError("--target-spacing: no plate has two targets")
            self.spacing = PointSpacingResidual(self.spots, pairs, float(spacing_mm), sigma=spacing_sigma_mm)
        blocks = [self.geometry, self.frames, self.laser, self.spots]
        residuals = [self.ray] + ([self.spacing] if self.spacing is not None else [])
        super().__init__(blocks, residuals, n_poses=len(q))
        self.scale_held = None
        if fix_scale and names and not length_scale_check(self)["identifiable"]:
            fixed = _fixed_length(model, names)
            self.scale_held = fixed or _scale_anchor(model, names)
            if not fixed:
                self._hold_geometry([self.scale_held])

    def _hold_geometry(self, names) -> None:
        """Fix geometry variables ``names`` (and rebuild the column layout)."""
        free = self.geometry.free.copy()
        for n in names:
            free[self.geometry.names.index(n)] = False
        self.geometry.free = free
        self._build_columns()

    def spot_errors(self, state) -> np.ndarray:
        """|E_i| [mm] per held spot (eq. 5) at ``state``."""
        ev = Evaluation(dict(zip(self.parameter_blocks, state)), False)
        return self.ray.errors(self.ray.evaluate(ev, False)[0])


def _fixed_length(model, names):
    """A non-zero length parameter of ``model`` not among ``names`` (held at its value: it already
    fixes the scale), or ``None``."""
    for n, u, v in zip(model.params.names, model.params.units, model.params.values):
        if u == "mm" and n not in names and abs(v) > 1.0:
            return n
    return None


def _scale_anchor(model, names) -> str:
    """The length parameter that fixes the scale: the free length with the largest nominal value."""
    lengths = [(abs(model.params.values[model.params.index(n)]), n) for n in names
               if model.params.units[model.params.index(n)] == "mm"]
    if not lengths:
        raise ClosedChainError("the length scale is free and no length parameter can hold it")
    return max(lengths)[1]


def length_scale_check(problem: Problem, state=None, tol: float = 1e-6) -> dict:
    """Can the data fix the length scale? Scaling every length of the robot model (all of them,
    estimated or not), of the mount and of the spots by ``1 + e`` scales residuals that carry no
    length reference by the same factor: then ``J s = -r`` exactly (``s``: the scale direction,
    each mm variable times its value) and the scale is a gauge freedom, whatever length is held.
    Only a known distance (a spacing residual) breaks it. Returns ``{"identifiable": bool,
    "mismatch": |J s + r| / |J s|}`` (prior rows are left out)."""
    state = problem.initial_state() if state is None else state
    geom = next(b for b in problem.parameter_blocks if isinstance(b, RobotGeometry))
    every = RobotGeometry(geom.model, geom.model.params.names, initial=problem.value(state, geom))
    blocks = [every if b is geom else b for b in problem.parameter_blocks]
    probe = Problem(blocks, [_rebind(rb, geom, every) for rb in problem.residual_blocks if rb.kind != "prior"],
                    n_poses=problem.n_poses)
    pstate = tuple(every.initial if b is every else v for b, v in zip(blocks, state))
    r, J, _ = probe.evaluate(pstate)
    s = np.where(np.array(probe.units) == "mm", probe.variable_values(pstate), 0.0)
    Js = J @ s
    mismatch = float(np.linalg.norm(Js + r) / max(np.linalg.norm(Js), 1e-300))
    return {"identifiable": bool(mismatch > tol), "mismatch": mismatch}


def _rebind(rb, old, new):
    """A shallow copy of residual block ``rb`` reading parameter block ``new`` instead of ``old``."""
    import copy

    out = copy.copy(rb)
    out.parameter_blocks = tuple(new if b is old else b for b in rb.parameter_blocks)
    chain = getattr(out, "chain", None)
    if chain is not None and chain.geometry is old:
        out.chain = copy.copy(chain)
        out.chain.geometry = new
    return out


def practically_unidentifiable(problem: Problem, state=None, *, max_std_mm: float = 1.0,
                               max_std_rad: float = 1e-3) -> list:
    """Geometry variables the data barely see: identifiable in exact arithmetic, but whose standard
    deviation would exceed ``max_std_mm`` / ``max_std_rad`` (e.g. a length along the beam, seen
    only through a mrad tilt of the mount). Greedy: the worst is removed and the rest re-analysed.
    Returns ``[{"name", "std", "unit", "why"}]`` (empty when the problem's sigmas are unknown)."""
    if not problem.sigma_known:
        return []
    state = problem.initial_state() if state is None else state
    _, J, _ = problem.evaluate(state)
    names, units = list(problem.names), np.array(problem.units)
    geom = np.array(problem.blocks) == "geometry"
    ident = analyse_identifiability(J, names, problem.blocks, explain=False)
    active = [names.index(n) for n in ident.identifiable]
    out = []
    while active:
        Ja = J[:, active]
        norms = np.linalg.norm(Ja, axis=0)
        cov = np.linalg.pinv((Ja / norms).T @ (Ja / norms)) / np.outer(norms, norms)
        std = np.sqrt(np.maximum(np.diag(cov), 0.0))
        limit = np.where(units[active] == "mm", max_std_mm, max_std_rad)
        ratio = np.where(geom[active], std / limit, 0.0)
        k = int(np.argmax(ratio))
        if ratio[k] <= 1.0:
            break
        i = active.pop(k)
        unit = units[i]
        Jk = J[:, active] / np.linalg.norm(J[:, active], axis=0)
        coef = np.linalg.lstsq(Jk, J[:, i] / np.linalg.norm(J[:, i]), rcond=None)[0]
        partners = [(names[active[b]], float(coef[b])) for b in np.argsort(-np.abs(coef))[:3] if abs(coef[b]) > 0.05]
        out.append({"name": names[i], "std": float(std[k]), "unit": str(unit), "trades_off_with": partners,
                    "why": f"barely observable: its standard deviation would be {std[k]:.3g} {unit} from these "
                           f"held spots (limit {limit[k]:g} {unit}); held at its initial value"})
    return out


def classify_unidentified(entries, spot_names, mount_names) -> dict:
    """Sort held / dropped geometry entries (dicts with ``name``, ``why``, ``trades_off_with``) by
    cause: ``"base_frame"`` (they move the arm as a common motion of the spots does: rotation about
    or shift along the first axis), ``"laser_mount"`` (the mount's four parameters absorb them: the
    last link and the mount cannot be told apart), ``"along_beam"`` (no effect at all: they move
    the beam along itself or turn it about itself), ``"other"`` (trade-offs among robot parameters)."""
    spot_names, mount_names = set(spot_names), set(mount_names)
    out = {"base_frame": [], "laser_mount": [], "along_beam": [], "other": []}
    for d in entries:
        partners = [n for n, _ in d.get("trades_off_with", [])]
        if not partners:
            out["along_beam"].append(d["name"])
        elif all(n in spot_names for n in partners):
            out["base_frame"].append(d["name"])
        elif any(n in mount_names for n in partners):
            out["laser_mount"].append(d["name"])
        else:
            out["other"].append(d["name"])
    return out


def e_op(errors) -> float:
    """The paper's spread measure E_OP (eq. 6): the mean in-plate error |E_i| [mm] over the held spots."""
    e = np.asarray(errors, dtype=float)
    return float(np.mean(e)) if e.size else float("nan")
