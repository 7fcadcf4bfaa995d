"""robocal: keep industrial robots accurate over their working life."""

__version__ = "0.1.0"
