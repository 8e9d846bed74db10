"""The editor served on the half-size sample character, and a Chromium page open on it, for the
browser tests (Playwright and Debian's headless Chromium).

Without Chromium these tests skip, except under CI=true, where a missing browser is a failure
(`make test` installs it when run as root).
"""

from __future__ import annotations

import os

import pytest

from toonmotion import api
from toonmotion.rig.pipeline import rig_drawing
from toonmotion.samples import sample_character
from toonmotion.testing.browser import CHROMIUM_ARGS, chromium_path
from toonmotion.web.background import serving


def _chromium():
    found = chromium_path()
    if found is None:
        if os.environ.get("CI") == "true":
            pytest.fail(
                "Debian's chromium is missing under CI; make test installs it (apt-get install chromium)"
            )
        pytest.skip("the editor's browser tests need Debian's chromium (apt-get install chromium)")
    return found


@pytest.fixture(scope="module")
def editor(tmp_path_factory):
    """The editor serving the half-size sample character: ``(url, project folder)``."""
    drawing, skeleton = sample_character(scale=0.5)
    folder = tmp_path_factory.mktemp("editor") / "hero"
    api.save_project(folder, rig_drawing(drawing, skeleton=skeleton))
    with serving(folder) as served:
        yield served.page, folder


@pytest.fixture(scope="module")
def page(editor):
    executable = _chromium()
    from playwright.sync_api import sync_playwright

    with sync_playwright() as playwright:
        browser = playwright.chromium.launch(executable_path=executable, args=list(CHROMIUM_ARGS))
        page = browser.new_page(viewport={"width": 1280, "height": 800})
        errors: list[str] = []
        page.on("pageerror", lambda error: errors.append(str(error)))
        page.goto(editor[0])
        page.wait_for_function("document.getElementById('status').textContent === 'ready'", timeout=30_000)
        page.errors = errors
        yield page
        browser.close()
