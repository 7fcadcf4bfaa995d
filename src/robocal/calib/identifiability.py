"""Identifiability: which parameters a pose set can determine, which trade off, and why.

The analysis works on the Jacobian with unit-norm columns (so mm and rad compare). A column that
is (numerically) zero has no effect on the measurements: *not observable*. Otherwise a greedy
pass over the columns in priority order keeps a column when its component orthogonal to the
columns kept so far is larger than ``tol`` of its norm (one QR factorization in priority order). The kept set is a maximal independent
set (a basis of the column space): every dropped column is a combination of kept ones, and no
identifiable column is dropped unless it is exactly such a combination. Each dropped parameter
is explained by the kept parameters it trades off against (least-squares coefficients).

With ``column_blocks`` (the parameter block of each column, ``Problem.column_blocks``) every
dropped entry names its block and :meth:`IdentifiabilityReport.by_block` groups the verdicts per
parameter block.

Observability indices of a pose set (Sun & Hollerbach's review): O1 = (prod s_i)^(1/n) / sqrt(m),
O2 = s_min / s_max, O3 = s_min, O4 = s_min^2 / s_max, on the scaled Jacobian.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

__all__ = ["IdentifiabilityReport", "analyse_identifiability", "observability_indices", "DEFAULT_PRIORITY",
           "IDENTIFIABILITY_TOL"]

#: The one tolerance of every identifiability verdict (planner and calibration): a column is
#: identifiable when its part independent of the columns kept before it exceeds this fraction of
#: its norm (unit-norm columns).
IDENTIFIABILITY_TOL = 1e-6

#: Blocks are tried in this order: frames the measurement setup always needs come first, so a
#: robot parameter that only duplicates a base or target coordinate is the one reported.
DEFAULT_PRIORITY = ("base", "targets", "planes", "geometry")


@dataclass
class IdentifiabilityReport:
    """identifiable: names kept; dropped: list of dicts (name, why, trades_off_with, and block when
    known); rank, condition_number (of the scaled Jacobian of all candidates), singular_values;
    block_of: {name: parameter block} when the analysis was given the columns' blocks."""

    identifiable: list
    dropped: list = field(default_factory=list)
    rank: int = 0
    condition_number: float = float("nan")
    singular_values: np.ndarray | None = None
    block_of: dict | None = None

    @classmethod
    def trivial(cls, names):
        return cls(list(names))

    @property
    def dropped_names(self) -> list:
        return [d["name"] for d in self.dropped]

    def by_block(self) -> dict:
        """``{block: {"identifiable": [names], "dropped": [{name, why, ...}]}}`` in column order
        (one pseudo-block ``""`` when the blocks are unknown)."""
        block_of = self.block_of or {}
        out: dict = {}
        for nm in list(self.identifiable) + [d["name"] for d in self.dropped]:
            out.setdefault(block_of.get(nm, ""), {"identifiable": [], "dropped": []})
        for nm in self.identifiable:
            out[block_of.get(nm, "")]["identifiable"].append(nm)
        for d in self.dropped:
            out[block_of.get(d["name"], "")]["dropped"].append(d)
        return out

    def explain(self) -> str:
        if not self.dropped:
            return f"all {len(self.identifiable)} parameters identifiable (condition {self.condition_number:.3g})"
        return "\n".join(f"{d['name']}: {d['why']}" for d in self.dropped)


def analyse_identifiability(J, names, blocks=None, *, tol: float = IDENTIFIABILITY_TOL, priority=DEFAULT_PRIORITY,
                            explain: bool = True, column_blocks=None, column_norms=None) -> IdentifiabilityReport:
    """Analyse the columns of ``J`` (M, n) named ``names``; ``blocks`` (n,) gives each column's
    identifiability group (priority order ``priority``, other groups after them);
    ``column_blocks`` (n,) optionally the parameter block of each column (reported per block).

    ``explain=False`` skips the least-squares explanation of each dropped parameter (and the
    singular values): a quick check of which set is identifiable.

    ``column_norms`` (n,): scale the columns by these norms instead of their own. For a reduced
    Jacobian -- columns already projected off other (eliminated, always identifiable) columns,
    given the norms of the unprojected columns -- the verdicts are those of the full Jacobian with
    the eliminated columns first in priority (:mod:`robocal.calib.schur`).
    """
    J = np.asarray(J, dtype=float)
    n = J.shape[1]
    names = list(names)
    blocks = np.array(["geometry"] * n) if blocks is None else np.asarray(blocks)
    norms = np.linalg.norm(J, axis=0) if column_norms is None else np.asarray(column_norms, dtype=float)
    scale = norms.max(initial=0.0)
    order = [i for b in priority for i in np.flatnonzero(blocks == b).tolist()]
    seen = set(order)
    order += [i for i in range(n) if i not in seen]
    kept, dropped = [], []
    zero = norms <= 1e-12 * max(scale, 1e-300)
    cand = [i for i in order if not zero[i]]
    for i in order:
        if zero[i]:
            dropped.append({"name": names[i], "why": "has no effect on the measurements (zero Jacobian column)",
                            "trades_off_with": []})
    if cand:
        # |R_jj| of a QR factorization with the columns in priority order is the part of column j
        # independent of all earlier columns (Gram-Schmidt in one Householder pass)
        # (a Gram-matrix Cholesky would be cheaper but squares the conditioning: on badly
        # conditioned problems it keeps columns that are exact combinations of others)
        Rdiag = np.abs(np.diag(np.linalg.qr(J[:, cand] / norms[cand], mode="r")))
        for i, rjj in zip(cand, Rdiag):
            if rjj > tol:
                kept.append(i)
            else:
                dropped.append({"name": names[i], "column": i, "why": None, "trades_off_with": []})
    pending = [d for d in dropped if d.get("why") is None]
    if kept and pending and explain:
        Jk = J[:, kept] / norms[kept]
        cols = [d["column"] for d in pending]
        coefs, *_ = np.linalg.lstsq(Jk, J[:, cols] / norms[cols], rcond=None)
        for d, coef in zip(pending, coefs.T):
            big = np.argsort(-np.abs(coef))[:3]
            partners = [(names[kept[b]], float(coef[b])) for b in big if abs(coef[b]) > 0.05]
            d["trades_off_with"] = partners
            terms = " ".join(f"{'+' if c >= 0 else '-'} {abs(c):.3g}*{nm}" for nm, c in partners)
            d["why"] = f"trades off against other parameters (its effect = {terms.lstrip('+ ')} in scaled units)"
    block_of = None if column_blocks is None else {nm: str(b) for nm, b in zip(names, column_blocks)}
    for d in dropped:
        d.pop("column", None)
        if block_of is not None:
            d["block"] = block_of[d["name"]]
    Js = J / np.where(norms > 0, norms, 1.0)
    s = np.sqrt(np.maximum(np.linalg.eigvalsh(Js.T @ Js)[::-1], 0.0)) if n and explain else np.zeros(0)
    rank = len(kept)
    cond = float(s[0] / s[rank - 1]) if rank and len(s) else float("inf")
    kept_sorted = [names[i] for i in sorted(kept)]
    return IdentifiabilityReport(kept_sorted, dropped, rank, cond, s, block_of)


def observability_indices(J) -> dict:
    """Observability indices O1..O4 of a Jacobian (M, n), columns scaled to unit norm first."""
    J = np.asarray(J, dtype=float)
    norms = np.linalg.norm(J, axis=0)
    s = np.linalg.svd(J / np.where(norms > 0, norms, 1.0), compute_uv=False)
    m, n = J.shape
    if s[-1] <= 0:
        return {"O1": 0.0, "O2": 0.0, "O3": 0.0, "O4": 0.0}
    return {"O1": float(np.exp(np.mean(np.log(s))) / np.sqrt(m)), "O2": float(s[-1] / s[0]),
            "O3": float(s[-1]), "O4": float(s[-1] ** 2 / s[0])}
