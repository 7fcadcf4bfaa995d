"""Every registered documented figure is regenerated from its source and compared with the printed
value (robocal.docs.figures). Slow figures run with ROBOCAL_SLOW=1 (before each release)."""

from __future__ import annotations

import math
import os

import pytest

from robocal.docs.figures import FIGURES, PRODUCERS, check_figure, datasets_needed, printed_value, repository_root
from robocal.io.datasets import datasets_root


def test_every_figure_is_still_where_its_pattern_looks():
    assert len({f.key for f in FIGURES}) == len(FIGURES), "figure keys must be unique"
    for fig in FIGURES:
        value, _ = printed_value(fig)
        assert math.isfinite(value), fig.key
        assert fig.producer in PRODUCERS, fig.key


@pytest.mark.parametrize("fig", FIGURES, ids=[f.key for f in FIGURES])
def test_documented_figure_is_reproduced(fig):
    if fig.slow and os.environ.get("ROBOCAL_SLOW") != "1":
        pytest.skip("slow figure: run with ROBOCAL_SLOW=1 (python -m robocal.docs.figures --check --all)")
    missing = [d for d in datasets_needed(fig.producer) if not (datasets_root() / d).is_dir()]
    if missing:
        pytest.skip(f"dataset {', '.join(missing)} not found under {datasets_root()}")
    row = check_figure(fig, repository_root())
    assert row["ok"], row
