"""Debian's Chromium driven by Playwright's Python API: what the browser tests (tests/test_browser.py, the term on
the hub in tests/test_hub.py) share.

``.ci/run`` installs ``chromium``; where it is absent, ``needs_chromium`` skips the test with a message. Screenshots
go to ``tests/_screenshots/`` (git-ignored).
"""

from __future__ import annotations

import contextlib
import shutil

import pytest

from conftest import ROOT

CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
CHROMIUM_ARGS = [
    "--no-sandbox",
    "--disable-gpu",
    "--disable-dev-shm-usage",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--no-first-run",
    "--disable-quic",
]
SHOTS = ROOT / "tests" / "_screenshots"
needs_chromium = pytest.mark.skipif(
    CHROMIUM is None,
    reason="no chromium on this machine: the browser test needs Debian's chromium (apt-get install chromium)",
)


@contextlib.contextmanager
def chromium():
    """A headless Chromium (Playwright's ``Browser``), closed on the way out."""
    from playwright.sync_api import sync_playwright

    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path=CHROMIUM, headless=True, args=CHROMIUM_ARGS)
        try:
            yield browser
        finally:
            browser.close()


def screenshot(page_or_locator, name):
    """Save a screenshot as ``tests/_screenshots/<name>.png``; returns its path."""
    SHOTS.mkdir(exist_ok=True)
    path = SHOTS / f"{name}.png"
    page_or_locator.screenshot(path=str(path))
    return path
