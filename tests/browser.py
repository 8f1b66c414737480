"""Debian's Chromium through Playwright, for the tests that need a real browser.

``chromium_or_skip()`` returns the browser's path, or skips the calling test module with the
reason (a failure instead when ``COURSE_REQUIRE_BROWSER`` is set, as ``.ci/run`` does: there a
missing browser is a broken install, not a reason to skip). ``jupyterlab(folder, home)`` serves
a folder in a real JupyterLab, and ``run_cell`` runs a notebook cell there.
"""

from __future__ import annotations

import contextlib
import os
import secrets
import shutil
import socket
import subprocess
import sys
import time
import urllib.request
from pathlib import Path

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


@contextlib.contextmanager
def jupyterlab(folder: Path, home: Path):
    """JupyterLab serving ``folder`` on a free local port, with a fresh config in ``home`` (no
    restored layout, no news prompt); yields ``(base_url, token)``. Its log is
    ``folder/lab.log``; a server that does not start fails the test with the log."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    token = secrets.token_hex(16)
    command = [
        sys.executable,
        "-m",
        "jupyterlab",
        "--no-browser",
        f"--port={port}",
        "--ip=127.0.0.1",
        f"--IdentityProvider.token={token}",
        f"--ServerApp.root_dir={folder}",
        "--LabApp.news_url=",  # no "get notified about Jupyter news?" prompt over the page
    ]
    if hasattr(os, "geteuid") and os.geteuid() == 0:
        command.append("--allow-root")
    env = {**os.environ, "JUPYTER_CONFIG_DIR": str(home / "config"), "MPLBACKEND": "Agg"}
    log = (folder / "lab.log").open("w")
    server = subprocess.Popen(command, stdout=log, stderr=subprocess.STDOUT, env=env)
    base = f"http://127.0.0.1:{port}"
    try:
        deadline = time.monotonic() + 90
        while True:
            try:
                urllib.request.urlopen(f"{base}/api/status?token={token}", timeout=2).close()
                break
            except OSError:
                if server.poll() is not None or time.monotonic() > deadline:
                    log.flush()
                    pytest.fail(f"JupyterLab did not start:\n{(folder / 'lab.log').read_text()}")
                time.sleep(0.5)
        yield base, token
    finally:
        server.terminate()
        try:
            server.wait(15)
        except subprocess.TimeoutExpired:
            server.kill()
        log.close()


def run_cell(page, sync_api, cell: str = ".jp-CodeCell") -> None:
    """Run the notebook cell ``cell`` (a selector) in JupyterLab: Lab drops a run request made
    before its kernel connection is up (the cell stays ``[ ]``) or asks which kernel to start
    (a dialog, accepted with its default), so run it again until it has started."""
    # the kernel is up: the toolbar's execution indicator says idle, in JupyterLab and in
    # Notebook 7 (should a version show it otherwise, the attempts below still run the cell)
    with contextlib.suppress(sync_api.TimeoutError):
        page.wait_for_selector(
            '.jp-Notebook-ExecutionIndicator[data-status="idle"]', state="attached", timeout=60_000
        )
    for _attempt in range(6):
        dialog = page.locator(".jp-Dialog .jp-mod-accept")
        if dialog.count():
            dialog.first.click()
        page.locator(f"{cell} .jp-InputArea-editor").first.click()
        page.keyboard.press("Shift+Enter")
        try:
            page.wait_for_function(
                "([sel]) => /\\[(\\*|\\d+)\\]/.test(document.querySelector("
                "sel + ' .jp-InputPrompt').textContent)",
                arg=[cell],
                timeout=10_000,
            )
            return
        except sync_api.TimeoutError:
            continue
    raise AssertionError(f"JupyterLab never started the cell {cell}")
