"""Old core against new core, side by side in one process (``bench_calibration.py --old-core REV``).

The old core is ``src/robocal/calib/{problem,solve,identifiability,initial}.py`` of git revision
REV, loaded beside the current one by ``_old_core.load_old_core`` (kinematics and kernels shared).
Both solve the same problems from the same start; the rows are interleaved (old, new, old, new...)
in every repeat so load changes on a shared machine hit both alike; medians, best and the ratio
new / old of the medians are printed, and the solutions must agree.
"""

from __future__ import annotations

import time

import numpy as np

from _old_core import load_old_core


def _time(fn, loops):
    t0 = time.perf_counter()
    for _ in range(loops):
        fn()
    return (time.perf_counter() - t0) / loops * 1e3


def _pairs(sc, geom, old, new_solve, CalibrationProblem, Target, sigma):
    """(label, old fn, new fn, old problem, new problem) rows."""

    def problems(free):
        args = (sc.nominal, sc.q, [Target("r1", None, tuple(sc.point0))], sc.points)
        kw = dict(free=free, base_initial=sc.base0, point_sigma_mm=sigma)
        return old.problem.CalibrationProblem(*args, **kw), CalibrationProblem(*args, **kw)

    po, pn = problems(geom)
    fo, fn_ = problems(None)
    so, sn = po.initial_state(), pn.initial_state()
    step = np.random.default_rng(0).normal(0.0, 1e-4, pn.n_variables)
    return [
        (f"solve(problem), {pn.n_variables} variables", lambda: old.solve.solve(po), lambda: new_solve(pn), po, pn),
        ("solve(problem, auto_identifiable=False)", lambda: old.solve.solve(po, auto_identifiable=False),
         lambda: new_solve(pn, auto_identifiable=False), po, pn),
        (f"solve, all {len(sc.nominal.params)} parameters free", lambda: old.solve.solve(fo), lambda: new_solve(fn_),
         fo, fn_),
        ("problem.evaluate (r and J, 300 x 26)", lambda: po.evaluate(so), lambda: pn.evaluate(sn), po, pn),
        ("problem.retract (one LM step)", lambda: po.retract(so, step), lambda: pn.retract(sn, step), po, pn),
    ]


def compare_cores(sc, geom, rev: str, *, repeat: int, budget: float, sigma: float) -> list[str]:
    """The old-vs-new table as printable lines."""
    from robocal.calib import CalibrationProblem, Target, solve

    old = load_old_core(rev)
    rows = _pairs(sc, geom, old, solve, CalibrationProblem, Target, sigma)
    lines = [f"old core ({old.rev}, monolithic CalibrationProblem) vs new core (parameter + residual blocks), "
             f"same process, rows interleaved, {repeat} repeats of ~{budget:g} s each"]
    # correctness: identical solutions
    agree = []
    for label, fo, fn, *_ in rows[:3]:
        ro, rn = fo(), fn()
        d = float(np.max(np.abs(ro.values - rn.values)))
        agree.append(f"  {label}: max |new - old| over the {len(rn.values)} variables {d:.1e} "
                     f"(iterations {ro.iterations} / {rn.iterations}, RMS {ro.rms_after:.6f} / {rn.rms_after:.6f} mm)")
    loops = {}
    for label, fo, *_ in rows:
        loops[label] = max(1, int(budget / max(_time(fo, 1) * 1e-3, 1e-9)))
    t_old = {label: [] for label, *_ in rows}
    t_new = {label: [] for label, *_ in rows}
    for _ in range(repeat):
        for label, fo, fn, *_ in rows:
            t_old[label].append(_time(fo, loops[label]))
            t_new[label].append(_time(fn, loops[label]))
    hdr = (f"{'':44s}{'old median':>13s}{'new median':>13s}{'old best':>13s}{'new best':>13s}{'new/old':>9s}"
           f"{'paired':>8s}")
    lines += ["", hdr, "-" * len(hdr)]
    for label, *_ in rows:
        mo, mn = float(np.median(t_old[label])), float(np.median(t_new[label]))
        unit, k = ("ms", 1.0) if mo >= 0.5 else ("us", 1e3)
        cells = [mo, mn, min(t_old[label]), min(t_new[label])]
        paired = float(np.median(np.array(t_new[label]) / np.array(t_old[label])))
        lines.append(f"{label:44s}" + "".join(f"{c * k:10.3f} {unit}" for c in cells) + f"{mn / mo:9.3f}"
                     f"{paired:8.3f}")
    lines.append("new/old: ratio of the medians; paired: median over the repeats of new / old timed back to back")
    lines += ["", "solutions (old / new):"] + agree
    return lines
