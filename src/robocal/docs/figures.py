"""Every registered figure of README.md and docs/ regenerated from its source and compared with the
printed value.

Each :class:`Figure` names the file, a regular expression whose first group is the printed number,
the producer that recomputes it (a dataset protocol, a simulation, a search) and the tolerance: half
a unit of the last printed digit plus a relative part stated per figure (cross-machine floating point
and solver stopping points). Producers are cached, so figures sharing a protocol run it once.

Usage::

    python -m robocal.docs.figures              # print the table (fast figures)
    python -m robocal.docs.figures --check      # exit 1 when a figure drifted beyond its tolerance
    python -m robocal.docs.figures --all        # include the slow ones (elastic-full on Justin, Hilti)

The fast figures also run in the test suite (``tests/test_doc_figures.py``); the slow ones run there
when ``ROBOCAL_SLOW=1`` is set (before each release).
"""

from __future__ import annotations

import argparse
import functools
import re
import sys
from dataclasses import dataclass
from pathlib import Path

__all__ = ["Figure", "FIGURES", "check_figures", "printed_value", "repository_root"]


def repository_root() -> Path:
    """The repository (``README.md`` and ``docs/``): this file is ``src/robocal/docs/figures.py``."""
    return Path(__file__).resolve().parents[3]


@dataclass(frozen=True)
class Figure:
    """One documented number.

    Attributes
    ----------
    key : str
        Identifier (``file:what``).
    file : str
        Path relative to the repository root.
    pattern : str
        Regular expression; its first group is the printed number.
    producer : str
        Name of the producer in :data:`PRODUCERS`.
    field : str
        Key of the producer's result dict.
    rel_tol : float
        Relative tolerance on top of half a unit of the last printed digit.
    slow : bool
        Longer than ~30 s: run with ``--all`` / ``ROBOCAL_SLOW=1``.
    note : str
        What the figure is (e.g. "training data", not a holdout).
    """

    key: str
    file: str
    pattern: str
    producer: str
    field: str
    rel_tol: float = 0.005
    slow: bool = False
    note: str = ""


# ----------------------------------------------------------------------------------------- producers
@functools.lru_cache(maxsize=None)
def _dataset(name: str, model: str) -> dict:
    from ..workflows.datasets.run import run_dataset

    r = run_dataset(name, model)
    out = {k: v for k, v in r.items() if isinstance(v, (int, float))}
    if "sets" in r:
        for s in r["sets"]:
            out[f"{s['set']}.holdout_rms_mm"] = s["holdout_rms_mm"]
    return out


@functools.lru_cache(maxsize=None)
def _nao_simulated() -> dict:
    """docs/self-calibration.md, second NAO test: nao-model's simulator, seed 3, 40 views per hand."""
    import numpy as np

    from ..handeye.self_calibration import assign_carriers, solve_self_calibration
    from ..io.capture_times import match_capture_times
    from ..sim.cameras.self_calibration import simulate_self_calibration

    run = simulate_self_calibration("nao_h25", n_images_per_chain=40, pixel_noise=0.3, joint_noise_deg=0.0, seed=3)
    q, _, _ = match_capture_times(run.frame_times, run.log_times, run.log_joints, tolerance=0.06)
    uv = run.image_points.copy()
    w, h = run.camera.image_size
    uv[~((uv[..., 0] >= 0) & (uv[..., 0] <= w - 1) & (uv[..., 1] >= 0) & (uv[..., 1] <= h - 1))] = np.nan
    idx = np.flatnonzero(np.all(np.isfinite(uv[..., 0]), axis=1))
    X = run.board.object_points()
    on, _, _ = assign_carriers(run.robot, q[idx], uv[idx], X, run.camera, ("left_hand", "right_hand"),
                               camera_end_effector="camera_top")
    res = solve_self_calibration(run.robot, q[idx], uv[idx], X, run.camera, on, camera_end_effector="camera_top",
                                 pixel_sigma=0.3)
    z = [(v - run.joint_offsets_rad[r["joint"]]) / s
         for r, v, s in zip(res.joint_report, res.joint_offsets, res.joint_offset_sigma) if r["identifiable"]]
    return {"max_abs_z": float(max(abs(x) for x in z)), "n_identifiable": len(z),
            "rms_px_per_coordinate": float(res.rms_px / np.sqrt(2))}


@functools.lru_cache(maxsize=None)
def _iso_cube(robot: str) -> dict:
    from ..performance.iso_cube import largest_iso_cube
    from ..robots import load_robot

    c = largest_iso_cube(load_robot(robot))
    return {"edge_mm": c.edge_mm, "centre_x_mm": float(c.centre_mm[0]), "centre_z_mm": float(c.centre_mm[2])}


PRODUCERS = {
    "boby_fanuc/geometric": lambda: _dataset("boby_fanuc", "geometric"),
    "boby_fanuc/elastic-joint": lambda: _dataset("boby_fanuc", "elastic-joint"),
    "dlr_justin/geometric": lambda: _dataset("dlr_justin", "geometric"),
    "dlr_justin/elastic-joint": lambda: _dataset("dlr_justin", "elastic-joint"),
    "dlr_justin/elastic-full": lambda: _dataset("dlr_justin", "elastic-full"),
    "nao/simulated": _nao_simulated,
    "iso_cube/abb_irb140": lambda: _iso_cube("abb_irb140"),
    "iso_cube/kuka_kr150_r3100": lambda: _iso_cube("kuka_kr150_r3100"),
}

_N = r"([0-9]+(?:\.[0-9]+)?)"
_ROW_BOBY = r"\| boby_fanuc \(mean over seeds 0-4\) \| "
_ROW_JUSTIN = r"\| dlr_justin \(seed 0\) \| "

FIGURES = [
    Figure("datasets:boby geometric rms", "docs/datasets.md", _ROW_BOBY + _N, "boby_fanuc/geometric", "holdout_rms_mm"),
    Figure("datasets:boby geometric mean", "docs/datasets.md", _ROW_BOBY + r"[0-9.]+ / " + _N, "boby_fanuc/geometric",
           "holdout_mean_mm"),
    Figure("datasets:boby elastic-joint rms", "docs/datasets.md", _ROW_BOBY + r"[0-9.]+ / [0-9.]+ / [0-9.]+ \| \*\*" + _N,
           "boby_fanuc/elastic-joint", "holdout_rms_mm", rel_tol=0.01),
    Figure("datasets:justin geometric mean", "docs/datasets.md", _ROW_JUSTIN + r"[0-9.]+ / " + _N,
           "dlr_justin/geometric", "holdout_mean_mm"),
    Figure("datasets:justin elastic-joint mean", "docs/datasets.md",
           _ROW_JUSTIN + r"[0-9.]+ / [0-9.]+ / [0-9.]+ \| [0-9.]+ / " + _N, "dlr_justin/elastic-joint",
           "holdout_mean_mm", rel_tol=0.01, slow=True),
    Figure("datasets:justin elastic-full mean (README headline)", "docs/datasets.md",
           _ROW_JUSTIN + r"[0-9.]+ / [0-9.]+ / [0-9.]+ \| [0-9.]+ / [0-9.]+ / [0-9.]+ [^|]*\| \*\*[0-9.]+ / " + _N,
           "dlr_justin/elastic-full", "holdout_mean_mm", rel_tol=0.01, slow=True),
    Figure("self-calibration:nao max |error/sigma|", "docs/self-calibration.md",
           r"9 identifiable offsets\s+within max \|error/sigma\| = " + _N, "nao/simulated", "max_abs_z", rel_tol=0.02),
    Figure("self-calibration:nao rms px", "docs/self-calibration.md", r"= [0-9.]+, RMS " + _N + r" px per coordinate \(regenerated",
           "nao/simulated", "rms_px_per_coordinate", rel_tol=0.01),
    Figure("iso9283:irb140 cube", "docs/iso9283.md", r"IRB 140 cube " + _N + " mm", "iso_cube/abb_irb140", "edge_mm",
           rel_tol=0.0),
    Figure("iso9283:kr150 cube", "docs/iso9283.md", r"KR 150 R3100 " + _N + " mm", "iso_cube/kuka_kr150_r3100",
           "edge_mm", rel_tol=0.0),
]


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
    s = m.group(1)
    return float(s), (len(s.split(".")[1]) if "." in s else 0)


def check_figures(*, include_slow: bool = False, only=None, root: Path | None = None) -> list[dict]:
    """Regenerate and compare; one row per figure: printed, computed, tolerance, ok."""
    rows = []
    for fig in FIGURES:
        if (fig.slow and not include_slow) or (only and not any(o in fig.key for o in only)):
            continue
        printed, decimals = printed_value(fig, root)
        computed = float(PRODUCERS[fig.producer]()[fig.field])
        tol = 0.5 * 10 ** (-decimals) + fig.rel_tol * abs(printed)
        rows.append({"key": fig.key, "file": fig.file, "printed": printed, "computed": computed, "tolerance": tol,
                     "ok": abs(computed - printed) <= tol, "note": fig.note})
    return rows


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m robocal.docs.figures", description=__doc__.splitlines()[0])
    ap.add_argument("--check", action="store_true", help="exit 1 when a figure drifted beyond its tolerance")
    ap.add_argument("--all", action="store_true", help="include the slow figures")
    ap.add_argument("--only", action="append", help="only figures whose key contains this text")
    a = ap.parse_args(argv)
    rows = check_figures(include_slow=a.all, only=a.only)
    print(f"{'figure':<52}{'printed':>10}{'computed':>12}{'tol':>9}  ok")
    for r in rows:
        print(f"{r['key']:<52}{r['printed']:>10g}{r['computed']:>12.5g}{r['tolerance']:>9.2g}  "
              f"{'yes' if r['ok'] else 'NO'}")
    bad = [r for r in rows if not r["ok"]]
    if bad:
        print(f"{len(bad)} figure(s) drifted: {', '.join(r['key'] for r in bad)}", file=sys.stderr)
    return 1 if (a.check and bad) else 0


if __name__ == "__main__":  # pragma: no cover
    from .._blas_threads import single_thread_blas

    single_thread_blas()  # numpy is not imported yet here (robocal/_blas_threads.py)
    sys.exit(main())
