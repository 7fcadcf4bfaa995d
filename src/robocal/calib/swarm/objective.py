"""Objective (7) of the IPSO paper, evaluated for a whole swarm from the problem's own residuals.

``f = (1/N) sum_j (||dp_j||^2 + k ||d delta_j||^2)`` over the problem's N poses (METHODS.md,
IPSO), where ``dp_j`` are the position residuals of pose j (all its target points) [mm] and
``d delta_j`` its orientation residual ``log(R_measured R_predicted^T)`` [rad]. In terms of the
problem's weighted residuals ``r`` (:meth:`Problem.evaluate`):

    f = s^2 ||r||^2 / N,   k = rotation_weight^2 [mm^2 / rad^2],

with ``s`` the problem's common measurement sigma (``Problem.residual_scale``, 1 when the blocks
have different or no sigmas) and ``rotation_weight`` the rotation blocks' mm per rad; f is then
in mm^2. Prior rows (a Gaussian prior on the robot geometry) add their squared weighted errors
times ``s^2``. :func:`objective_at` computes f from ``Problem.evaluate`` for one state; the
:class:`SwarmObjective` computes the same numbers for P states at once, which the tests compare:
the point and rotation residuals of each end effector and configuration set are summed inside one
compiled call (:meth:`ParameterBatchFK.squared_residuals`: f (P,) directly, no frame stored) when
the base frames are not searched; otherwise through the batched frames and numpy.

Supported residual blocks: point and tool-point positions, rotation and tool-rotation residuals,
priors on the robot geometry; parameter blocks searched: robot geometry, vector blocks (target
points) and frame blocks (base, tool). Anything else raises :class:`SwarmInputError`.
"""

from __future__ import annotations

import numpy as np

from ...kinematics.batch import ParameterBatchFK
from ...transforms import so3_exp
from ..blocks import FramesBlock, RobotGeometry, VectorBlock
from ..residuals import PointResidual, RotationResidual, ToolPointResidual, ToolRotationResidual
from ..residuals.prior import PriorResidual
from .pso import SwarmInputError

__all__ = ["SwarmObjective", "objective_at"]


def objective_at(problem, state) -> float:
    """Objective (7) at one state from ``problem.evaluate``: ``s^2 ||r||^2 / N`` [mm^2]."""
    r, _, _ = problem.evaluate(state, jacobian=False)
    return float(problem.residual_scale**2 * (r @ r) / max(problem.n_poses, 1))


def _rotation_sq(R_meas, R_pred):
    """Squared rotation angle of ``R_meas R_pred^T`` (...,): ``theta = 2 asin(||R_meas - R_pred||_F / sqrt 8)``
    (the chordal form, accurate for small angles)."""
    d2 = np.sum((R_meas - R_pred) ** 2, axis=(-2, -1))
    th = 2.0 * np.arcsin(np.minimum(np.sqrt(d2 / 8.0), 1.0))
    return th * th


class SwarmObjective:
    """Objective (7) for P states at once: ``f(X)`` with X (P, n) steps of the variables ``names``
    (a subset of ``problem.names``, in the problem's tangent coordinates [mm | rad]) from ``state0``.

    problem: a :class:`~robocal.calib.core.Problem`; state0: the state the steps start from
    (default the problem's initial state); names: the searched variables (default all).
    """

    def __init__(self, problem, state0=None, names=None):
        self.problem = problem
        self.state0 = problem.initial_state() if state0 is None else state0
        names = list(problem.names) if names is None else list(names)
        index = {n: i for i, n in enumerate(problem.names)}
        unknown = [n for n in names if n not in index]
        if unknown:
            raise SwarmInputError(f"search variables not in the problem: {', '.join(unknown)}")
        self.names = tuple(names)
        self.columns = np.array([index[n] for n in names], dtype=int)
        self._block_columns = self._map_columns()
        self._fk = {}
        for rb in problem.residual_blocks:
            self._check_supported(rb)
        self._groups, self._rest = self._plan_fused()
        self.scale2 = problem.residual_scale**2 / max(problem.n_poses, 1)

    # ------------------------------------------------------------------ set-up
    def _map_columns(self):
        """{block: (positions in the search vector, positions in the block's variables)}."""
        out = {}
        owners = self.problem.column_blocks
        for blk in self.problem.parameter_blocks:
            var_pos = np.flatnonzero(blk.free)  # block variables behind the block's problem columns
            cols = np.flatnonzero(owners == blk.name)
            sel = [(k, var_pos[list(cols).index(c)]) for k, c in enumerate(self.columns) if c in set(cols)]
            if not sel:
                continue
            if not isinstance(blk, (RobotGeometry, VectorBlock, FramesBlock)):
                raise SwarmInputError(f"the swarm cannot search block {blk.name!r} ({type(blk).__name__}); "
                                      "fix its variables or use LM")
            k, j = zip(*sel)
            out[blk] = (np.array(k, dtype=int), np.array(j, dtype=int))
        return out

    def _check_supported(self, rb):
        if isinstance(rb, PriorResidual):
            if not isinstance(rb.block, (RobotGeometry, VectorBlock)):
                raise SwarmInputError(f"the swarm supports priors on geometry and vector blocks, not on {rb.block.name!r}")
            return
        if not isinstance(rb, (PointResidual, RotationResidual, ToolPointResidual, ToolRotationResidual)):
            raise SwarmInputError(f"the swarm cannot evaluate {type(rb).__name__} residuals (kind {rb.kind!r}); "
                                  "supported: point, rotation, tool point, tool rotation, geometry prior")

    def _plan_fused(self):
        """([group], [residual blocks left to numpy]): blocks sharing model, joints, end effector,
        geometry, base frames and stations form one group, evaluated in one compiled call."""
        groups, rest = {}, []
        for rb in self.problem.residual_blocks:
            if isinstance(rb, PriorResidual):
                rest.append(rb)
                continue
            if isinstance(rb, (PointResidual, ToolPointResidual, ToolRotationResidual)):
                c = rb.chain
                src = (c.model, c.q, c.geometry, c.frames, c.stations)
            else:
                src = (rb.model, rb.q, rb.geometry, rb.frames, rb.stations)
            if src[3] in self._block_columns:  # searched base frames: the numpy path
                rest.append(rb)
                continue
            ees = np.unique(rb.chain.ee_of_target) if isinstance(rb, PointResidual) else \
                [rb.chain.ee_of_target[0] if hasattr(rb, "chain") else rb.ee]
            for e in ees:
                key = (id(src[0]), id(src[1]), int(e), src[2], src[3], id(src[4]))
                g = groups.get(key)
                if g is None:
                    B = np.asarray(self.state0[self.problem.parameter_blocks.index(src[3])])[src[4]]
                    g = groups[key] = dict(model=src[0], q=src[1], ee=int(e), geometry=src[2],
                                           base=np.ascontiguousarray(B[:, :3, :]), points=[], rotations=[])
                self._add_terms(g, rb, e)
        out = []
        for g in groups.values():
            pts, rots = g.pop("points"), g.pop("rotations")
            N = len(g["base"])
            g["p_src"] = [p[0] for p in pts]
            g["p_meas"] = np.ascontiguousarray(np.concatenate([p[1] for p in pts], axis=1) if pts else np.zeros((N, 0, 3)))
            g["p_mask"] = np.ascontiguousarray(np.concatenate([p[2] for p in pts], axis=1) if pts
                                               else np.zeros((N, 0), dtype=bool))
            g["p_w2"] = np.array([w for p in pts for w in p[3]], dtype=float)
            g["r_src"] = [r[0] for r in rots]
            g["r_meas"] = np.ascontiguousarray(np.stack([r[1] for r in rots], axis=1) if rots else np.zeros((N, 0, 3, 3)))
            g["r_w2"] = np.array([r[2] for r in rots], dtype=float)
            g["static"] = not any(s[0] in self._block_columns for s in g["p_src"] + g["r_src"] if s[0] is not None)
            g["cache"] = {}
            out.append(g)
        return out, rest

    @staticmethod
    def _add_terms(g, rb, e):
        """Point terms (source, measured (N, K, 3), mask (N, K), squared weights (K,)) and rotation
        terms (source, measured (N, 3, 3), squared weight) of block ``rb`` at end effector ``e``."""
        if isinstance(rb, PointResidual):
            ks = np.flatnonzero(rb.chain.ee_of_target == e)
            g["points"].append(((rb.chain.targets, ks), rb.measured[:, ks], rb.mask[:, ks], [rb.weight**2] * len(ks)))
        elif isinstance(rb, ToolPointResidual):
            g["points"].append(((rb.tool, None), rb.measured[:, None], rb.mask[:, None], [rb.weight**2]))
        elif isinstance(rb, ToolRotationResidual):
            g["rotations"].append(((rb.tool, None), rb.measured, (rb.weight * rb.rotation_weight) ** 2))
        else:
            g["rotations"].append(((None, None), rb.measured, (rb.weight * rb.rotation_weight) ** 2))

    def _group_inputs(self, g, vals, P):
        """Per-particle targets (P, K, 3) and right rotation factors (P, M, 3, 3) of one group."""
        if g["static"] and P in g["cache"]:
            return g["cache"][P]
        tg = [vals[b][:, ks] if ks is not None else vals[b][:, 0, None, :3, 3] for b, ks in g["p_src"]]
        rr = [np.broadcast_to(np.eye(3), (P, 1, 3, 3)) if b is None else vals[b][:, 0, None, :3, :3]
              for b, _ in g["r_src"]]
        out = (np.ascontiguousarray(np.concatenate(tg, axis=1) if tg else np.zeros((P, 0, 3))),
               np.ascontiguousarray(np.concatenate(rr, axis=1) if rr else np.zeros((P, 0, 3, 3))))
        if g["static"]:
            g["cache"][P] = out
        return out

    def _fk_of(self, model, q, ee):
        key = (id(model), id(q), int(ee))
        fk = self._fk.get(key)
        if fk is None:
            fk = self._fk[key] = ParameterBatchFK(model, q, int(ee))
        return fk

    def _frames(self, model, q, ee, params):
        """End-effector frames (P, N, 3, 4) in the robot base frame, one compiled call."""
        return self._fk_of(model, q, ee)(params)

    # ------------------------------------------------------------------ values
    def block_values(self, X) -> dict:
        """{parameter block: batched value (P, ...)} for steps X (P, n)."""
        P = len(X)
        vals = {}
        for i, blk in enumerate(self.problem.parameter_blocks):
            v0 = np.asarray(self.state0[i], dtype=float)
            m = self._block_columns.get(blk)
            if m is None:
                vals[blk] = np.broadcast_to(v0, (P,) + v0.shape)
                continue
            d = np.zeros((P, blk.size))
            d[:, m[1]] = X[:, m[0]]
            vals[blk] = self._retract(blk, v0, d)
        return vals

    @staticmethod
    def _retract(blk, v0, d):
        P = len(d)
        if isinstance(blk, RobotGeometry):
            out = np.repeat(v0[None], P, axis=0)
            out[:, blk.index] += d
            return out
        if isinstance(blk, FramesBlock):
            d = d.reshape(P, -1, 6)
            R = so3_exp(d[..., :3])  # (P, G, 3, 3): left perturbation [exp(w) | v] T0
            out = np.repeat(v0[None], P, axis=0)
            out[..., :3, :3] = R @ v0[:, :3, :3]
            out[..., :3, 3] = np.einsum("pgij,gj->pgi", R, v0[:, :3, 3]) + d[..., 3:]
            return out
        return v0[None] + d.reshape((P,) + v0.shape)

    # ------------------------------------------------------------------ objective
    def __call__(self, X) -> np.ndarray:
        """Objective (7) (P,) [mm^2] for steps X (P, n)."""
        X = np.atleast_2d(np.asarray(X, dtype=float))
        vals = self.block_values(X)
        self._call_cache = {}
        P = len(X)
        total = np.zeros(P)
        for g in self._groups:
            tg, rr = self._group_inputs(g, vals, P)
            self._fk_of(g["model"], g["q"], g["ee"]).squared_residuals(
                vals[g["geometry"]], g["base"], tg, g["p_meas"], g["p_mask"], g["p_w2"], rr, g["r_meas"], g["r_w2"],
                out=total)
        for rb in self._rest:
            total += self._squared(rb, vals)
        self._call_cache = {}
        return total * self.scale2

    def _squared(self, rb, vals):
        """Sum of squared weighted residuals of one block, per particle (P,)."""
        if isinstance(rb, PriorResidual):
            blk = rb.block
            v = vals[blk]
            local = v[:, blk.index] if isinstance(blk, RobotGeometry) else v.reshape(len(v), -1)
            mean = blk.prior.mean
            mean_local = mean[blk.index] if isinstance(blk, RobotGeometry) else np.ravel(mean)
            e = (mean_local - local)[:, rb.rows] * rb.row_weight
            return np.sum(e * e, axis=1)
        if isinstance(rb, PointResidual):
            return self._points_sq(rb, vals)
        if isinstance(rb, ToolPointResidual):
            return self._tool_point_sq(rb, vals)
        if isinstance(rb, ToolRotationResidual):
            return self._tool_rotation_sq(rb, vals)
        return self._rotation_sq(rb, vals)

    def _chain_frames(self, chain, vals, ee):
        """Instrument-frame rotation (P, N, 3, 3) and origin (P, N, 3) of end effector ``ee``,
        computed once per call for chains sharing model, joints, blocks and stations."""
        key = (id(chain.model), id(chain.q), int(ee), chain.geometry, chain.frames, id(chain.stations))
        hit = self._call_cache.get(key)
        if hit is None:
            hit = self._call_cache[key] = self._instrument_frames(chain, vals, ee)
        return hit

    def _instrument_frames(self, chain, vals, ee):
        F = self._frames(chain.model, chain.q, ee, vals[chain.geometry])
        R_be, o_be = F[..., :3], F[..., 3]
        if chain.frames not in self._block_columns:  # the base is not searched: one frame per pose
            B = np.asarray(self.state0[self.problem.parameter_blocks.index(chain.frames)])[chain.stations]
            if np.array_equal(B, np.broadcast_to(np.eye(4), B.shape)):
                return R_be, o_be
            return B[:, :3, :3] @ R_be, np.einsum("nij,pnj->pni", B[:, :3, :3], o_be) + B[:, :3, 3]
        B = vals[chain.frames][:, chain.stations]  # (P, N, 4, 4)
        return B[..., :3, :3] @ R_be, np.einsum("pnij,pnj->pni", B[..., :3, :3], o_be) + B[..., :3, 3]

    def _points_sq(self, rb, vals):
        chain = rb.chain
        t = vals[chain.targets]  # (P, K, 3)
        acc = 0.0
        for e in np.unique(chain.ee_of_target):
            R, o = self._chain_frames(chain, vals, e)
            ks = np.flatnonzero(chain.ee_of_target == e)
            pred = np.einsum("pnij,pkj->pnki", R, t[:, ks]) + o[:, :, None]
            diff = np.where(rb.mask[None, :, ks, None], rb.measured[None, :, ks] - pred, 0.0)
            acc = acc + np.sum(diff * diff, axis=(1, 2, 3))
        return acc * rb.weight**2

    def _tool_point_sq(self, rb, vals):
        chain = rb.chain
        R, o = self._chain_frames(chain, vals, chain.ee_of_target[0])
        origin = vals[rb.tool][:, 0, :3, 3]
        pred = (R @ origin[:, None, :, None])[..., 0] + o
        diff = np.where(rb.mask[None, :, None], rb.measured[None] - pred, 0.0)
        return np.sum(diff * diff, axis=(1, 2)) * rb.weight**2

    def _tool_rotation_sq(self, rb, vals):
        chain = rb.chain
        R_pred, _ = self._chain_frames(chain, vals, chain.ee_of_target[0])
        R_tool = vals[rb.tool][:, None, 0, :3, :3]
        if rb.tool in self._block_columns or not np.array_equal(R_tool[0, 0], np.eye(3)):
            R_pred = R_pred @ R_tool
        return np.sum(_rotation_sq(rb.measured[None], R_pred), axis=1) * (rb.weight * rb.rotation_weight) ** 2

    def _rotation_sq(self, rb, vals):
        F = self._frames(rb.model, rb.q, rb.ee, vals[rb.geometry])
        Rb = vals[rb.frames][:, rb.stations, :3, :3]
        R_pred = Rb @ F[..., :3]
        return np.sum(_rotation_sq(rb.measured[None], R_pred), axis=1) * (rb.weight * rb.rotation_weight) ** 2
