"""The API reference (docs/api.md, MkDocs + mkdocstrings, numpy-style docstrings) builds in strict
mode without a warning, and documents every public name with shapes, units and what it raises."""

import importlib.util
import inspect
import re
import subprocess
import sys
from pathlib import Path

import pytest

import robocal

ROOT = Path(__file__).resolve().parents[1]


def test_every_public_name_is_in_the_reference():
    text = (ROOT / "docs" / "api.md").read_text(encoding="utf-8")
    documented = {line.rsplit(".", 1)[1].strip() for line in text.splitlines() if line.startswith("::: ")}
    assert documented == set(robocal.__all__)


@pytest.mark.parametrize("name", robocal.__all__)
def test_numpydoc_sections(name):
    obj = getattr(robocal, name)
    doc = inspect.getdoc(obj) or ""
    assert doc, name
    if inspect.isfunction(obj):
        for section in ("Parameters\n----------", "Returns\n-------", "Raises\n------"):
            assert section in doc, f"{name}: no {section.splitlines()[0]} section"
        assert re.search(r"\[(mm|rad|deg|mm/rad|s)\]|shape \(", doc), f"{name}: no unit or shape"
    elif name.endswith("Options"):
        assert "Parameters\n----------" in doc, name


@pytest.mark.skipif(importlib.util.find_spec("mkdocs") is None or importlib.util.find_spec("mkdocstrings") is None,
                    reason="mkdocs and mkdocstrings[python] are not installed (pip install -e .[docs])")
def test_docs_build_strict_without_warnings(tmp_path):
    r = subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "--site-dir", str(tmp_path / "site")],
                       cwd=ROOT, capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    assert "WARNING" not in r.stderr, r.stderr
    html = (tmp_path / "site" / "api" / "index.html").read_text(encoding="utf-8")
    for name in robocal.__all__:
        assert name in html, name
