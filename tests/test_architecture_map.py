"""docs/architecture.md's module index names every module of the tree, and nothing else."""

from __future__ import annotations

import re

from robocal.docs.architecture import BEGIN, END, module_index
from robocal.docs.figures import repository_root


def test_every_module_is_in_the_architecture_map():
    page = (repository_root() / "docs" / "architecture.md").read_text(encoding="utf-8")
    assert BEGIN in page and END in page, "run: python -m robocal.docs.architecture --write"
    listed = set(re.findall(r"^- `([\w/]+\.py)`", page[page.index(BEGIN):page.index(END)], re.M))
    tree = set(re.findall(r"^- `([\w/]+\.py)`", module_index(), re.M))
    missing, stale = sorted(tree - listed), sorted(listed - tree)
    assert not missing and not stale, (
        f"modules missing from docs/architecture.md: {missing}; listed but gone: {stale} "
        "(regenerate: python -m robocal.docs.architecture --write)")
