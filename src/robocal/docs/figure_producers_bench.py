"""Producers of documented figures that a script of ``benchmarks/`` prints (:mod:`robocal.docs.figures`):
the accuracy figures of a benchmark, never its times (machine-dependent, not checked). Each returns a
flat ``{field: value}`` dict and is cached."""

from __future__ import annotations

import contextlib
import functools
import importlib.util
import io
import re

__all__ = ["BENCH_PRODUCERS", "camera_calibration", "ik_seed"]

_F = r"([0-9.]+(?:e[+-]?[0-9]+)?)"


def _bench_module(script: str):
    """``benchmarks/SCRIPT`` imported as a module (its folder on ``sys.path`` for its helpers)."""
    import sys

    from .figure_producers import repository_root

    folder = repository_root() / "benchmarks"
    if str(folder) not in sys.path:
        sys.path.insert(0, str(folder))
    spec = importlib.util.spec_from_file_location(f"_robocal_figures_{script[:-3]}", folder / script)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@functools.lru_cache(maxsize=None)
def ik_seed(robot: str) -> dict:
    """docs/kinematics.md "Measured": ``python benchmarks/bench_ik_seed.py`` (seed 1, 20 000 FK
    samples, GA 10 x 5, 2000 held-out poses) for ``robot`` in ``irb140`` (nominal), ``tilted`` (the
    IRB140 with beta tilts), ``ur10`` (joint-box branch), one repeat of each timing (not used).

    Fields: ``K``, ``width``, ``lam``, ``weight`` (the chosen structure), ``ga.first``, ``ga.last``
    [deg] (validation RMS joint error), ``ga.evaluations``, ``raw.{joint|position|rotation}.{median|p95|max}``
    [deg, mm], ``domain.branch_percent``, ``domain.back_percent``, and per IK start
    ``ik.{network|middle|zero|box|closed_form}.{converged|on_branch|median_it|p95_it}`` [%, iterations]."""
    import numpy as np

    from ..robots import load_robot

    bench = _bench_module("bench_ik_seed.py")
    buf = io.StringIO()
    args = (20000, 10, 5, 2000, 1, 1)
    with contextlib.redirect_stdout(buf):
        if robot == "irb140":
            bench.run(robot, load_robot("abb_irb140"), *args)
        elif robot == "tilted":
            bench.run(robot, bench.tilted_irb140(), *args)
        else:
            ur10 = load_robot("ur10")
            box = {"J1": (-90, 90), "J2": (-170, -10), "J3": (10, 150), "J5": (10, 150)}
            bench.run(robot, ur10, *args, branch=bench.joint_box_branch(ur10, {k: np.radians(v) for k, v in box.items()}))
    text = buf.getvalue()
    out = {}
    m = re.search(r"chosen K = (\d+), width " + _F + ", lam " + _F + ", position weight " + _F, text)
    out.update(zip(("K", "width", "lam", "weight"), map(float, m.groups())))
    m = re.search(r"validation RMS joint error " + _F + r" deg .*?-> " + _F + r" deg after \d+ generations; (\d+) structures",
                  text)
    out.update(zip(("ga.first", "ga.last", "ga.evaluations"), map(float, m.groups())))
    for what in ("joint", "position", "rotation"):
        m = re.search(r"\| " + what + r"[^|]*\| " + _F + r" \| " + _F + r" \| " + _F + r" \|", text)
        out.update({f"raw.{what}.{q}": float(v) for q, v in zip(("median", "p95", "max"), m.groups())})
    m = re.search(r"domain check: " + _F + r" % of held-out.*?; " + _F + " % of poses needing", text)
    out["domain.branch_percent"], out["domain.back_percent"] = map(float, m.groups())
    for key, label in (("network", "GA-RBF network seed"), ("middle", "nominal: middle of the joint ranges"),
                       ("zero", "zero joints"), ("box", "middle of the branch's joint box"),
                       ("closed_form", "closed form")):
        m = re.search(r"\| " + re.escape(label) + r"[^|]*\| " + r" \| ".join([_F] * 4) + r" \|", text)
        if m:
            out.update({f"ik.{key}.{f}": float(v) for f, v in zip(("converged", "on_branch", "median_it", "p95_it"),
                                                                    m.groups())})
    return out


@functools.lru_cache(maxsize=None)
def camera_calibration(seeds: int = 3) -> dict:
    """docs/handeye.md "Side by side with OpenCV": ``python benchmarks/bench_camera_calibration.py
    --seeds SEEDS``'s two tables (rendered images against the truth; the ROS-Industrial real images
    when the data set is present), as ``"{board} | {pipeline}|{col}|{pos}"`` (the numbers of each
    table cell, :func:`robocal.docs.figure_producers._markdown_rows` with two label cells; the real
    table's rows have one label cell and are keyed ``"{set}|{col}|{pos}"``)."""
    from .figure_producers import _markdown_rows

    bench = _bench_module("bench_camera_calibration.py")
    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        bench.rendered(list(range(seeds)))
    rendered = _markdown_rows(buf.getvalue(), label_cells=2)
    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        bench.real()
    return {**rendered, **_markdown_rows(buf.getvalue(), label_cells=1)}


BENCH_PRODUCERS = {"camera/bench_calibration": camera_calibration,
                   **{f"ik_seed/{r}": functools.partial(ik_seed, r) for r in ("irb140", "tilted", "ur10")}}
