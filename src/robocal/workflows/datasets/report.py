"""All three real-data protocols as one plain-text table (``python -m robocal.workflows.datasets``)."""

from __future__ import annotations

from ...io.datasets import HILTI_SETS
from .boby_fanuc import calibrate_boby_seeds
from .dlr_justin import calibrate_justin
from .hilti_trailblazer import calibrate_hilti

__all__ = ["report"]

_STATS = "{rms:6.3f} {mean:6.3f} {max:6.2f}"


def _boby_lines(root) -> list:
    r = calibrate_boby_seeds(range(5), root=root)
    lines = ["boby_fanuc (24/12, mean over seeds 0-4)"]
    for k in ("nominal", "calibrated"):
        lines.append(f"  {k:38s} " + _STATS.format(**r[k]))
    for run in r["runs"]:
        lines.append(f"    seed {run['seed']}: nominal {run['nominal']['rms']:.3f}, calibrated "
                     f"{run['calibrated']['rms']:.3f} (train {run['train_rms']:.3f})")
    return lines


def _justin_lines(root) -> list:
    r = calibrate_justin(0, root=root)
    lines = ["dlr_justin (400/100, seed 0, both markers)"]
    for k, label in (("nominal", "base + 2 markers"), ("offsets", "+ 18 joint offsets"), ("all", "+ all DH (prior)")):
        lines.append(f"  {label:38s} " + _STATS.format(**r[k]) + f"   (train {r[k]['train_rms']:.2f})")
    return lines


def _hilti_lines(root) -> list:
    r = calibrate_hilti(root=root)
    lines = [f"hilti_trailblazer (fit on flat: train RMS {r['result'].rms_before:.2f} -> {r['result'].rms_after:.2f} mm; per-station CROSS Kabsch, "
             f"ss 0/7)",
             "  set               n   nominal RMS/p95xy/p95z   calibrated RMS/p95xy/p95z  mean   max"]
    for s in HILTI_SETS:
        n, c = r["nominal"][s]["all"], r["calibrated"][s]["all"]
        lines.append(f"  {s:16s} {c['n']:4d}   {n['rms']:5.2f} {n['p95_xy']:5.1f} {n['p95_z']:5.1f}        "
                     f"{c['rms']:5.2f} {c['p95_xy']:5.1f} {c['p95_z']:5.1f}   {c['mean']:5.2f} {c['max']:5.1f}")
    return lines


def report(root=None) -> str:
    """The holdout figures of the three protocols (docs/datasets.md) as a plain-text table [mm]."""
    header = ["dataset / model                           holdout RMS   mean    max  [mm]"]
    return "\n".join(header + _boby_lines(root) + _justin_lines(root) + _hilti_lines(root))
