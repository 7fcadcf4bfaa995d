"""The residual-block protocol, the evaluation context and the registry of residual kinds.

A residual block (one measurement kind over all its measurements) declares

``parameter_blocks``
    the parameter blocks it reads;
``kind``
    a short name for reports (``"point"``, ``"rotation"``, ...);
``row_poses``
    (m,) the pose index of each row (-1 for rows that belong to no pose, e.g. priors), fixed
    when the block is built; with ``kind`` it labels every row;
``sigma``
    the measurement standard deviation (rows are weighted ``1 / sigma``; ``None``: weight 1);
``evaluate(ev, jacobian)``
    ``(r, jac)``: the weighted residuals ``r`` (m,) = ``weight * (measured - predicted)`` for all
    measurements at once, and (with ``jacobian``) ``jac``: one array (m, block.size) per parameter
    block it reads, ``-dr/d(delta)`` w.r.t. the block's tangent step (the derivative of the
    *prediction*, so ``r(x + delta) ~ r - J delta``). Blocks that ``ev.wants`` nothing from may be
    left out. No per-measurement Python loops: the work is batched over measurements.
``example(rng)`` (class method)
    a small, seeded instance (or a list of them) whose parameter blocks carry their values in
    ``initial``: the finite-difference test (``tests/test_residual_blocks.py``) checks every
    registered class through it, so a block without one fails the suite.

Every subclass registers itself in :data:`RESIDUAL_BLOCKS` (``class X(ResidualBlock, register=False)``
opts out, for abstract helpers and deliberate test doubles).

Several blocks often need the same expensive prediction (the robot chain's target points): they
ask the :class:`Evaluation` for it through ``ev.shared(key, compute)``, which computes it once per
evaluation.
"""

from __future__ import annotations

import numpy as np

__all__ = ["ResidualBlock", "Evaluation", "RESIDUAL_BLOCKS"]

#: every registered residual-block class, by ``module.qualname``
RESIDUAL_BLOCKS: dict = {}


class Evaluation:
    """One evaluation of residual blocks: the parameter-block values, whether Jacobians are wanted
    (and for which blocks), and results shared between residual blocks.

    values: mapping parameter block -> value; jacobian: Jacobians wanted at all; wanted: the
    blocks with free variables (``None``: all).
    """

    __slots__ = ("_values", "jacobian", "_wanted", "_cache")

    def __init__(self, values, jacobian: bool, wanted=None):
        self._values = values
        self.jacobian = bool(jacobian)
        self._wanted = wanted
        self._cache = {}

    def __getitem__(self, block):
        return self._values[block]

    def wants(self, block) -> bool:
        """Is the Jacobian w.r.t. ``block`` needed in this evaluation?"""
        return self.jacobian and (self._wanted is None or block in self._wanted)

    def shared(self, key, compute):
        """``compute(self)``, computed once per evaluation for each ``key``."""
        try:
            return self._cache[key]
        except KeyError:
            out = self._cache[key] = compute(self)
            return out


class ResidualBlock:
    """Base class of residual blocks (see the module docstring for the protocol)."""

    kind: str = "residual"

    def __init_subclass__(cls, register: bool = True, **kwargs):
        super().__init_subclass__(**kwargs)
        if register:
            RESIDUAL_BLOCKS[f"{cls.__module__}.{cls.__qualname__}"] = cls

    def __init__(self, parameter_blocks, row_poses, sigma: float | None = None):
        self.parameter_blocks = tuple(parameter_blocks)
        self.row_poses = np.asarray(row_poses, dtype=int).reshape(-1)
        self.row_poses.flags.writeable = False
        if sigma is not None and not sigma > 0:
            raise ValueError(f"{type(self).__name__}: sigma must be positive, got {sigma!r}")
        self.sigma = None if sigma is None else float(sigma)
        self.weight = 1.0 if sigma is None else 1.0 / float(sigma)

    @property
    def n_rows(self) -> int:
        return len(self.row_poses)

    def evaluate(self, ev: Evaluation, jacobian: bool):
        """``(r (m,), {parameter block: (m, size)} or None)``; see the module docstring."""
        raise NotImplementedError

    def residuals(self, ev: Evaluation) -> np.ndarray:
        """The weighted residuals (m,) alone."""
        return self.evaluate(ev, False)[0]

    def jacobian(self, ev: Evaluation) -> dict:
        """``{parameter block: (m, size)}``, the derivative of the prediction."""
        return self.evaluate(ev, True)[1]

    def errors(self, r) -> np.ndarray | None:
        """Per-measurement errors in measurement units (e.g. point distances [mm]) from this
        block's weighted rows ``r``, for reports; ``None`` if the kind has no such figure."""
        return None

    @classmethod
    def example(cls, rng):
        """A small instance (or a list of them) built from ``rng`` (a numpy Generator)."""
        raise NotImplementedError(f"{cls.__module__}.{cls.__qualname__} has no example() factory")

    def __repr__(self) -> str:
        reads = ", ".join(b.name for b in self.parameter_blocks)
        return f"{type(self).__name__}({self.n_rows} rows, reads {reads})"
