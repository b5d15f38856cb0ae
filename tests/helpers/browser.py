"""Debian's chromium driven by Playwright, for the browser tests (marker ``browser``).

``bash .ci/setup`` installs chromium (as root) and the dev extra playwright; the tests skip
where either is missing, except in CI, where a missing chromium fails.
"""

from __future__ import annotations

import os
import shutil

import pytest

CHROMIUM_ARGS = [
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
]


def headless_chromium():
    """Yield a headless chromium ``Browser`` (a generator for a fixture); skip without one."""
    sync_api = pytest.importorskip("playwright.sync_api", reason="playwright (the dev extra) drives chromium")
    executable = shutil.which("chromium")
    if executable is None:
        message = "Debian's chromium is not installed; `bash .ci/setup` installs it (as root)"
        if os.environ.get("CI"):
            pytest.fail(message)
        pytest.skip(message)
    with sync_api.sync_playwright() as playwright:
        chromium = playwright.chromium.launch(executable_path=executable, args=CHROMIUM_ARGS, headless=True)
        yield chromium
        chromium.close()
