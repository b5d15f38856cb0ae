"""Finding a secret in every form it can take in printed or written text.

Independent of :mod:`hht3d.redaction`: the forms are computed here, from the standard library,
so that a test using :func:`forms_found` would catch a form the package forgot.
"""

from __future__ import annotations

import base64
from urllib.parse import quote, quote_plus


def secret_forms(secret: str) -> dict[str, str]:
    """The forms of ``secret``, by name, all lower-cased (searches ignore letter case)."""
    raw = secret.encode()
    forms = {
        "as given": secret,
        "url-encoded": quote(secret, safe=""),
        "form-encoded": quote_plus(secret),
        "base64": base64.b64encode(raw).decode(),
        "base64 url-safe": base64.urlsafe_b64encode(raw).decode(),
        "base64 unpadded": base64.b64encode(raw).decode().rstrip("="),
    }
    return {name: form.lower() for name, form in forms.items()}


def forms_found(text, secret: str) -> list[str]:
    """The names of the forms of ``secret`` that ``text`` (str or bytes) holds, ignoring letter case."""
    if isinstance(text, bytes):
        text = text.decode("latin-1")
    text = text.lower()
    return [name for name, form in secret_forms(secret).items() if form in text]
