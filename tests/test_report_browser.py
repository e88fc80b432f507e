"""The report as a reader sees it (issue 22): rendered by headless Chromium, a click on a
header sorts the table, the failure thumbnails load; the example report in docs/ is the current
page's (sortable tables, failure thumbnails) and its screenshot is committed beside it.

The browser test needs Debian's ``chromium`` and ``chromium-driver`` and ``selenium`` (dev
extra); without them it is skipped, saying which is missing.
"""

from __future__ import annotations

import re
import shutil
import subprocess
import sys
from pathlib import Path
from typing import Any

import cv2
import pytest

ROOT = Path(__file__).resolve().parent.parent


def _browser() -> tuple[str, str]:
    pytest.importorskip("selenium", reason="selenium is not installed (pip install -e '.[dev]')")
    binary = next(filter(None, map(shutil.which, ("chromium", "chromium-browser"))), None)
    driver = shutil.which("chromedriver")
    if binary is None or driver is None:
        pytest.skip("no headless browser: install Debian's chromium and chromium-driver "
                    "packages (apt-get install chromium chromium-driver)")
    return binary, driver


@pytest.fixture(scope="module")
def report(clip_factory, tmp_path_factory: pytest.TempPathFactory) -> Path:
    root = tmp_path_factory.mktemp("browser-report")
    folder = root / "in"
    folder.mkdir()
    for scenario in ("leave_return", "smooth"):
        clip = clip_factory(scenario, frames=90)
        shutil.copy(clip.path, folder / f"{scenario}.mp4")
        shutil.copy(clip.gt, folder / f"{scenario}.gt.txt")
    for command in (["batch", str(folder), "-c", "s0", "-c", "s1", "-c", "robust", "--jobs",
                     "1", "--no-video", "-q", "--out", str(root / "results")],
                    ["report", str(root / "results"), "-q", "--out", str(root / "report")]):
        done = subprocess.run([sys.executable, "-m", "vtrack", *command], capture_output=True,
                              text=True, timeout=300, check=False)
        assert done.returncode == 0, done.stderr
    return root / "report"


def _open(page: Path, tmp_path: Path) -> tuple[Any, Any]:
    """Headless Chromium in a 1400x1000 window showing ``page``; returns the driver and
    selenium's ``By``."""
    binary, driver_path = _browser()
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service
    from selenium.webdriver.common.by import By

    options = webdriver.ChromeOptions()
    options.binary_location = binary
    for flag in ("--headless", "--no-sandbox", "--disable-gpu", "--no-first-run",
                 "--window-size=1400,1000", f"--user-data-dir={tmp_path / 'profile'}"):
        options.add_argument(flag)
    browser = webdriver.Chrome(service=Service(driver_path), options=options)
    browser.get(page.as_uri())
    return browser, By


def test_a_click_sorts_the_table_and_the_failure_thumbnails_load(report: Path,
                                                                  tmp_path: Path) -> None:
    browser, By = _open(report / "index.html", tmp_path)
    from selenium.webdriver.support.ui import WebDriverWait
    try:
        table = browser.find_element(By.CSS_SELECTOR, "#results + .scroll table")
        headers = table.find_elements(By.TAG_NAME, "th")
        column = [h.text for h in headers].index("AUC")

        def auc_column() -> list[float]:
            rows = table.find_elements(By.CSS_SELECTOR, "tbody tr")
            return [float(r.find_elements(By.TAG_NAME, "td")[column].text) for r in rows]

        before = auc_column()
        headers[column].click()
        assert auc_column() == sorted(before)
        headers[column].click()
        assert auc_column() == sorted(before, reverse=True)
        assert headers[column].get_attribute("data-dir") == "desc"
        thumbnails = [i for i in browser.find_elements(By.TAG_NAME, "img")
                      if "failures_" in i.get_attribute("src")]
        assert thumbnails
        for image in thumbnails:  # loading="lazy": each loads once scrolled into view
            browser.execute_script("arguments[0].scrollIntoView()", image)
            WebDriverWait(browser, 20).until(
                lambda b, image=image: b.execute_script("return arguments[0].complete", image))
            assert browser.execute_script("return arguments[0].naturalWidth", image) > 600
        browser.execute_script("window.scrollTo(0, 0)")
        # the page fits a 1400 px window: nothing wider than the body
        assert browser.execute_script(
            "return document.documentElement.scrollWidth <= window.innerWidth")
        shot = tmp_path / "shot.png"
        browser.save_screenshot(str(shot))
        assert cv2.imread(str(shot)).std() > 10  # a page was drawn, not a blank
    finally:
        browser.quit()


@pytest.fixture(scope="module")
def multi_report(clip_factory, tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A report of multi-target runs (three configs on one clip with MOTChallenge ground
    truth) beside a single-target one."""
    root = tmp_path_factory.mktemp("browser-multi-report")
    folder = root / "in"
    folder.mkdir()
    multi = clip_factory("multi", frames=90)
    shutil.copy(multi.path, folder / "multi.mp4")
    shutil.copy(multi.mot, folder / "multi.mot.txt")
    for command in (["batch", str(folder), "-c", "s3", "-c", "s4_multi", "-c", "fixed_camera",
                     "--jobs", "1", "--no-video", "-q", "--out", str(root / "results")],
                    ["report", str(root / "results"), "-q", "--out", str(root / "report")]):
        done = subprocess.run([sys.executable, "-m", "vtrack", *command], capture_output=True,
                              text=True, timeout=300, check=False)
        assert done.returncode == 0, done.stderr
    return root / "report"


def test_the_multi_target_table_fits_a_1400_px_window_and_sorts(multi_report: Path,
                                                                 tmp_path: Path) -> None:
    """Issue 22: the multi-target table overflowed a 1400 px window. In headless Chromium at
    1400 px it fits: no horizontal scrolling of the page nor of the table's own box, and a
    click on a header sorts it."""
    browser, By = _open(multi_report / "index.html", tmp_path)
    try:
        table = browser.find_element(By.CSS_SELECTOR, "#multi-target + .scroll table")
        box = browser.find_element(By.CSS_SELECTOR, "#multi-target + .scroll")
        assert browser.execute_script(
            "return document.documentElement.scrollWidth <= window.innerWidth")
        assert browser.execute_script(
            "return arguments[0].scrollWidth <= arguments[0].clientWidth", box)
        headers = table.find_elements(By.TAG_NAME, "th")
        titles = [h.text for h in headers]
        assert {"MOTA", "IDF1"} <= set(titles), titles
        column = titles.index("MOTA")

        def mota() -> list[float]:
            rows = table.find_elements(By.CSS_SELECTOR, "tbody tr")
            return [float(r.find_elements(By.TAG_NAME, "td")[column].text) for r in rows]

        before = mota()
        assert len(before) == 3
        headers[column].click()
        assert mota() == sorted(before)
        headers[column].click()
        assert mota() == sorted(before, reverse=True)
    finally:
        browser.quit()


def test_the_example_report_in_docs_is_the_current_page() -> None:
    page = (ROOT / "docs" / "example-report" / "index.html").read_text()
    assert '<table class="sortable">' in page and "<script>" in page
    thumbnails = re.findall(r'src="(plots/failures_[^"]+\.png)"', page)
    assert thumbnails
    for path in thumbnails:
        assert (ROOT / "docs" / "example-report" / path).is_file(), path
    screenshot = cv2.imread(str(ROOT / "docs" / "report-screenshot.png"))
    assert screenshot is not None and screenshot.shape[1] >= 1000
