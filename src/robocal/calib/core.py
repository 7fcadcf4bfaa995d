"""A calibration problem built from blocks: parameter blocks + residual blocks.

:class:`Problem` lays out the columns (the free variables of each parameter block, in block order),
stacks the rows of every residual block (in order; prior rows of blocks with a prior last), and
gives the solvers (:mod:`robocal.calib.solve`), the identifiability analysis and the covariance
what they need from any list of blocks:

* ``initial_state()``, ``retract(state, step)`` -- a state is a tuple of block values in block
  order; a step (n_variables,) moves each block on its manifold;
* ``evaluate(state, jacobian)`` -- ``(r (M,), J (M, n), labels (M, 2))`` with ``r`` the weighted
  residuals (measured - predicted) and ``J`` the derivative of the prediction, so
  ``r(retract(x, dx)) ~ r - J dx``; ``labels`` = (pose index or -1, kind code) per row, the kind
  code indexing ``kinds`` (``row_label(i)`` gives the names);
* ``names``, ``units``, ``blocks`` (identifiability group per column), ``column_blocks``
  (parameter-block name per column), ``variable_values(state)`` (reported values).

Example: a tool point touching one fixed point from several flange poses::

    tool = VectorBlock("tcp", ["tcp.x", "tcp.y", "tcp.z"], ["mm"] * 3, np.zeros(3))
    spot = VectorBlock("P_ref", ["P_ref.x", "P_ref.y", "P_ref.z"], ["mm"] * 3, p0)
    problem = Problem([tool, spot], [FixedPointResidual(T_base_flange, tool, spot, sigma=0.05)])
    result = solve(problem)
"""

from __future__ import annotations

from collections import Counter

import numpy as np

from .errors import ProblemError
from .residuals.base import Evaluation
from .residuals.prior import PriorResidual

__all__ = ["Problem"]


class Problem:
    """Parameter blocks and residual blocks (see the module docstring).

    parameter_blocks: sequence of :class:`~robocal.calib.blocks.ParameterBlock` (unique names and
    variable names); residual_blocks: sequence of :class:`~robocal.calib.residuals.ResidualBlock`
    reading only those blocks; n_poses: number of poses for per-pose robust weights (default: the
    largest pose label + 1); kinds: order of the kind codes in ``labels`` (default: order of
    first appearance; kinds not listed are appended).

    ``damping``: how the Levenberg-Marquardt solve changes its damping between trials (class
    attribute, :mod:`robocal.calib._iterate`): ``"tenfold"`` (/10 after a taken step, x10 after a
    refused one) or ``"gain"`` (Nielsen's rule, from the ratio of the actual to the predicted cost
    reduction; for problems whose steps the linear model predicts poorly, e.g. the bilinear lumped
    elastic model of a large data set: set it on the instance, docs/elastic.md).
    """

    #: damping update of the LM solve: "tenfold" or "gain" (see the class docstring)
    damping = "tenfold"

    def __init__(self, parameter_blocks, residual_blocks, *, n_poses: int | None = None, kinds=None):
        self.parameter_blocks = tuple(parameter_blocks)
        self._index = {b: i for i, b in enumerate(self.parameter_blocks)}
        self._by_name = {b.name: b for b in self.parameter_blocks}
        if len(self._by_name) != len(self.parameter_blocks):
            raise ProblemError(f"parameter blocks: duplicate block names in {[b.name for b in self.parameter_blocks]}")
        priors = [PriorResidual(b) for b in self.parameter_blocks if b.prior is not None and b.n_free]
        self.residual_blocks = tuple(residual_blocks) + tuple(priors)
        for rb in self.residual_blocks:
            for b in rb.parameter_blocks:
                if b not in self._index:
                    raise ProblemError(f"{type(rb).__name__} reads the parameter block {b.name!r}, "
                                       "which is not in the problem")
        self._make_state = tuple
        self._build_columns()
        self._build_rows(n_poses, kinds)

    # ------------------------------------------------------------------ layout
    def _build_columns(self):
        names, units, groups, owners = [], [], [], []
        self._plan, self._retract_plan = {}, []
        c = 0
        for i, blk in enumerate(self.parameter_blocks):
            loc = np.flatnonzero(blk.free)
            if not len(loc):
                continue
            plan = (c, c + len(loc), None if len(loc) == blk.size else loc)
            self._plan[blk] = plan
            self._retract_plan.append((i, blk) + plan)
            names += [blk.names[j] for j in loc]
            units += [blk.units[j] for j in loc]
            groups += [blk.group] * len(loc)
            owners += [blk.name] * len(loc)
            c += len(loc)
        dup = sorted(n for n, k in Counter(names).items() if k > 1)
        if dup:
            raise ProblemError(f"variable names used twice: {', '.join(dup)}")
        self.names, self.units = tuple(names), tuple(units)
        self.blocks = np.array(groups, dtype=str)
        self.column_blocks = np.array(owners, dtype=str)
        self.n_variables = c
        self._wanted = frozenset(self._plan)

    def _build_rows(self, n_poses, kinds):
        kinds = list(kinds or [])
        for rb in self.residual_blocks:
            if rb.kind not in kinds:
                kinds.append(rb.kind)
        self.kinds = tuple(kinds)
        self._row_slices, poses, codes, r0 = [], [], [], 0
        for rb in self.residual_blocks:
            self._row_slices.append((r0, r0 + rb.n_rows))
            poses.append(rb.row_poses)
            codes.append(np.full(rb.n_rows, self.kinds.index(rb.kind)))
            r0 += rb.n_rows
        self.n_residuals = r0
        labels = np.stack([np.concatenate(poses or [np.zeros(0, int)]),
                           np.concatenate(codes or [np.zeros(0, int)])], axis=1).astype(int)
        labels.flags.writeable = False
        self.labels = labels
        needed = int(labels[:, 0].max(initial=-1)) + 1
        if n_poses is not None and n_poses < needed:
            raise ProblemError(f"n_poses = {n_poses}, but residual rows refer to pose {needed - 1}")
        self.n_poses = needed if n_poses is None else int(n_poses)

    def row_label(self, i: int) -> tuple:
        """(pose index or -1, kind name, residual block) of row ``i``."""
        for rb, (r0, r1) in zip(self.residual_blocks, self._row_slices):
            if r0 <= i < r1:
                return int(self.labels[i, 0]), rb.kind, rb
        raise IndexError(f"row {i} out of range 0..{self.n_residuals - 1}")

    def block(self, name):
        """The parameter block named ``name`` (or the block itself)."""
        if name in self._index:
            return name
        try:
            return self._by_name[name]
        except KeyError:
            raise ProblemError(f"no parameter block named {name!r}; blocks: {list(self._by_name)}") from None

    # ------------------------------------------------------------------ states
    def growing_scale_columns(self):
        """Columns (n,) bool whose scale follows their norm upward in a solve's first round, or None
        (:mod:`robocal.calib._iterate`, "Growing column scales"). None here; a lumped elastic
        :class:`~robocal.calib.problem.CalibrationProblem` names its compliance and gravity columns."""
        return None

    def initial_state(self):
        """Every block's initial value (copies), as the problem's state type."""
        return self._make_state([np.array(b.initial, dtype=float) for b in self.parameter_blocks])

    def initial_values(self) -> np.ndarray:
        """``variable_values(initial_state())``, cached while no block's initial value changes (a copy)."""
        inits = [b.initial for b in self.parameter_blocks]
        cached = getattr(self, "_initial_values_cache", None)
        if cached is not None and len(cached[0]) == len(inits) and all(
                np.array_equal(a, b) for a, b in zip(cached[0], inits)):
            return cached[1].copy()
        vals = self.variable_values(self.initial_state())
        self._initial_values_cache = ([np.array(b, dtype=float) for b in inits], vals.copy())
        return vals

    def value(self, state, block):
        """The value of ``block`` (object or name) in ``state``."""
        return state[self._index[self.block(block)]]

    def retract(self, state, step):
        """The state moved by ``step`` (n_variables,): each block with free variables retracts its
        part of the step (zeros for its fixed variables); other blocks keep their value."""
        step = np.asarray(step, dtype=float)
        out = list(state)
        for i, blk, c0, c1, loc in self._retract_plan:
            d = step[c0:c1]
            if loc is not None:
                full = np.zeros(blk.size)
                full[loc] = d
                d = full
            out[i] = blk.retract(state[i], d)
        return self._make_state(out)

    def variable_values(self, state, group: str | None = None) -> np.ndarray:
        """(n,) reported values of the free variables (``block.local``), in column order; only the
        columns of identifiability group ``group`` if given."""
        parts = []
        for i, blk, _c0, _c1, loc in self._retract_plan:
            if group is None or blk.group == group:
                v = blk.local(state[i])
                parts.append(v if loc is None else v[loc])
        return np.concatenate(parts) if parts else np.zeros(0)

    # ------------------------------------------------------------------ residuals
    def evaluate(self, state, jacobian: bool = True):
        """``(r, J, labels)`` at ``state``: weighted residuals (M,), the prediction Jacobian (M, n)
        (``None`` without ``jacobian``) and the row labels (M, 2)."""
        if not self.n_residuals:
            raise ProblemError("the problem has no measurements")
        ev = Evaluation(dict(zip(self.parameter_blocks, state)), jacobian, self._wanted)
        r = np.empty(self.n_residuals)
        J = np.zeros((self.n_residuals, self.n_variables)) if jacobian else None
        plan = self._plan
        for rb, (r0, r1) in zip(self.residual_blocks, self._row_slices):
            rr, jac = rb.evaluate(ev, jacobian)
            r[r0:r1] = rr
            if jacobian:
                for blk, Jb in jac.items():
                    p = plan.get(blk)
                    if p is not None:
                        J[r0:r1, p[0]:p[1]] = Jb if p[2] is None else Jb[:, p[2]]
        return r, J, self.labels

    def scatter_columns(self, jac: dict, shape) -> np.ndarray:
        """Per-block Jacobians ``{block: (*shape, size)}`` as one array (*shape, n_variables)."""
        J = np.zeros(tuple(shape) + (self.n_variables,))
        for blk, Jb in jac.items():
            p = self._plan.get(blk)
            if p is not None:
                J[..., p[0]:p[1]] = Jb if p[2] is None else Jb[..., p[2]]
        return J

    def point_errors(self, r):
        """Distances [mm] of every measured point (residual blocks of kind ``"point"``) from the
        weighted residuals ``r`` (M,); ``None`` if the problem has no point measurements."""
        parts = [rb.errors(r[r0:r1]) for rb, (r0, r1) in zip(self.residual_blocks, self._row_slices)
                 if rb.kind == "point"]
        return np.concatenate(parts) if parts else None

    @property
    def _measurement_sigmas(self) -> list:
        return [rb.sigma for rb in self.residual_blocks if not isinstance(rb, PriorResidual)]

    @property
    def sigma_known(self) -> bool:
        """Every measurement block states its sigma: the covariance is absolute (not rescaled)."""
        s = self._measurement_sigmas
        return bool(s) and all(x is not None for x in s)

    @property
    def residual_scale(self) -> float:
        """Measurement units per weighted residual unit (the common sigma, else 1)."""
        s = set(self._measurement_sigmas)
        return next(iter(s)) if len(s) == 1 and None not in s else 1.0

    # ------------------------------------------------------------------ robot model
    def model_at(self, state):
        """The robot model of the first :class:`~robocal.calib.blocks.RobotGeometry` block with the
        state's parameters, its base the first frame of the first ``"base"`` block (if any)."""
        from .blocks.robot import RobotGeometry

        geom = next((b for b in self.parameter_blocks if isinstance(b, RobotGeometry)), None)
        if geom is None:
            raise ProblemError("the problem has no robot geometry block")
        model = geom.model.with_params(self.value(state, geom))
        frames = next((b for b in self.parameter_blocks if b.group == "base"), None)
        return model if frames is None else model.replace(T_world_base=self.value(state, frames)[0])
