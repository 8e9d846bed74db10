"""Headless Chromium for the editor's browser tests and benchmark (Playwright drives Debian's
``chromium``; nothing is downloaded)."""

from __future__ import annotations

import shutil

# The flags this machine's closed network and a root user need: no sandbox (root), no GPU (WebGL
# through SwiftShader), nothing fetched in the background.
CHROMIUM_ARGS = (
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--use-angle=swiftshader",
    "--enable-unsafe-swiftshader",
)


def chromium_path() -> str | None:
    """Debian's Chromium on the PATH, or None."""
    return shutil.which("chromium") or shutil.which("chromium-browser")
