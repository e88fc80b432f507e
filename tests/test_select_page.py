"""What ``vtrack select``'s page shows is what it writes: its frames are numbered as the input
numbers them (as ``vtrack frame --at`` and ``vtrack run --start`` count), and a box typed into
its field is the box confirmed. The browser test drives a real headless Chromium; it is skipped,
saying what is missing, without Debian's chromium and chromium-driver and selenium.
"""

from __future__ import annotations

import json
import signal
import subprocess
import sys
import urllib.error
import urllib.request
from pathlib import Path

import cv2
import numpy as np
import pytest
from conftest import START_BOUND_S
from test_select import Select, _browser

from vtrack.errors import InputError
from vtrack.picker.frames import FrameStore, read_frame
from vtrack.scenes import make_scene, write_image_sequence, write_video

W, H = 160, 120


@pytest.fixture(scope="module")
def gapped(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A 12-image sequence whose 0004..0006.jpg (frames 3..5) are missing."""
    folder = tmp_path_factory.mktemp("gapped") / "seq"
    write_image_sequence(make_scene("smooth", seed=4, width=W, height=H, frames=12, fps=30),
                         folder)
    for number in (4, 5, 6):
        (folder / "img" / f"{number:04d}.jpg").unlink()
    (folder / "groundtruth_rect.txt").unlink()
    return folder / "img"


def _image(data: bytes) -> np.ndarray:
    return cv2.imdecode(np.frombuffer(data, np.uint8), cv2.IMREAD_COLOR).astype(int)


def test_the_picker_numbers_frames_as_the_input_does(gapped: Path) -> None:
    """After 3 missing images the page's frame 3 was image 0007.jpg (vtrack frame's and run's
    frame 6), so a box drawn on it was printed --start 3; frames 9..11 did not exist."""
    with FrameStore(str(gapped)) as store:
        for index in (0, 2, 6, 8, 11):
            shown = _image(store.get(index))
            assert np.abs(shown - read_frame(str(gapped), index)).mean() < 3, index
        for index in (3, 5, 4):  # before and after the store passed them
            with pytest.raises(InputError) as absent:  # AbsentFrame
                store.get(index)
            assert (getattr(absent.value, "previous", None),
                    getattr(absent.value, "following", None)) == (2, 6)
            assert str(absent.value) == (f"{gapped}: frame {index} is missing from the "
                                         "numbering (no image between 0003.jpg and 0007.jpg); "
                                         "the next frame it has is frame 6")
        assert store.get(12) is None  # past the last image, numbered 11


def test_select_names_a_missing_start_frame_and_the_page_server_steps_over_it(
        gapped: Path) -> None:
    done = subprocess.run([sys.executable, "-m", "vtrack", "select", str(gapped), "--frame", "4"],
                          capture_output=True, text=True, timeout=START_BOUND_S,
                          check=False)
    assert done.returncode == 2 and done.stdout == ""
    assert done.stderr == (f"vtrack: error: {gapped}: frame 4 is missing from the numbering "
                           "(no image between 0003.jpg and 0007.jpg); the next frame it has is "
                           "frame 6\n")
    select = Select(str(gapped))
    try:
        with pytest.raises(urllib.error.HTTPError) as missing:
            urllib.request.urlopen(select.url + "frame/4", timeout=10)
        answer = json.loads(missing.value.read())
        assert missing.value.code == 404 and (answer["previous"], answer["next"]) == (2, 6)
        with urllib.request.urlopen(select.url + "frame/9", timeout=10) as response:
            assert np.abs(_image(response.read()) - read_frame(str(gapped), 9)).mean() < 3
    finally:
        select.stop()


@pytest.fixture(scope="module")
def browser(tmp_path_factory: pytest.TempPathFactory):
    """Headless Chromium in a 900x700 window."""
    binary, driver_path = _browser()
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service

    options = webdriver.ChromeOptions()
    options.binary_location = binary
    for flag in ("--headless", "--no-sandbox", "--disable-gpu", "--no-first-run",
                 "--disable-background-networking", "--window-size=900,700",
                 f"--user-data-dir={tmp_path_factory.mktemp('profile')}"):
        options.add_argument(flag)
    driver = webdriver.Chrome(service=Service(driver_path), options=options)
    yield driver
    driver.quit()


def _confirmed(browser, select: Select) -> tuple[int, str, str]:
    """Click 'Use this box', wait for the page to say it is done; the command's exit code and
    output."""
    from selenium.webdriver.common.by import By
    from selenium.webdriver.support.ui import WebDriverWait

    browser.find_element(By.ID, "confirm").click()
    WebDriverWait(browser, 20).until(
        lambda b: b.find_element(By.TAG_NAME, "body").get_attribute("data-done"))
    return select.finish()


def test_the_page_steps_over_missing_frames(gapped: Path, browser) -> None:
    """'next' from frame 2 showed image 0007.jpg as frame 3; a box drawn on it was printed
    --start 3."""
    from selenium.webdriver.common.by import By
    from selenium.webdriver.support.ui import WebDriverWait

    select = Select(str(gapped), "--frame", "2")
    try:
        wait = WebDriverWait(browser, 20)
        browser.get(select.url)
        where = browser.find_element(By.ID, "where")
        wait.until(lambda b: where.text.startswith("frame 2 "))
        for button, shown in (("next", 6), ("prev", 2), ("next", 6)):
            browser.find_element(By.ID, button).click()
            wait.until(lambda b, shown=shown: where.text.startswith(f"frame {shown} "))
        browser.find_element(By.ID, "init").send_keys("10,20,30,40")
        code, out, err = _confirmed(browser, select)
    finally:
        select.stop()
    assert code == 0, err
    assert out.strip() == "--start 6 --init 10,20,30,40"


def test_the_box_confirmed_is_the_box_typed(gapped: Path, browser) -> None:
    """Typed '10.5 20.25 30 40' (the form --init takes) was ignored and the dragged box
    confirmed; '10.5,20.25,30,40' was shown but 11,20,30,40 confirmed; a half-typed box left
    the last one to confirm."""
    from selenium.webdriver.common.action_chains import ActionChains
    from selenium.webdriver.common.by import By
    from selenium.webdriver.support.ui import WebDriverWait

    select = Select(str(gapped))
    try:
        browser.get(select.url)
        image, field = browser.find_element(By.ID, "frame"), browser.find_element(By.ID, "init")
        confirm = browser.find_element(By.ID, "confirm")
        WebDriverWait(browser, 20).until(
            lambda b: b.execute_script("return arguments[0].naturalWidth", image) == W)
        (ActionChains(browser).move_to_element_with_offset(image, -40, -30).click_and_hold()
         .move_by_offset(30, 20).release().perform())
        assert confirm.is_enabled() and field.get_attribute("value")
        field.clear()
        field.send_keys("10,20,30")  # not a box: nothing to confirm, and the page says so
        assert not confirm.is_enabled()
        assert "four numbers" in browser.find_element(By.ID, "status").text
        field.clear()
        field.send_keys("10.5 20.25 30 40")
        code, out, err = _confirmed(browser, select)
    finally:
        select.stop()
    assert code == 0, err
    assert out.strip() == "--init 10.5,20.25,30,40"
    assert (gapped.parent / "init.txt").read_text() == "10.5,20.25,30,40\n"


def test_a_page_whose_select_stopped_says_so(gapped: Path, browser) -> None:
    """After Ctrl-C in the terminal (or a box confirmed on another page) 'Use this box' and
    'next' did nothing and the page still said "Confirm with 'Use this box'"."""
    from selenium.webdriver.common.by import By
    from selenium.webdriver.support.ui import WebDriverWait

    select = Select(str(gapped))
    try:
        browser.get(select.url)
        wait = WebDriverWait(browser, 20)
        wait.until(lambda b: b.find_element(By.ID, "where").text.startswith("frame 0 "))
        select.process.send_signal(signal.SIGINT)
        code, out, err = select.finish()
        assert code == 130 and out == "" and err.endswith("vtrack: interrupted\n")
        field = browser.find_element(By.ID, "init")
        field.clear()
        field.send_keys("10,20,30,40")
        browser.find_element(By.ID, "confirm").click()
        status = browser.find_element(By.ID, "status")
        wait.until(lambda b: "not running any more" in status.text)
        assert not browser.find_element(By.ID, "confirm").is_enabled()
        assert not browser.find_element(By.ID, "next").is_enabled()
    finally:
        select.stop()


def test_a_box_dragged_to_the_edge_of_a_scaled_frame_stays_inside_it(tmp_path: Path,
                                                                     browser) -> None:
    """A 240-wide frame shown 160 CSS pixels wide (a window smaller than the frame): a drag
    from image x 10.5 to past the right edge gave 11,..,230,.. (x, y, w and h each rounded),
    which ends at 241, and the page's own confirm was refused 'not inside the 240x180 frame'."""
    from selenium.webdriver.common.action_chains import ActionChains
    from selenium.webdriver.common.by import By
    from selenium.webdriver.support.ui import WebDriverWait

    video = write_video(make_scene("smooth", seed=4, width=240, height=180, frames=10, fps=30),
                        tmp_path / "wide.mp4")
    select = Select(str(video))
    try:
        browser.get(select.url)
        image = browser.find_element(By.ID, "frame")
        WebDriverWait(browser, 20).until(
            lambda b: b.execute_script("return arguments[0].naturalWidth", image) == 240)
        browser.execute_script("arguments[0].style.width = '160px'", image)  # 1.5 px a pixel
        assert image.rect["width"] == 160
        (ActionChains(browser).move_to_element_with_offset(image, 7 - 80, 10 - 60)
         .click_and_hold().move_by_offset(300, 30).release().perform())
        assert browser.find_element(By.ID, "init").get_attribute("value") == "11,15,229,45"
        code, out, err = _confirmed(browser, select)
    finally:
        select.stop()
    assert code == 0, err
    assert out.strip() == "--init 11,15,229,45"


def test_select_help_says_a_box_on_a_later_frame_is_not_saved() -> None:
    """--help said every confirmed box is written to the sidecar; one drawn on frame N > 0 is
    printed as --start N --init and not saved (the README said so, --help did not)."""
    from click.testing import CliRunner

    from vtrack.cli import main

    done = CliRunner().invoke(main, ["select", "--help"], terminal_width=200)
    assert done.exit_code == 0
    text = " ".join(done.output.split())
    assert "printed as --start N --init x,y,w,h and not saved" in text
    assert "typed as x,y,w,h" in text


def test_the_saved_box_is_offered_on_frame_0_only(tmp_path: Path, browser) -> None:
    """select --frame 7 on an input with a sidecar showed the sidecar's box (frame 0's) on
    frame 7, ready to confirm: one click printed --start 7 --init with frame 0's box."""
    from selenium.webdriver.common.by import By
    from selenium.webdriver.support.ui import WebDriverWait

    video = write_video(make_scene("smooth", seed=4, width=W, height=H, frames=10, fps=30),
                        tmp_path / "saved.mp4")
    (tmp_path / "saved.init.txt").write_text("12,14,30,20\n")
    for frame, shown in ((7, ""), (0, "12,14,30,20")):
        select = Select(str(video), "--frame", str(frame))
        try:
            browser.get(select.url)
            WebDriverWait(browser, 20).until(lambda b, frame=frame: b.find_element(
                By.ID, "where").text.startswith(f"frame {frame} "))
            assert browser.find_element(By.ID, "init").get_attribute("value") == shown
            assert browser.find_element(By.ID, "confirm").is_enabled() == bool(shown)
        finally:
            select.stop()


def test_the_page_learns_the_last_frame_when_it_steps_past_it(tmp_path: Path, browser) -> None:
    """A folder whose last image does not decode: the page said 'frame 10 of 0..11' (the
    images counted), and 'next' answered only 'no frame 11' while still saying 0..11."""
    from selenium.webdriver.common.by import By
    from selenium.webdriver.support.ui import WebDriverWait

    folder = write_image_sequence(
        make_scene("smooth", seed=4, width=W, height=H, frames=12, fps=30), tmp_path / "cut")
    (folder / "img" / "0012.jpg").write_bytes(b"not a picture")
    select = Select(str(folder), "--frame", "10")
    try:
        browser.get(select.url)
        wait = WebDriverWait(browser, 20)
        where = browser.find_element(By.ID, "where")
        wait.until(lambda b: where.text == "frame 10 of 0..11")  # the images counted
        browser.find_element(By.ID, "next").click()
        status = browser.find_element(By.ID, "status")
        wait.until(lambda b: status.text == "no frame 11 (frames 0..10)")
        assert where.text == "frame 10 of 0..10"
    finally:
        select.stop()
