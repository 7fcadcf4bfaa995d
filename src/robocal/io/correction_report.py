"""The per-target report of ``robocal correct MODEL PROGRAM``: a CSV file, one row per target."""

from __future__ import annotations

import csv
import io

from .atomic import atomic_write_text

__all__ = ["REPORT_FORMAT", "REPORT_COLUMNS", "write_correction_report"]

REPORT_FORMAT = "robocal-program-correction/1"
#: columns, in order: the target, whether it was corrected, sizes of the correction, the reason otherwise
REPORT_COLUMNS = ("target", "kind", "line", "status", "cartesian_correction_mm", "orientation_correction_deg",
                  "max_joint_change_deg", "remaining_error_mm", "within_limits", "joints_deg", "sigma_mm",
                  "unknown_mm", "frames", "note")


def write_correction_report(path, rows, *, program: str, model: str, overwrite: bool = False):
    """Write ``rows`` (dicts keyed by :data:`REPORT_COLUMNS`) as CSV with a ``# key: value`` header
    (atomic; an existing file only with ``overwrite``). Returns the path."""
    buf = io.StringIO()
    buf.write(f"# format: {REPORT_FORMAT}\n# program: {program}\n# model: {model}\n")
    w = csv.DictWriter(buf, fieldnames=REPORT_COLUMNS, lineterminator="\n", extrasaction="ignore")
    w.writeheader()
    for row in rows:
        w.writerow({k: (f"{v:.6g}" if isinstance(v, float) else v) for k, v in row.items()})
    return atomic_write_text(path, buf.getvalue(), overwrite=overwrite)
