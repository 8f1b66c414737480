"""Debian's Chromium through Playwright, for the tests that need a real browser.

``chromium_or_skip()`` returns the browser's path, or skips the calling test module with the
reason (a failure instead when ``COURSE_REQUIRE_BROWSER`` is set, as ``.ci/run`` does: there a
missing browser is a broken install, not a reason to skip).
"""

from __future__ import annotations

import os
import shutil

import pytest

# Chromium on a machine without network: no background connections, no GPU, no sandbox (root).
CHROMIUM_ARGS = [
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
]


def chromium_or_skip() -> str:
    """The path of Chromium (``COURSE_CHROMIUM`` or ``chromium`` on PATH), else skip the module."""
    chromium = os.environ.get("COURSE_CHROMIUM") or shutil.which("chromium") or ""
    if not chromium:
        reason = "no Chromium installed (apt-get install chromium, or set COURSE_CHROMIUM)"
        if os.environ.get("COURSE_REQUIRE_BROWSER"):  # set by .ci/run, which installs one
            pytest.fail(reason, pytrace=False)
        pytest.skip(reason, allow_module_level=True)
    return chromium
