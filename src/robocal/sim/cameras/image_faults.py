"""Faults written into a folder of simulated camera images (tests/test_handeye_gate.py and
docs/reliability.md's camera gate): every other image stretched sideways, as if from another camera
or a resampling."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ...io.images import list_images, read_image_gray, write_png

__all__ = ["stretch_every_other_image"]


def stretch_every_other_image(folder, factor: float = 1.3) -> list:
    """Stretch the 1st, 3rd, ... image of ``folder`` (sorted by name) by ``factor`` along the image's
    x axis (``x' = factor x - 0.15 w``: the middle of the picture stays in view), in place, as 8-bit
    grey PNG; linear interpolation, grey 128 where no source pixel maps.

    Returns
    -------
    list of Path
        The images changed.
    """
    changed = []
    for f in sorted(list_images(Path(folder)))[::2]:
        im = read_image_gray(f).astype(float)
        w = im.shape[1]
        x = (np.arange(w) + 0.15 * w) / factor          # source column of each output column
        inside = (x >= 0) & (x <= w - 1)
        x0 = np.clip(np.floor(x).astype(int), 0, w - 2)
        t = x - x0
        out = im[:, x0] * (1 - t) + im[:, x0 + 1] * t
        out[:, ~inside] = 128.0
        write_png(f, np.clip(np.rint(out), 0, 255).astype(np.uint8), overwrite=True)
        changed.append(f)
    return changed
