"""Every registered documented figure is regenerated from its source and compared with the printed
value (robocal.docs.figures). Slow figures run with ROBOCAL_SLOW=1 (before each release)."""

from __future__ import annotations

import os

import pytest

from robocal.docs.figures import FIGURES, PRODUCERS, check_figures, printed_value, repository_root
from robocal.io.datasets import datasets_root

NEEDS_DATA = {"boby_fanuc", "dlr_justin", "hilti_trailblazer"}


def test_every_figure_is_still_where_its_pattern_looks():
    for fig in FIGURES:
        value, _ = printed_value(fig)
        assert value > 0, fig.key
        assert fig.producer in PRODUCERS, fig.key


@pytest.mark.parametrize("fig", FIGURES, ids=[f.key for f in FIGURES])
def test_documented_figure_is_reproduced(fig):
    if fig.slow and os.environ.get("ROBOCAL_SLOW") != "1":
        pytest.skip("slow figure: run with ROBOCAL_SLOW=1 (python -m robocal.docs.figures --check --all)")
    if fig.producer.split("/")[0] in NEEDS_DATA and not (datasets_root() / fig.producer.split("/")[0]).is_dir():
        pytest.skip(f"dataset {fig.producer.split('/')[0]} not found under {datasets_root()}")
    (row,) = check_figures(include_slow=True, only=[fig.key], root=repository_root())
    assert row["ok"], row
