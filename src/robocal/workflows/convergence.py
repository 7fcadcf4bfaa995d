"""One convergence policy for every command that fits something (issue 25).

A fit has converged when its solver met a stated criterion (the policy of
:mod:`robocal.calib._iterate`: relative cost change, chi-square change, step size, or a first-order
stationary point); an iteration cap reached, or "no step reduces the cost" away from a stationary
point, is NOT converged. A command gathers its fits in one :class:`Convergence`; when any did not
converge it writes no robot/camera/tool file unless the user passes ``--allow-unconverged``, marks
its JSON (``convergence``) and report, prints one ``Warning:`` line (:meth:`Convergence.warning`)
and exits 4 (``robocal.cli._common.finish_convergence``).
"""

from __future__ import annotations

import contextlib
import contextvars
from dataclasses import dataclass

__all__ = ["Convergence", "DEFAULT_HINT", "fit_reason", "record_fit", "recording_fits"]

_FITS = contextvars.ContextVar("robocal_recorded_fits", default=None)


@contextlib.contextmanager
def recording_fits():
    """Collect the solver results :func:`record_fit` sees inside the block (a list, yielded): a study
    or protocol counts how many of its fits did not converge and reports it next to its figures."""
    fits = []
    token = _FITS.set(fits)
    try:
        yield fits
    finally:
        _FITS.reset(token)


def record_fit(result):
    """Add a solver result to the innermost :func:`recording_fits` list (if any); returns ``result``."""
    log = _FITS.get()
    if log is not None:
        log.append(result)
    return result

#: What to try when a fit did not converge (commands with other knobs pass their own).
DEFAULT_HINT = "raise --max-iterations, start closer (better nominal or initial values) or free fewer parameters"


def fit_reason(result) -> str:
    """``"<reason> after <n> iterations, condition number <c>"`` of a solver result (``reason`` or
    ``message``; ``iterations`` and ``condition_number`` where it has them)."""
    reason = getattr(result, "reason", None) or getattr(result, "message", None) or "not converged"
    it = getattr(result, "iterations", None)
    text = f"{reason} after {it} iterations" if it is not None else str(reason)
    cond = getattr(result, "condition_number", None)
    return text + (f", condition number {cond:.3g}" if cond is not None else "")


@dataclass(frozen=True)
class Convergence:
    """Whether every fit of one command converged.

    Attributes
    ----------
    n_fits : int
        How many fits the command ran.
    not_converged : tuple of str
        One ``"<fit>: <reason>"`` per fit that did not converge (empty when all did).
    what_to_try : str
        The advice printed with the warning.
    iterations : tuple of int or None
        Each fit's solver iterations, in order (None where the fit has no count); empty when unknown.
    """

    n_fits: int
    not_converged: tuple = ()
    what_to_try: str = DEFAULT_HINT
    iterations: tuple = ()

    @classmethod
    def of(cls, fits, what_to_try: str = DEFAULT_HINT) -> Convergence:
        """From ``fits``: an iterable of ``(label, converged, reason)`` (or ``(label, result)`` with a
        solver result that has ``converged`` and ``reason``/``message``/``iterations``)."""
        fits = list(fits)
        bad, iterations = [], []
        for fit in fits:
            if len(fit) == 2:
                label, res = fit
                ok, reason = bool(res.converged), fit_reason(res)
                it = getattr(res, "iterations", None)
                iterations.append(None if it is None else int(it))
            else:
                label, ok, reason = fit
                iterations.append(None)
            if not ok:
                bad.append(f"{label}: {reason}" if label else str(reason))
        return cls(len(fits), tuple(bad), what_to_try, tuple(iterations))

    @property
    def converged(self) -> bool:
        return not self.not_converged

    @property
    def n_not_converged(self) -> int:
        return len(self.not_converged)

    def may_write_model(self, allow_unconverged: bool) -> bool:
        """Whether the command may write its robot/camera/tool file."""
        return self.converged or bool(allow_unconverged)

    def warning(self) -> str:
        """The one warning line (without the ``Warning:`` prefix): what did not converge and what to try."""
        what = "; ".join(self.not_converged[:3]) + (f"; and {self.n_not_converged - 3} more"
                                                    if self.n_not_converged > 3 else "")
        head = ("the fit did not converge" if self.n_fits <= 1
                else f"{self.n_not_converged} of {self.n_fits} fits did not converge")
        return f"{head} ({what}); try: {self.what_to_try} (or pass --allow-unconverged to accept the result)"

    def skipped_note(self, files: str) -> str:
        """A note for the output: which model file(s) were not written and why."""
        return f"{files} not written: the fit did NOT converge (pass --allow-unconverged to write anyway)"

    @classmethod
    def from_dict(cls, d: dict | None) -> Convergence:
        """Back from :meth:`as_dict` (None: one fit that converged)."""
        if not d:
            return cls(1)
        return cls(int(d["n_fits"]), tuple(d["reasons"]), d.get("what_to_try", DEFAULT_HINT),
                   tuple(d.get("iterations", ())))

    def as_dict(self) -> dict:
        """The JSON mark: ``converged``, ``n_fits``, ``n_not_converged``, ``reasons``, ``what_to_try``,
        ``iterations`` (each fit's, in order; null where a fit has no count)."""
        return {"converged": self.converged, "n_fits": self.n_fits, "n_not_converged": self.n_not_converged,
                "reasons": list(self.not_converged), "what_to_try": self.what_to_try,
                "iterations": list(self.iterations)}
