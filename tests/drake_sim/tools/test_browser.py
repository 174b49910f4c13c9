"""Headless Chromium over the DevTools protocol: replays and the live Meshcat page show the
robot (skipped when no Chromium is installed)."""

import io

import numpy as np
import pytest
from PIL import Image
from pydrake.geometry import Meshcat

import drake_sim.tools.browser as mut
from drake_sim import flip
from drake_sim.runs.flip import FlipRun
from drake_sim.tools.replay_frames import capture_replay
from tests.browser_helpers import (
    COUNT_MESHES,
    assert_not_blank,
    require_chromium,
    robot_pixels,
)
from tests.flip_helpers import default_robot, flip_scenario, seeded

SIZE = (640, 400)
MIN_ROBOT_PIXELS = 150  # The body covers 250 to 1 000 pixels at this size; the rest has none.


def test_find_chromium_follows_the_override(monkeypatch):
    monkeypatch.setenv("DRAKE_SIM_CHROMIUM", "")
    assert mut.find_chromium() is None
    monkeypatch.setenv("DRAKE_SIM_CHROMIUM", "sh")
    assert mut.find_chromium().endswith("/sh")


def test_no_browser_is_a_clear_error(monkeypatch):
    monkeypatch.setenv("DRAKE_SIM_CHROMIUM", "")
    with pytest.raises(mut.BrowserError, match="no Chromium found"):
        mut.HeadlessBrowser()


def test_file_url(tmp_path):
    assert mut.file_url(tmp_path / "a b.html") == f"file://{tmp_path}/a%20b.html"


@pytest.fixture(scope="module")
def browser():
    require_chromium()
    with mut.HeadlessBrowser(size=SIZE, timeout=60.0) as dut:
        yield dut


@pytest.mark.browser
def test_evaluate_and_wait(browser):
    browser.open("about:blank")
    assert browser.evaluate("1 + 2") == 3
    assert browser.evaluate("Promise.resolve([1, 'a'])") == [1, "a"]
    with pytest.raises(mut.BrowserError, match="script failed"):
        browser.evaluate("undefined_name.x")
    with pytest.raises(mut.BrowserError, match="timed out"):
        browser.wait_for("false", timeout=0.3)


@pytest.mark.browser
def test_replay_screenshots_show_the_robot_moving(browser, tmp_path):
    bare, html = tmp_path / "bare.yaml", tmp_path / "replay.html"
    bare.write_text("scene: {world: ''}\n")
    args = ["--headless", "--duration", "2", "--config", str(bare), "--record", str(html)]
    assert flip.main(args) == 0
    first, last = capture_replay(html, frames=2, size=SIZE, browser=browser)
    assert first.size == SIZE
    for picture in (first, last):
        assert_not_blank(picture)
        assert robot_pixels(picture) > MIN_ROBOT_PIXELS
    # The replay's animation was followed: the robot is elsewhere at the end.
    moved = np.count_nonzero(np.any(np.asarray(first) != np.asarray(last), axis=-1))
    assert moved > MIN_ROBOT_PIXELS


@pytest.mark.browser
def test_live_meshcat_page_shows_the_robot(browser):
    meshcat = Meshcat()
    scenario = flip_scenario()
    run = FlipRun(seeded(scenario, 1), default_robot(), meshcat=meshcat, realtime=False)
    run.run(0.5)
    pose = scenario.scene.robot_pose
    meshcat.SetCameraPose([pose.x - 0.6, pose.y - 1.5, 0.8], [pose.x + 0.3, pose.y, 0.1])
    # The page stays connected to Meshcat's websocket, so it never "finishes" loading for
    # `chromium --screenshot`; over the protocol we wait for the scene itself instead.
    browser.open(meshcat.web_url())
    assert browser.wait_for(COUNT_MESHES) > 0
    run.run(0.6)  # Publishes once more, now that the page listens.
    browser.evaluate("new Promise(r => setTimeout(r, 500))")
    picture = Image.open(io.BytesIO(browser.screenshot()))
    assert picture.size == SIZE
    assert_not_blank(picture)
    assert robot_pixels(picture) > MIN_ROBOT_PIXELS
