"""Tools that keep the documentation honest: every documented figure regenerated and checked
(``python -m robocal.docs.figures --check``)."""
