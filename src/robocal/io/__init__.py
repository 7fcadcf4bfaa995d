"""Every file format robocal reads or writes, one module per format family; units are declared in
the files and converted here (inside robocal: mm, rad).

- :mod:`.header`: what the text formats share: the ``# key: value`` header block, declared units,
  reading a file's text, and :class:`~robocal.io.header.FileFormatError`, the base of every
  reader's error (file, line, column in the message);
- :mod:`.table`: the CSV table under the header (column row, data rows, numeric cells);
- :mod:`.atomic`: writing through a temporary file and a rename;
- :mod:`.measurements`: measurement files ``robocal-measurements/1`` (docs/measurement-files.md);
- :mod:`.programs`, :mod:`.targets`: robot programs (KRL, RAPID, FANUC TP, UR script and
  robocal's joint table ``robocal-program/1``), Cartesian targets ``robocal-targets/1`` and the
  corrected targets ``robocal-corrected-targets/1``;
- :mod:`.importers`: other software's exports (tracker CSV, SpatialAnalyzer text, joint logs);
- :mod:`.tcp_files`: tool-calibration inputs (sensor points, flange poses, parallel barriers);
- :mod:`.thermal_files`: thermal run directories, sphere files, sensor and set-up JSON;
- :mod:`.urdf`: URDF import and export;
- :mod:`.datasets`: the third-party real data sets (one reader module per data set).

``io`` may import ``kinematics``, ``transforms`` and the math packages' result types; it never
imports ``robots``, ``workflows``, ``cli``, ``report``, ``store`` or ``sim`` (callers pass robot
models in). This package re-exports the measurement-file API.
"""

from .atomic import atomic_write_bytes, atomic_write_text
from .measurements import (
    DEFAULT_TARGET,
    FORMAT,
    MeasurementFileError,
    Measurements,
    read_measurements,
    write_measurements,
)

__all__ = [
    "DEFAULT_TARGET",
    "FORMAT",
    "MeasurementFileError",
    "Measurements",
    "atomic_write_bytes",
    "atomic_write_text",
    "read_measurements",
    "write_measurements",
]
