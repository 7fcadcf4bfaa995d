"""``python -m robocal.workflows.datasets``: print the real-data protocol table."""

from .report import report

print(report())
