"""Keeping credentials out of everything hht3d prints or writes.

:func:`redact` blanks, in any text:

* the values of secret-looking ``storage_options`` seen in this process
  (:func:`remember_secrets`: keys, secrets, tokens, passwords, SAS and
  connection strings, at any depth);
* the values of secret-looking environment variables (``AWS_SECRET_ACCESS_KEY``,
  ``AZURE_STORAGE_SAS_TOKEN``, ...);
* the query parameters of URLs (signed URLs carry their signature, credential
  and token there) and the password of ``scheme://user:password@host``.

:func:`hht3d.errors.one_line`, through which every message, summary error
and progress line passes, applies it.

Examples
--------
>>> remember_secrets({"key": "AKIDEXAMPLE", "client_kwargs": {"endpoint_url": "http://127.0.0.1:9000"}})
>>> redact("denied for AKIDEXAMPLE at https://b.example/x.ply?X-Amz-Signature=abc&X-Amz-Expires=60")
'denied for *** at https://b.example/x.ply?X-Amz-Signature=***&X-Amz-Expires=***'
"""
from __future__ import annotations

import os
import re

__all__ = ["SECRET_NAME", "remember_secrets", "redact"]

#: Names (of options and environment variables) whose values are secrets.
SECRET_NAME = re.compile(r"secret|token|passw|credential|signature|sas|connection_string|account_key|"
                         r"key", re.IGNORECASE)
#: Shorter values are not blanked (they would blank ordinary words).
MIN_SECRET = 6
MASK = "***"
_QUERY = re.compile(r"(?<=[?&])([A-Za-z0-9_.\-]+)=[^&\s'\"<>]*")
_URL_QUERY = re.compile(r"\b[a-z][a-z0-9+.\-]*://[^\s'\"<>?]*\?[^\s'\"<>]*", re.IGNORECASE)
_USERINFO = re.compile(r"(\b[a-z][a-z0-9+.\-]*://[^\s/:@'\"]+):[^\s/@'\"]+@", re.IGNORECASE)
_seen: set[str] = set()


def remember_secrets(options) -> None:
    """Record the secret-looking values of ``options`` (a nested ``storage_options`` mapping)."""
    if not isinstance(options, dict):
        return
    for name, value in options.items():
        if isinstance(value, dict):
            remember_secrets(value)
        elif isinstance(value, str) and len(value) >= MIN_SECRET and SECRET_NAME.search(str(name)):
            _seen.add(value)


def _environment_secrets() -> set[str]:
    return {v for k, v in os.environ.items() if len(v) >= MIN_SECRET and SECRET_NAME.search(k)
            and not k.endswith(("_FILE", "_PATH"))}


def redact(text: str) -> str:
    """``text`` with known secrets, URL query values and URL passwords replaced by ``***``."""
    text = str(text)
    for secret in sorted(_seen | _environment_secrets(), key=len, reverse=True):
        text = text.replace(secret, MASK)
    text = _URL_QUERY.sub(lambda m: _QUERY.sub(lambda q: f"{q.group(1)}={MASK}", m.group(0)), text)
    return _USERINFO.sub(rf"\1:{MASK}@", text)
