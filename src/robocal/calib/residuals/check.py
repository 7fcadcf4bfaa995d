"""Finite-difference check of a residual block's analytic Jacobian, through each block's retraction."""

from __future__ import annotations

import numpy as np

from .base import Evaluation, ResidualBlock

__all__ = ["jacobian_errors", "perturbed_values"]


def perturbed_values(residual: ResidualBlock, rng=None, scale: float = 1e-3) -> dict:
    """The initial values of the residual's parameter blocks, each moved by a random tangent step
    of ~``scale`` (so the check does not sit on a special point such as a zero rotation)."""
    values = {}
    for blk in residual.parameter_blocks:
        v = np.array(blk.initial, dtype=float)
        if rng is not None and blk.size:
            v = blk.retract(v, rng.normal(0.0, scale, blk.size))
        values[blk] = v
    return values


def jacobian_errors(residual: ResidualBlock, values=None, *, h: float = 1e-6) -> dict:
    """Largest difference per parameter block between the analytic Jacobian and central differences.

    Each variable ``i`` of each block ``b`` is moved by ``b.retract(value, +-h e_i)``; the
    difference ``-(r+ - r-) / 2h`` (the prediction derivative) is compared with the block's
    column ``i``: ``max |fd - J|`` relative to the largest derivative of the residual over all its
    blocks (at least 1), so a block the rows barely depend on (a base frame under distances) is
    judged on the scale of the rows, not on its own near-zero columns where differences are
    rounding noise. ``values``: {block: value}, default the blocks' initial values. Also checks the shapes of ``r`` and of every Jacobian and raises
    ``AssertionError`` naming the block if one is wrong.
    """
    values = perturbed_values(residual) if values is None else dict(values)
    name = type(residual).__name__
    r, jac = residual.evaluate(Evaluation(values, True), True)
    if r.shape != (residual.n_rows,):
        raise AssertionError(f"{name}: residuals have shape {r.shape}, expected ({residual.n_rows},)")
    unknown = [b for b in jac if b not in values]
    if unknown:
        raise AssertionError(f"{name}: Jacobian for a block it does not read: {unknown[0]!r}")
    diffs, scale = {}, 1.0
    for blk in residual.parameter_blocks:
        Ja = jac.get(blk, np.zeros((len(r), blk.size)))
        if Ja.shape != (len(r), blk.size):
            raise AssertionError(f"{name}: Jacobian for {blk.name!r} has shape {Ja.shape}, expected {(len(r), blk.size)}")
        fd = _central_differences(residual, values, blk, h)
        diffs[blk.name] = float(np.max(np.abs(fd - Ja), initial=0.0))
        scale = max(scale, float(np.max(np.abs(fd), initial=0.0)), float(np.max(np.abs(Ja), initial=0.0)))
    return {b: d / scale for b, d in diffs.items()}


def _central_differences(residual, values, blk, h):
    """-(r(retract(+h e_i)) - r(retract(-h e_i))) / 2h for every variable i of ``blk``: (m, size)."""
    fd = np.empty((residual.n_rows, blk.size))
    for i in range(blk.size):
        d = np.zeros(blk.size)
        d[i] = h
        rp = residual.evaluate(Evaluation({**values, blk: blk.retract(values[blk], d)}, False), False)[0]
        rm = residual.evaluate(Evaluation({**values, blk: blk.retract(values[blk], -d)}, False), False)[0]
        fd[:, i] = -(rp - rm) / (2.0 * h)
    return fd
