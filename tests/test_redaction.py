"""Secrets out of every message (hht3d.redaction), in every form a message can carry them.

The oracle of "found" is tests/helpers/secrets.py, which computes the forms (letter case, URL
encoding, base64) independently; every case is checked twice: the secret is found in the raw
text (the search works), and in no form once redacted.
"""

from __future__ import annotations

import base64
from urllib.parse import quote

import pytest

from helpers.secrets import forms_found
from hht3d.errors import shown
from hht3d.redaction import is_secret_name, redact, remember_secrets

SECRET = "wJalrXUtnFEMI+K7MDENG/bPxRfiCYzEXAMPLE"
KEY_ID = "AKIAIOSFODNN7EXAMPLE"
#: Never remembered: only its place in the text (a query value, a URL password) can give it away.
UNSEEN = "p4ssw0rdNeverRemembered42"


@pytest.fixture(autouse=True, scope="module")
def remembered():
    remember_secrets({"key": KEY_ID, "secret": SECRET})


CASES = {
    "as given": f"denied for {SECRET}",
    "lower-cased message": f"unknown extension '.ply?awsaccesskeyid={KEY_ID.lower()}&signature={SECRET.lower()}'",
    "upper-cased": f"ERROR {SECRET.upper()}",
    "url-encoded": f"GET /x.ply?X-Amz-Credential={quote(KEY_ID)}%2F20261203&X-Amz-Signature={quote(SECRET, safe='')}",
    "base64": f"Authorization: Basic {base64.b64encode(SECRET.encode()).decode()}",
    "userinfo": f"s3://{KEY_ID}:{SECRET}@bucket/scan.ply",
}
UNSEEN_CASES = {
    "query without a scheme": f"unknown extension '.ply?signature={UNSEEN.lower()}&expires=1'",
    "signed URL": f"https://b.example/x.ply?X-Amz-Signature={UNSEEN}&X-Amz-Expires=60",
    "userinfo": f"s3://{KEY_ID}:{UNSEEN}@bucket/scan.ply",
}


@pytest.mark.parametrize("text", CASES.values(), ids=CASES)
def test_a_secret_in_any_form_is_redacted(text):
    secret = KEY_ID if "Credential" in text and SECRET not in text else SECRET
    assert forms_found(text, secret), "the search must find it in the raw text"
    assert forms_found(redact(text), SECRET) == [] and forms_found(redact(text), KEY_ID) == []


@pytest.mark.parametrize("text", UNSEEN_CASES.values(), ids=UNSEEN_CASES)
def test_an_unseen_secret_is_redacted_by_its_place(text):
    """A signature or password hht3d never saw (a signed URL pasted as an input) is blanked where
    it stands: a query value, with or without the URL before it, or a URL's password."""
    assert forms_found(text, UNSEEN) and not forms_found(redact(text), UNSEEN)


def test_a_long_url_is_redacted_before_it_is_cut():
    """A value shown in a message is cut to 80 characters; a password before an '@' that the cut
    would drop must not survive."""
    password = "hunter2pw"
    url = f"https://user:{password}@{'very-long-host-name.' * 8}example.org/scan.ply"
    assert forms_found(url, password) and not forms_found(shown(url), password)


@pytest.mark.parametrize(
    "name, secret",
    [
        ("secret", True),
        ("aws_secret_access_key", True),
        ("token", True),
        ("signature_version", False),
        ("key_file", False),
        ("endpoint_url", False),
    ],
)
def test_which_option_names_hold_secrets(name, secret):
    """``config_kwargs.signature_version: UNSIGNED`` (anonymous access) is a setting, not a credential."""
    assert is_secret_name(name) == secret
