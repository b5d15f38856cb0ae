"""Keeping credentials out of everything hht3d prints or writes.

:func:`redact` blanks, in any text:

* the values of secret-looking ``storage_options`` seen in this process
  (:func:`remember_secrets`: keys, secrets, tokens, passwords, SAS and
  connection strings, at any depth) and of secret-looking environment
  variables (``AWS_SECRET_ACCESS_KEY``, ``AZURE_STORAGE_SAS_TOKEN``, ...), in
  every form a message may carry them: any letter case, URL-encoded or
  decoded, base64;
* the values of query parameters, in URLs and wherever a ``?name=value``
  appears (signed URLs carry their signature, credential and token there; a
  message may quote the query alone, or lower-cased);
* the password of ``scheme://user:password@host``.

:func:`hht3d.errors.one_line`, through which every message, summary error
and progress line passes, applies it.

Examples
--------
>>> remember_secrets({"key": "AKIDEXAMPLE", "client_kwargs": {"endpoint_url": "http://127.0.0.1:9000"}})
>>> redact("denied for AKIDEXAMPLE at https://b.example/x.ply?X-Amz-Signature=abc&X-Amz-Expires=60")
'denied for *** at https://b.example/x.ply?X-Amz-Signature=***&X-Amz-Expires=***'
"""

from __future__ import annotations

import base64
import os
import re
from typing import Any
from urllib.parse import quote, unquote

__all__ = ["SECRET_NAME", "NOT_SECRET", "is_secret_name", "remember_secrets", "secret_forms", "redact"]

#: Names (of options and environment variables) whose values are secrets.
SECRET_NAME = re.compile(
    r"secret|token|passw|credential|signature|sas|connection_string|account_key|"
    r"key",
    re.IGNORECASE,
)
#: Names that match :data:`SECRET_NAME` but hold settings, not secrets (``signature_version: s3v4``).
NOT_SECRET = re.compile(r"_version$|_file$|_path$", re.IGNORECASE)
#: Shorter values are not blanked (they would blank ordinary words).
MIN_SECRET = 6
MASK = "***"
_QUERY = re.compile(r"(?<=[?&])([A-Za-z0-9_.\-]+)=[^&\s'\"<>]*")
_QUERIES = re.compile(r"\?[A-Za-z0-9_.\-]+=[^\s'\"<>]*")
_USERINFO = re.compile(r"(\b[a-z][a-z0-9+.\-]*://[^\s/:@'\"]*):[^\s/@'\"]+@", re.IGNORECASE)
_seen: set[str] = set()


def is_secret_name(name: object) -> bool:
    """Whether an option or environment variable called ``name`` holds a secret."""
    return bool(SECRET_NAME.search(str(name))) and not NOT_SECRET.search(str(name))


def remember_secrets(options: Any) -> None:
    """Record the secret-looking values of ``options`` (a nested ``storage_options`` mapping)."""
    if not isinstance(options, dict):
        return
    for name, value in options.items():
        if isinstance(value, dict):
            remember_secrets(value)
        elif isinstance(value, str) and len(value) >= MIN_SECRET and is_secret_name(name):
            _seen.add(value)


def _environment_secrets() -> set[str]:
    return {v for k, v in os.environ.items() if len(v) >= MIN_SECRET and is_secret_name(k)}


def secret_forms(secret: str) -> set[str]:
    """The texts that carry ``secret``: as given, URL-encoded and decoded, base64 (standard and URL-safe)."""
    raw = secret.encode()
    return {
        secret,
        quote(secret, safe=""),
        unquote(secret),
        base64.b64encode(raw).decode(),
        base64.urlsafe_b64encode(raw).decode(),
        base64.b64encode(raw).decode().rstrip("="),
    }


def redact(text: object) -> str:
    """``text`` with known secrets (in any form), query values and URL passwords replaced by ``***``."""
    text = str(text)
    forms = {form for secret in _seen | _environment_secrets() for form in secret_forms(secret)}
    for form in sorted(forms, key=len, reverse=True):
        text = re.sub(re.escape(form), MASK, text, flags=re.IGNORECASE)
    text = _QUERIES.sub(lambda m: _QUERY.sub(lambda q: f"{q.group(1)}={MASK}", m.group(0)), text)
    return _USERINFO.sub(rf"\1:{MASK}@", text)
