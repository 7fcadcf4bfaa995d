"""Database credentials stay out of task payloads, logs, JSON and errors (issue 29).

* :func:`redact_url` masks a password in ``user:pass@host`` and in the query string
  (``?password=...``, ``sslpassword``, ``passwd``, ``pwd``, ``secret``, ``token``) for every
  message, report and JSON file.
* :func:`strip_credentials` removes them from a URL that travels (a Dask task's arguments).
* :func:`with_credentials` puts the password back where the database is opened: from the
  environment variable ``ROBOCAL_DB_PASSWORD``, or from the file named by
  ``ROBOCAL_DB_PASSWORD_FILE`` (a file on the worker, readable by its user only).
"""

from __future__ import annotations

import os
from pathlib import Path
from urllib.parse import parse_qsl, quote, unquote, urlencode, urlsplit, urlunsplit

__all__ = ["PASSWORD_ENV", "PASSWORD_FILE_ENV", "SECRET_QUERY_KEYS", "redact_url", "strip_credentials",
           "url_password", "with_credentials"]

PASSWORD_ENV = "ROBOCAL_DB_PASSWORD"
PASSWORD_FILE_ENV = "ROBOCAL_DB_PASSWORD_FILE"
#: Query-string keys whose values are secrets (case-insensitive).
SECRET_QUERY_KEYS = frozenset({"password", "passwd", "pwd", "sslpassword", "secret", "token", "api_key", "apikey"})


def _split(url: str):
    try:
        parts = urlsplit(url)
        _ = parts.port  # a malformed port raises here
        return parts
    except ValueError:
        return None


def _host(parts) -> str:
    host = parts.hostname or ""
    if ":" in host:  # IPv6
        host = f"[{host}]"
    return host + (f":{parts.port}" if parts.port is not None else "")


def _query(parts, replace):
    pairs = parse_qsl(parts.query, keep_blank_values=True)
    return urlencode([(k, replace(v) if k.lower() in SECRET_QUERY_KEYS else v) for k, v in pairs], safe="*:/")


def url_password(url: str) -> str | None:
    """The password a URL carries (in its user part or its query string), or None."""
    parts = _split(url) if isinstance(url, str) and "://" in url else None
    if parts is None:
        return None
    if parts.password is not None:
        return unquote(parts.password)
    for k, v in parse_qsl(parts.query, keep_blank_values=True):
        if k.lower() in SECRET_QUERY_KEYS:
            return v
    return None


def redact_url(url: str) -> str:
    """The URL with any password replaced by ``***`` (for messages, reports and JSON)."""
    parts = _split(url) if isinstance(url, str) and "://" in url else None
    if parts is None or url_password(url) is None:
        return url
    netloc = parts.netloc
    if parts.password is not None:
        netloc = f"{parts.username or ''}:***@{_host(parts)}"
    return urlunsplit((parts.scheme, netloc, parts.path, _query(parts, lambda v: "***"), parts.fragment))


def strip_credentials(url: str) -> str:
    """The URL without its password (user part and secret query keys): what may travel to workers."""
    parts = _split(url) if isinstance(url, str) and "://" in url else None
    if parts is None or url_password(url) is None:
        return url
    netloc = parts.netloc
    if parts.password is not None:
        netloc = (f"{parts.username}@" if parts.username else "") + _host(parts)
    pairs = [(k, v) for k, v in parse_qsl(parts.query, keep_blank_values=True) if k.lower() not in SECRET_QUERY_KEYS]
    return urlunsplit((parts.scheme, netloc, parts.path, urlencode(pairs), parts.fragment))


def with_credentials(url: str) -> str:
    """``url`` with the password from ``ROBOCAL_DB_PASSWORD`` or the file ``ROBOCAL_DB_PASSWORD_FILE``
    when it names a user but carries no password; otherwise unchanged."""
    parts = _split(url) if isinstance(url, str) and "://" in url else None
    if parts is None or url_password(url) is not None or not parts.username:
        return url
    secret = os.environ.get(PASSWORD_ENV)
    if secret is None and os.environ.get(PASSWORD_FILE_ENV):
        try:
            secret = Path(os.environ[PASSWORD_FILE_ENV]).read_text(encoding="utf-8").strip()
        except OSError as exc:
            raise OSError(f"{PASSWORD_FILE_ENV}={os.environ[PASSWORD_FILE_ENV]}: cannot read the database "
                          f"password: {exc.strerror or exc}") from None
    if not secret:
        return url
    netloc = f"{quote(parts.username, safe='')}:{quote(secret, safe='')}@{_host(parts)}"
    return urlunsplit((parts.scheme, netloc, parts.path, parts.query, parts.fragment))
