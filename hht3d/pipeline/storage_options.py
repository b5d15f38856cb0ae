"""The pipeline's ``storage_options:`` block: options of the fsspec back-end of URL inputs and outputs.

It holds what the back-end needs besides credentials, e.g. an endpoint,
a region or anonymous access::

    storage_options:
      client_kwargs: {endpoint_url: https://s3.example.org, region_name: eu-west-1}

Credentials never come from a pipeline file: the back-ends read them from
their usual places (``AWS_ACCESS_KEY_ID``/``AWS_SECRET_ACCESS_KEY``,
``~/.aws/credentials``, ``GOOGLE_APPLICATION_CREDENTIALS``,
``AZURE_STORAGE_*``, instance roles), so a key that names a secret is refused.
"""

from __future__ import annotations

from ..errors import PipelineError, shown
from ..redaction import is_secret_name, remember_secrets
from .document import at

__all__ = ["storage_options"]


def storage_options(doc: dict) -> dict:
    """The checked ``storage_options`` of a pipeline document (``{}`` if absent).

    Raises
    ------
    PipelineError
        Not a mapping, or a key (at any depth) that names a credential.
    """
    block = doc.get("storage_options")
    if block is None:
        return {}
    if not isinstance(block, dict):
        raise PipelineError(
            f"{at(doc, 'storage_options')}: storage_options must be a mapping of fsspec options, got {shown(block)}"
        )
    remember_secrets(block)
    _no_credentials(block, "storage_options")
    return dict(block)


def _no_credentials(block: dict, dotted: str) -> None:
    for key, value in block.items():
        if is_secret_name(key) and not isinstance(value, dict):
            raise PipelineError(
                f"{at(block, key)}: {dotted}.{key}: credentials do not belong in a pipeline "
                "file; remove it and give them through the environment (e.g. "
                "AWS_ACCESS_KEY_ID, AWS_SECRET_ACCESS_KEY), the back-end's config file or an "
                "instance role"
            )
        if isinstance(value, dict):
            _no_credentials(value, f"{dotted}.{key}")
