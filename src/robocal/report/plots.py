"""Plot images for the command line and reports (headless matplotlib, PNG files)."""

from __future__ import annotations

import io
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from ..io.atomic import atomic_write_bytes  # noqa: E402

__all__ = ["plot_accuracy_map", "save_figure"]


def save_figure(fig, path, overwrite: bool = True) -> Path:
    """Save a figure atomically (rendered in memory, then a temporary file and a rename)."""
    buf = io.BytesIO()
    try:
        fig.savefig(buf, format=Path(path).suffix.lstrip(".") or "png", dpi=120, bbox_inches="tight")
    finally:
        plt.close(fig)
    return atomic_write_bytes(path, buf.getvalue(), overwrite=overwrite)


def plot_accuracy_map(positions_mm, errors_mm, path, title: str, repeatability_mm: float | None = None) -> Path:
    """Top and side views of the workspace coloured by position error, and an error histogram.

    positions_mm (N, 3) flange positions in the base frame; errors_mm (N,) error magnitudes.
    """
    p = np.asarray(positions_mm, dtype=float)
    e = np.asarray(errors_mm, dtype=float)
    fig, axes = plt.subplots(1, 3, figsize=(16, 4.6), gridspec_kw={"wspace": 0.35})
    vmax = float(np.percentile(e, 99))
    for ax, (i, j, lab) in zip(axes[:2], [(0, 1, ("x [mm]", "y [mm]")), (0, 2, ("x [mm]", "z [mm]"))]):
        sc = ax.scatter(p[:, i], p[:, j], c=e, s=10, cmap="viridis", vmin=0.0, vmax=vmax)
        ax.set_xlabel(lab[0])
        ax.set_ylabel(lab[1])
        ax.set_aspect("equal", adjustable="datalim")
        ax.set_title("top view" if j == 1 else "side view")
    fig.colorbar(sc, ax=axes[:2], label="position error [mm]", shrink=0.85)
    axes[2].hist(e, bins=40, color="tab:blue", alpha=0.8)
    axes[2].set_xlabel("position error [mm]")
    axes[2].set_ylabel("poses")
    if repeatability_mm is not None:
        axes[2].axvline(repeatability_mm, color="tab:red", ls="--", label=f"repeatability {repeatability_mm:.3f} mm")
        axes[2].legend()
    fig.suptitle(title)
    return save_figure(fig, path)
