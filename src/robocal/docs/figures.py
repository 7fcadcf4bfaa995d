"""Every registered figure of README.md and docs/ regenerated from its source and compared with the
printed value.

Each :class:`Figure` names the file, a regular expression whose first group is the printed number,
the producer that recomputes it (a dataset protocol, a simulation, a search;
``figure_producers.py``) and the tolerance (the registry: ``figure_registry.py``): half a unit of
the last printed digit plus a relative part stated per figure (cross-machine floating point and
solver stopping points). Producers are cached, so figures sharing a protocol run it once.

Usage::

    python -m robocal.docs.figures              # print the table (fast figures)
    python -m robocal.docs.figures --check      # exit 1 when a figure drifted beyond its tolerance
    python -m robocal.docs.figures --all        # include the slow ones (elastic-full on Justin, Hilti)
    python -m robocal.docs.figures --all --only kinematics:   # one page or figure (keys contain the text)
    python -m robocal.docs.figures --audit      # the numbers of README.md and docs/ no figure checks
    python -m robocal.docs.figures --audit --check            # exit 1 when a page has more than its baseline

The fast figures also run in the test suite (``tests/test_doc_figures.py``); the slow ones run there
when ``ROBOCAL_SLOW=1`` is set (before each release). The audit (:mod:`robocal.docs.figure_audit`)
runs in ``tests/test_doc_figure_audit.py``.
"""


from __future__ import annotations

import argparse
import re
import sys
from pathlib import Path

from .figure_producers import PRODUCERS, SLOW_PRODUCERS, datasets_needed, repository_root
from .figure_registry import FIGURES, Figure

__all__ = ["Figure", "FIGURES", "PRODUCERS", "SLOW_PRODUCERS", "check_figure", "check_figures", "datasets_needed",
           "printed_value", "repository_root"]


# ----------------------------------------------------------------------------------------- checking
def printed_value(fig: Figure, root: Path | None = None) -> tuple[float, int]:
    """The number as printed in the file, and its count of decimals.

    Raises
    ------
    robocal.errors.InputFileError
        If the pattern no longer matches (the text was edited: update the registry with it).
    """
    from ..errors import InputFileError

    root = root or repository_root()
    text = (root / fig.file).read_text(encoding="utf-8")
    m = re.search(fig.pattern, text)
    if not m:
        raise InputFileError(f"{fig.file}: the figure {fig.key!r} is no longer where its pattern looks "
                             f"({fig.pattern!r}); update robocal/docs/figures.py with the text")
    s = m.group(1).replace("−", "-")
    mantissa, _, exponent = s.partition("e")
    decimals = len(mantissa.split(".")[1]) if "." in mantissa else 0
    return float(s), decimals - int(exponent or 0)


def check_figure(fig: Figure, root: Path | None = None) -> dict:
    """Regenerate one figure and compare: ``key, file, printed, computed, tolerance, ok, note``."""
    printed, decimals = printed_value(fig, root)
    computed = float(PRODUCERS[fig.producer]()[fig.field])
    tol = 0.5 * 10 ** (-decimals) + fig.rel_tol * abs(printed)
    return {"key": fig.key, "file": fig.file, "printed": printed, "computed": computed, "tolerance": tol,
            "ok": abs(computed - printed) <= tol, "note": fig.note}


def check_figures(*, include_slow: bool = False, only=None, root: Path | None = None) -> list[dict]:
    """Regenerate and compare (:func:`check_figure`); ``only``: texts one of which each key contains."""
    return [check_figure(fig, root) for fig in FIGURES
            if not (fig.slow and not include_slow) and not (only and not any(o in fig.key for o in only))]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m robocal.docs.figures", description=__doc__.splitlines()[0])
    ap.add_argument("--check", action="store_true", help="exit 1 when a figure drifted beyond its tolerance")
    ap.add_argument("--all", action="store_true", help="include the slow figures")
    ap.add_argument("--only", action="append", help="only figures whose key contains this text")
    ap.add_argument("--audit", action="store_true",
                    help="list the numbers of README.md and docs/*.md that no figure checks (robocal.docs.figure_audit); "
                         "with --check: exit 1 when a page has more than its baseline")
    ap.add_argument("--write-baseline", action="store_true", help="with --audit: store the counts as the new baseline")
    a = ap.parse_args(argv)
    if a.audit:
        return _audit(a.check, a.write_baseline)
    rows = []
    for fig in FIGURES:
        if (fig.slow and not a.all) or (a.only and not any(o in fig.key for o in a.only)):
            continue
        try:
            rows.append(check_figure(fig))
        except Exception as exc:  # one broken producer or pattern must not hide the other figures
            rows.append({"key": fig.key, "file": fig.file, "printed": float("nan"), "computed": float("nan"),
                         "tolerance": float("nan"), "ok": False, "note": f"error: {type(exc).__name__}: {exc}"})
    print(f"{'figure':<52}{'printed':>10}{'computed':>12}{'tol':>9}  ok")
    for r in rows:
        print(f"{r['key']:<52}{r['printed']:>10g}{r['computed']:>12.5g}{r['tolerance']:>9.2g}  "
              f"{'yes' if r['ok'] else 'NO'}" + (f"  ({r['note']})" if r["note"] == "training data"
                                                 or r["note"].startswith("error") else ""))
    bad = [r for r in rows if not r["ok"]]
    if bad:
        print(f"{len(bad)} figure(s) drifted: {', '.join(r['key'] for r in bad)}", file=sys.stderr)
    return 1 if (a.check and bad) else 0


def _audit(check: bool, write: bool) -> int:
    """``--audit``: print the uncovered numbers per page and the counts against the baseline."""
    from .figure_audit import audit, baseline, uncovered_counts, write_baseline

    numbers = audit()
    for n in numbers:
        print(f"{n.file}:{n.line}: {n.text:<10} {n.context[:110]}")
    counts, base = uncovered_counts(numbers), baseline()
    print(f"\n{'page':<36}{'uncovered':>10}{'baseline':>10}")
    for f in sorted(set(counts) | set(base)):
        print(f"{f:<36}{counts.get(f, 0):>10}{base.get(f, 0):>10}" + ("  GREW" if counts.get(f, 0) > base.get(f, 0) else ""))
    print(f"{'total':<36}{sum(counts.values()):>10}{sum(base.values()):>10}")
    if write:
        write_baseline(counts)
        print("baseline written", file=sys.stderr)
    grew = [f for f in counts if counts[f] > base.get(f, 0)]
    return 1 if (check and grew) else 0


if __name__ == "__main__":  # pragma: no cover
    from .._blas_threads import single_thread_blas

    single_thread_blas()  # numpy is not imported yet here (robocal/_blas_threads.py)
    sys.exit(main())
