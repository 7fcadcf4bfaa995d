"""Reading and writing files at robocal's boundaries (measurement files; see docs/measurement-files.md)."""

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
