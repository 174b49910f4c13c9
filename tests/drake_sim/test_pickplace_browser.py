"""The user's path through the browser: ``python -m drake_sim.pickplace`` with a viewer waits
for the Meshcat "Pick" button; a click in the live page runs the task (headless Chromium)."""

import io
import json
import re
import select
import signal
import subprocess
import sys
import time

import pytest
from PIL import Image

from drake_sim.tools.browser import HeadlessBrowser
from tests.browser_helpers import COUNT_MESHES, assert_not_blank, require_chromium

CLICK_PICK = """(() => {
  const label = Array.from(document.querySelectorAll('.property-name'))
      .find(e => e.textContent.trim() === 'Pick');
  if (!label) return false;
  label.closest('li').click();
  return true;
})()"""


def read_line_matching(process, pattern: str, timeout: float, stderr) -> str:
    """Reads the process's stdout until a line matches ``pattern`` (seconds of wall time);
    the assertion otherwise shows the end of the process's ``stderr`` file."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        ready, _, _ = select.select([process.stdout], [], [], 1.0)
        if ready:
            line = process.stdout.readline()
            if re.search(pattern, line):
                return line
            if not line and process.poll() is not None:
                break
    tail = stderr.read_text()[-2000:]
    raise AssertionError(f"no line matching {pattern!r} (exit code {process.poll()}):\n{tail}")


@pytest.mark.browser
def test_pick_button_in_the_live_page_runs_the_task(tmp_path):
    require_chromium()
    report = tmp_path / "report.json"
    # stderr to a file: a pipe nobody reads would block the app once full.
    with (tmp_path / "stderr.txt").open("w") as stderr:
        process = subprocess.Popen(
            [
                sys.executable,
                "-m",
                "drake_sim.pickplace",
                "--mode",
                "kinematic",
                "--report",
                report,
            ],
            stdout=subprocess.PIPE,
            stderr=stderr,
            text=True,
        )
    try:
        # A hang guard, not a speed limit: a first run on a cold cache, beside the rest of the
        # suite on two cores, fits its covers and tables before the page is up.
        line = read_line_matching(process, "press 'Pick'", 600, tmp_path / "stderr.txt")
        url = re.search(r"http://\S+", line).group(0)
        with HeadlessBrowser(size=(640, 400), timeout=60.0) as browser:
            browser.open(url)
            browser.wait_for(f"{COUNT_MESHES} > 20", timeout=60.0)  # the Panda's links are in
            browser.wait_for(CLICK_PICK, timeout=30.0)
            read_line_matching(process, "^success", 600, tmp_path / "stderr.txt")
            picture = Image.open(io.BytesIO(browser.screenshot())).convert("RGB")
        assert_not_blank(picture)
        process.send_signal(signal.SIGINT)  # the viewer keeps running until Ctrl-C
        assert process.wait(timeout=60) == 0
    finally:
        if process.poll() is None:
            process.kill()
    data = json.loads(report.read_text())
    assert data["success"] and data["place_error_m"] < 0.02
