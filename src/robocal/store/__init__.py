"""History of calibration and maintenance cycles in a real database (SQLite file by default, a
server database by URL through SQLAlchemy). See docs/history.md."""

import os

from ._backends import HistoryBusyError, HistoryError, redact_url
from ._credentials import PASSWORD_ENV, PASSWORD_FILE_ENV, strip_credentials, url_password, with_credentials
from ._schema import CYCLE_STATUSES, SCHEMA_VERSION
from ._validate import ALLOWED_UNITS, CYCLE_KINDS, HistoryInputError
from .history import (
    CycleRecord, CycleWriter, HistoryLookupError, HistoryStore, ParameterRow, Quantity, Series, StoredCycle,
    UnknownRobotError,
)

#: Environment variable naming the default history database (a path or URL).
HISTORY_DB_ENV = "ROBOCAL_HISTORY_DB"
#: The default history database when the environment variable is not set (in the working folder).
DEFAULT_HISTORY_DB = "robocal-history.sqlite"


def default_history_target() -> str:
    """``$ROBOCAL_HISTORY_DB`` if set, else ``robocal-history.sqlite`` in the working folder."""
    return os.environ.get(HISTORY_DB_ENV) or DEFAULT_HISTORY_DB


__all__ = [
    "ALLOWED_UNITS", "CYCLE_KINDS", "CYCLE_STATUSES", "CycleRecord", "CycleWriter", "DEFAULT_HISTORY_DB",
    "HISTORY_DB_ENV", "HistoryBusyError", "HistoryError", "HistoryInputError", "HistoryLookupError", "HistoryStore",
    "ParameterRow", "Quantity", "SCHEMA_VERSION", "Series", "StoredCycle", "UnknownRobotError",
    "default_history_target", "redact_url", "PASSWORD_ENV", "PASSWORD_FILE_ENV", "strip_credentials", "url_password",
    "with_credentials",
]
