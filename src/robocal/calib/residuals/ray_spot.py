"""A laser ray through a fixed spot: the virtual closed kinematic chain (METHODS.md section 3).

A laser pointer on the flange (mount: :class:`~robocal.calib.blocks.LaserMount`, eq. 3) shines on
a plate; the joints are adjusted until the spot sits on a marked target ``P``, and the joints are
read. Each such *held spot* closes the chain: the ray predicted from the joints must pass through
``P``. The measurement is the in-plate error of eq. 5, ``E = S - P``, where ``S`` is the ray's
intersection with the plate plane through ``P`` (normal ``n``); its two in-plane components are
the residual rows, and ``E_OP = mean |E|`` (eq. 6) is the paper's spread measure.

With the ray origin ``A``, a second beam point ``B = A + L u`` (``u`` the unit beam direction),
``lambda = n.(P - A) / n.u`` and ``S = A + lambda u``, the prediction ``f = E_2x3 (S - P)`` has the
derivative ``df = E M ((1 - lambda/L) dA + (lambda/L) dB - dP)`` with ``M = I - u n^T / (n.u)``
(the projection along the beam onto the plate): the beam points' derivatives come from the shared
robot chain (:class:`~robocal.calib.residuals.TargetChain`, the identification Jacobian (3-6)).
"""

from __future__ import annotations

import numpy as np

from ..blocks import StationFrames, TargetPoints
from ..blocks.manifolds import tangent_basis
from ..errors import ProblemError
from .base import ResidualBlock
from .chain import TargetChain

__all__ = ["RaySpotResidual", "laser_chain", "BEAM_LENGTH_MM"]

#: distance of the second beam point from the ray origin [mm] (any length; it only sets the
#: finite-difference scale of the beam direction)
BEAM_LENGTH_MM = 500.0


def laser_chain(model, q, geometry, *, frames=None, end_effector=None) -> TargetChain:
    """The robot chain carrying the two beam points at joints ``q`` (H, n_ctrl): a
    :class:`TargetChain` whose (fixed) target block only names the points and their end
    effector; the residual supplies their values from the laser mount. ``frames``: the base frame
    block (default: the robot base is the reference frame, fixed)."""
    frames = StationFrames(np.eye(4), free=False) if frames is None else frames
    beam = TargetPoints(["beam.origin", "beam.far"], np.zeros((2, 3)), name="beam",
                        end_effectors=[end_effector, end_effector], free=False)
    return TargetChain(model, q, geometry, frames, beam)


class RaySpotResidual(ResidualBlock):
    """Two rows per held spot: the in-plate components of ``E = S - P`` (eq. 5), weighted 1/sigma.

    chain: :func:`laser_chain` (one row of joints per held spot); laser: a
    :class:`~robocal.calib.blocks.LaserMount`; spots: a 3*S-variable block of the fixed spots'
    positions (S, 3) [mm] in the robot base frame; spot_of_row (H,): the spot each held spot was
    held on; normals (S, 3): the plate normal at each spot (sets the plane the error is measured
    in); sigma [mm]: per in-plane component (the detection tolerance's spread).
    """

    kind = "ray_spot"

    def __init__(self, chain: TargetChain, laser, spots, spot_of_row, normals, sigma: float | None = None):
        self.spot_of_row = np.asarray(spot_of_row, dtype=int).reshape(-1)
        H = len(self.spot_of_row)
        if len(chain.q) != H:
            raise ProblemError(f"ray_spot: {len(chain.q)} joint rows for {H} held spots")
        S = spots.size // 3
        if H and (self.spot_of_row.min() < 0 or self.spot_of_row.max() >= S):
            raise ProblemError(f"ray_spot: spot index out of range 0..{S - 1}")
        self.set_normals(normals, S)
        self.chain, self.laser, self.spots = chain, laser, spots
        blocks = (chain.geometry, chain.frames, laser, spots)
        super().__init__(blocks, np.repeat(np.arange(H), 2), sigma)

    def set_normals(self, normals, n_spots: int | None = None) -> None:
        """The plate normal (S, 3) at every spot (normalised here) and the in-plate axes."""
        n = np.asarray(normals, dtype=float).reshape(-1 if n_spots is None else n_spots, 3)
        self.normals = n / np.linalg.norm(n, axis=1, keepdims=True)
        east, north = tangent_basis(self.normals)
        self.basis = np.stack([east, north], axis=1)  # (S, 2, 3): the in-plate axes

    # ------------------------------------------------------------------ geometry
    def beam(self, ev):
        """Beam points (H, 2, 3) [mm] in the reference frame and their Jacobians per block."""
        return ev.shared((self.chain, self.laser, "beam"), self._beam)

    def _beam(self, ev):
        pts_f, dpts_f = self.laser.beam_points(ev[self.laser], BEAM_LENGTH_MM)
        ch = self.chain
        wants = None
        if ev.jacobian:
            wants = (ev.wants(ch.geometry), ev.wants(ch.frames), ev.wants(self.laser))
        out = ch.predict(ev[ch.geometry], ev[ch.frames], pts_f, ch.q, ch.stations, wants)
        jac = {b: J for b, J in out.jac.items() if b is not ch.targets}
        if wants is not None and wants[2]:
            Jt = out.jac[ch.targets]  # (H, 2, 3, 6): R_ref_flange per beam point
            R = np.stack([Jt[:, 0, :, 0:3], Jt[:, 1, :, 3:6]], axis=1)  # (H, 2, 3, 3)
            jac[self.laser] = np.einsum("hkij,kjc->hkic", R, dpts_f)
        return out.points, jac

    def intersections(self, ev):
        """``(S_pts (H, 3), P (H, 3), lambda (H,), u (H, 3))``: each ray's intersection with its
        plate plane, the spot, the distance along the beam, the beam direction."""
        pts, _ = self.beam(ev)
        A, B = pts[:, 0], pts[:, 1]
        u = (B - A) / BEAM_LENGTH_MM
        P = np.asarray(ev[self.spots], dtype=float).reshape(-1, 3)[self.spot_of_row]
        n = self.normals[self.spot_of_row]
        denom = np.einsum("hi,hi->h", n, u)
        if np.any(np.abs(denom) < 1e-3):
            h = int(np.argmin(np.abs(denom)))
            raise ProblemError(f"ray_spot: held spot {h}: the beam runs along the plate (angle to the plate "
                               f"{np.degrees(np.arcsin(min(1.0, abs(denom[h])))):.3f} deg)")
        lam = np.einsum("hi,hi->h", n, P - A) / denom
        return A + lam[:, None] * u, P, lam, u

    # ------------------------------------------------------------------ residual
    def evaluate(self, ev, jacobian):
        S_pts, P, lam, u = self.intersections(ev)
        E = self.basis[self.spot_of_row]  # (H, 2, 3)
        w = self.weight
        r = -np.einsum("hci,hi->hc", E, S_pts - P).ravel() * w
        if not jacobian:
            return r, None
        _, jac_pts = self.beam(ev)
        n = self.normals[self.spot_of_row]
        M = np.eye(3) - np.einsum("hi,hj->hij", u, n) / np.einsum("hi,hi->h", n, u)[:, None, None]
        G = np.einsum("hci,hij->hcj", E, M) * w  # (H, 2, 3)
        t = lam / BEAM_LENGTH_MM
        H = len(t)
        jac = {}
        for blk, Jb in jac_pts.items():  # (H, 2, 3, c): beam origin and far point
            dS = (1.0 - t)[:, None, None] * Jb[:, 0] + t[:, None, None] * Jb[:, 1]
            jac[blk] = np.einsum("hci,hik->hck", G, dS).reshape(2 * H, -1)
        if ev.wants(self.spots):
            Js = np.zeros((H, 2, self.spots.size))
            cols = 3 * self.spot_of_row[:, None] + np.arange(3)
            Js[np.arange(H)[:, None, None], np.arange(2)[None, :, None], cols[:, None, :]] = -G
            jac[self.spots] = Js.reshape(2 * H, -1)
        return r, jac

    def errors(self, r) -> np.ndarray:
        """|E_i| [mm] per held spot (eq. 5) from this block's weighted rows."""
        return np.linalg.norm((np.asarray(r) * (self.sigma or 1.0)).reshape(-1, 2), axis=1)

    @classmethod
    def example(cls, rng):
        from ..blocks import LaserMount, RobotGeometry, VectorBlock
        from .examples import example_robot

        model = example_robot(rng)
        q = rng.uniform(-1.5, 1.5, (7, model.n_joints))
        geometry = RobotGeometry(model, model.params.names)
        frames = StationFrames(np.eye(4) + 0.0)
        chain = laser_chain(model, q, geometry, frames=frames)
        T0 = np.eye(4)
        T0[:3, 3] = rng.normal(0, 30, 3)
        laser = LaserMount(rng.normal(0, [0.01, 0.01, 1.0, 1.0]), T0=T0)
        spots = VectorBlock("spots", [f"s{k}.{c}" for k in range(3) for c in "xyz"], ["mm"] * 9,
                            rng.normal(0, 400, 9), group="targets")
        rows = np.arange(7) % 3
        res = cls(chain, laser, spots, rows, np.tile([0.0, 0.0, 1.0], (3, 1)), sigma=0.05)
        from .base import Evaluation

        pts, _ = res.beam(Evaluation({b: b.initial for b in res.parameter_blocks}, False))
        u = pts[:, 1] - pts[:, 0]
        # each plate faces the first beam held on it, tilted a little (the ray meets it steeply)
        res.set_normals(-u[:3] / BEAM_LENGTH_MM + rng.normal(0, 0.2, (3, 3)))
        return res
