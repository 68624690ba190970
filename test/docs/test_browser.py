"""The pages of the built site as a reader sees them, in Debian's headless Chromium, one
browser for every page: no error on the console and every image loaded on each page; a
screenshot that is not blank of each page but FORD's ~400 API pages
(builtsite.is_generated_api: a screenshot costs more than the rest of a page's checks, and
those pages share a few templates). The screenshots are kept in build/docs-screenshots/ to
be looked at."""

from __future__ import annotations

import io
import shutil
from pathlib import Path

import pytest

from builtsite import ROOT, is_generated_api, pages, served

SHOTS = ROOT / "build" / "docs-screenshots"
# the number of colours below which a screenshot counts as blank
MIN_COLOURS = 2
# how often a wait looks again (selenium polls every 0.5 s by default)
POLL_SECONDS = 0.02


@pytest.fixture(scope="module")
def browser():
    webdriver = pytest.importorskip("selenium.webdriver")
    from selenium.webdriver.chrome.service import Service

    driver_path = shutil.which("chromedriver")
    browser_path = shutil.which("chromium")
    assert driver_path and browser_path, "chromium and chromium-driver (make docs-deps)"
    options = webdriver.ChromeOptions()
    options.binary_location = browser_path
    for arg in ("--headless=new", "--no-sandbox", "--disable-gpu", "--window-size=1280,1000",
                "--disable-dev-shm-usage"):
        options.add_argument(arg)
    options.set_capability("goog:loggingPrefs", {"browser": "ALL"})
    driver = webdriver.Chrome(service=Service(driver_path), options=options)
    driver.set_page_load_timeout(60)
    yield driver
    driver.quit()


@pytest.fixture(scope="module")
def base_url():
    with served() as url:
        yield url


IMAGES = """
return Array.from(document.images).map(i => [i.currentSrc || i.src, i.complete, i.naturalWidth]);
"""
MATH_DONE = """
return !window.MathJax || !MathJax.startup || !MathJax.startup.promise || (MathJax.startup.promise.then(() => { window.__typeset = true; }), window.__typeset === true);
"""


def _wait(driver, script: str, seconds: float = 20) -> None:
    from selenium.webdriver.support.ui import WebDriverWait
    WebDriverWait(driver, seconds, poll_frequency=POLL_SECONDS).until(
        lambda d: d.execute_script(script))


def _colours(png: bytes) -> int:
    from PIL import Image
    with Image.open(io.BytesIO(png)) as image:
        return len(image.convert("RGB").getcolors(maxcolors=1 << 24) or [])


@pytest.mark.parametrize("page", pages(), ids=str)
def test_page(browser, base_url: str, page: Path) -> None:
    browser.get_log("browser")                     # what earlier pages left
    browser.get(base_url + page.as_posix())
    _wait(browser, "return document.readyState === 'complete'")
    _wait(browser, "return Array.from(document.images).every(i => i.complete)")
    _wait(browser, MATH_DONE)
    errors = [e["message"] for e in browser.get_log("browser") if e["level"] == "SEVERE"]
    assert not errors, f"{page}: console errors: {errors}"
    broken = [src for src, complete, width in browser.execute_script(IMAGES) if width == 0]
    assert not broken, f"{page}: images not loaded: {broken}"
    if is_generated_api(page):
        return
    png = browser.get_screenshot_as_png()
    shot = SHOTS / page.with_suffix(".png")
    shot.parent.mkdir(parents=True, exist_ok=True)
    shot.write_bytes(png)
    assert _colours(png) >= MIN_COLOURS, f"{page}: the screenshot is blank ({shot})"
