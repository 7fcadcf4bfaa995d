"""The parameter-block protocol: a named group of unknowns on a manifold.

A calibration problem (METHODS.md section 3; DESIGN.md "One idea underneath everything") is a list
of parameter blocks and a list of residual blocks. A parameter block owns

``name``
    unique within a problem (``"geometry"``, ``"base"``, ``"targets"``, ``"tool"``, ...);
``group``
    the identifiability class of its columns (``"geometry"``, ``"base"``, ``"targets"``,
    ``"planes"`` or a new name; :data:`robocal.calib.identifiability.DEFAULT_PRIORITY` ranks them);
``names``, ``units``
    one per variable (tangent coordinate), e.g. ``base.rx`` [rad], ``r1.x`` [mm];
``initial``
    the starting value in the block's own representation ((P,) vector, (G, 4, 4) frames, ...);
``retract(value, delta)``
    the value moved by a tangent step ``delta`` (size,) -- the manifold's retraction;
``local(value)``
    (size,) coordinates of a value for reports (a frame: rotation vector and origin);
``free``
    (size,) bool, which variables are estimated (the others keep their value);
``prior``
    an optional :class:`GaussianPrior`; the problem then adds its prior residual rows;
``prior_error(value, mean)``
    ``(e, D)``: the prior error ``e`` (size,) "mean minus value" in local coordinates and
    ``D = -de/d(delta)`` (size, size), the derivative convention of residual blocks.

Values are never modified in place: ``retract`` returns a new array.
"""

from __future__ import annotations

import difflib
from dataclasses import dataclass

import numpy as np

from ..errors import ProblemError

__all__ = ["ParameterBlock", "GaussianPrior", "free_mask"]


@dataclass(frozen=True)
class GaussianPrior:
    """A Gaussian prior on a parameter block: ``sigma`` (scalar or (size,)) in the units of the
    block's variables; ``mean`` in the block's value representation (default: its initial value).
    Adds one residual row per free variable, ``e / sigma`` (see ``ParameterBlock.prior_error``)."""

    sigma: object
    mean: object = None


def free_mask(free, names, block: str) -> np.ndarray:
    """(size,) bool from ``True`` / ``False``, a (size,) bool sequence or an iterable of variable names."""
    n = len(names)
    if isinstance(free, (bool, np.bool_)):
        return np.full(n, bool(free))
    if isinstance(free, np.ndarray) and free.dtype == bool:
        if free.shape != (n,):
            raise ProblemError(f"{block}: free mask has shape {free.shape}, expected ({n},)")
        return free.copy()
    items = list(free)
    if items and all(isinstance(x, (bool, np.bool_)) for x in items):
        if len(items) != n:
            raise ProblemError(f"{block}: free mask has {len(items)} entries, expected {n}")
        return np.array(items, dtype=bool)
    mask = np.zeros(n, dtype=bool)
    index = {nm: i for i, nm in enumerate(names)}
    for nm in items:
        if nm not in index:
            near = difflib.get_close_matches(str(nm), names, n=1)
            hint = f"; did you mean {near[0]!r}?" if near else ""
            raise ProblemError(f"{block}: no variable named {nm!r}{hint}")
        mask[index[nm]] = True
    return mask


class ParameterBlock:
    """Base class of parameter blocks (see the module docstring for the protocol).

    Subclasses implement :meth:`retract`, :meth:`local` and :meth:`prior_error`.
    """

    group: str = "other"

    def __init__(self, name: str, names, units, initial, *, free=True, prior: GaussianPrior | None = None,
                 group: str | None = None):
        self.name = str(name)
        if group is not None:
            self.group = str(group)
        self.names = tuple(str(n) for n in names)
        self.units = tuple(str(u) for u in units)
        if len(self.units) != len(self.names):
            raise ProblemError(f"{self.name}: {len(self.names)} variable names but {len(self.units)} units")
        self.size = len(self.names)
        initial = np.array(initial, dtype=float)
        if not np.all(np.isfinite(initial)):
            raise ProblemError(f"{self.name}: the initial value contains NaN or infinite numbers")
        initial.flags.writeable = False
        self.initial = initial
        self.free = free_mask(free, self.names, self.name)
        self.prior = None
        if prior is not None:
            self.prior = self._checked_prior(prior)

    def _checked_prior(self, prior: GaussianPrior) -> GaussianPrior:
        sigma = np.broadcast_to(np.asarray(prior.sigma, dtype=float), (self.size,)).copy()
        if not np.all(sigma > 0):
            raise ProblemError(f"{self.name}: prior sigma must be positive, got {prior.sigma!r}")
        mean = self.initial if prior.mean is None else np.asarray(prior.mean, dtype=float)
        if mean.shape != self.initial.shape:
            raise ProblemError(f"{self.name}: prior mean has shape {mean.shape}, expected {self.initial.shape}")
        return GaussianPrior(sigma=sigma, mean=mean)

    @property
    def n_free(self) -> int:
        return int(self.free.sum())

    def with_free(self, free) -> "ParameterBlock":
        """A copy of the block with another free mask (``free`` as in the constructor)."""
        import copy

        out = copy.copy(self)
        out.free = free_mask(free, self.names, self.name)
        return out

    # ------------------------------------------------------------------ the manifold
    def retract(self, value, delta):
        """The value moved by the tangent step ``delta`` (size,)."""
        raise NotImplementedError

    def local(self, value) -> np.ndarray:
        """(size,) coordinates of ``value`` for reports."""
        raise NotImplementedError

    def prior_error(self, value, mean):
        """``(e (size,), D (size, size))``: ``e`` = mean minus value in local coordinates,
        ``D = -de/d(delta)``."""
        raise NotImplementedError

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self.name!r}, {self.size} variables, {self.n_free} free)"
