"""Headless Chromium driven over the DevTools protocol, for screenshots of Meshcat pages.

Chromium is started with ``--remote-debugging-pipe``: the DevTools protocol (CDP) then runs
over two pipes (Chromium reads commands on its fd 3 and writes replies on its fd 4, each
message a JSON object followed by a NUL byte), so no port, websocket library or browser
download is needed. One browser start serves many screenshots, which is what makes an
animated GIF of a replay cheap.

Example::

    with HeadlessBrowser(size=(640, 400)) as browser:
        browser.open(file_url(Path("replay.html")))
        browser.wait_for("typeof viewer !== 'undefined'")
        Path("shot.png").write_bytes(browser.screenshot())
"""

from __future__ import annotations

import base64
import contextlib
import json
import os
import select
import shutil
import subprocess
import tempfile
import time
from pathlib import Path

CHROMIUM_NAMES = ("chromium", "chromium-browser", "google-chrome", "google-chrome-stable")
"""Executables searched on ``PATH`` (after ``$DRAKE_SIM_CHROMIUM``) by ``find_chromium``."""

_FLAGS = (
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--enable-unsafe-swiftshader",  # WebGL in software: Meshcat draws with three.js.
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--hide-scrollbars",
    "--mute-audio",
    "--remote-debugging-pipe",
)


class BrowserError(RuntimeError):
    """Chromium is missing, crashed, or a page did not do what was waited for in time."""


def find_chromium() -> str | None:
    """Returns the path of a Chromium (or Chrome) executable, or None if there is none.

    ``$DRAKE_SIM_CHROMIUM`` wins when set (an empty value means "no browser").
    """
    override = os.environ.get("DRAKE_SIM_CHROMIUM")
    if override is not None:
        return shutil.which(override) if override else None
    for name in CHROMIUM_NAMES:
        path = shutil.which(name)
        if path:
            return path
    return None


class HeadlessBrowser:
    """One headless Chromium with one page, controlled over the DevTools protocol.

    Args:
        size: the page's viewport, ``(width, height)`` in CSS pixels.
        executable: the browser; ``find_chromium()`` when None.
        timeout: seconds allowed for any single protocol call.

    Raises:
        BrowserError: when no browser is found or it does not start.
    """

    def __init__(
        self,
        *,
        size: tuple[int, int] = (1280, 800),
        executable: str | None = None,
        timeout: float = 30.0,
    ):
        executable = executable or find_chromium()
        if executable is None:
            raise BrowserError(
                "no Chromium found (install it, e.g. `apt-get install chromium`, or set "
                "DRAKE_SIM_CHROMIUM)"
            )
        self.timeout = timeout
        self._next_id = 0
        self._buffer = b""
        self._profile = tempfile.TemporaryDirectory(prefix="drake_sim_chromium_")
        # The browser's pipe ends go in as the shell's stdin and stdout, which it moves to 3
        # and 4 before it runs the browser (no Python runs in the forked child).
        child_r, self._to_browser = os.pipe()
        self._from_browser, child_w = os.pipe()
        remap = 'exec "$@" 3<&0 4>&1 </dev/null >/dev/null'
        args = ["sh", "-c", remap, "sh", executable, *_FLAGS]  # sh from PATH
        args += [f"--user-data-dir={self._profile.name}", f"--window-size={size[0]},{size[1]}"]
        try:
            self._process = subprocess.Popen(
                [*args, "about:blank"], stdin=child_r, stdout=child_w, stderr=subprocess.DEVNULL
            )
        except OSError as e:
            self._profile.cleanup()
            os.close(self._to_browser)
            os.close(self._from_browser)
            raise BrowserError(f"cannot start {executable}: {e}") from None
        finally:
            os.close(child_r)
            os.close(child_w)
        try:
            target = self._call("Target.createTarget", {"url": "about:blank"})["targetId"]
            attached = self._call("Target.attachToTarget", {"targetId": target, "flatten": True})
            self._session = attached["sessionId"]
            self.call("Page.enable")
            self.call("Runtime.enable")
            self.set_size(size)
        except BaseException:
            self.close()
            raise

    def __enter__(self) -> HeadlessBrowser:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def close(self) -> None:
        """Ends the browser and removes its temporary profile."""
        if self._process.poll() is None:
            with contextlib.suppress(BrowserError):
                self._call("Browser.close", timeout=5.0)
            try:
                self._process.wait(timeout=5.0)
            except subprocess.TimeoutExpired:
                self._process.kill()
                self._process.wait()
        for fd in (self._to_browser, self._from_browser):
            with contextlib.suppress(OSError):
                os.close(fd)
        self._profile.cleanup()

    def call(self, method: str, params: dict | None = None) -> dict:
        """Sends a protocol command to the page and returns its result."""
        return self._call(method, params, session=self._session)

    def set_size(self, size: tuple[int, int]) -> None:
        """Sets the viewport to ``(width, height)`` CSS pixels at a device scale of 1."""
        width, height = size
        self.call(
            "Emulation.setDeviceMetricsOverride",
            {"width": width, "height": height, "deviceScaleFactor": 1, "mobile": False},
        )

    def open(self, url: str, *, timeout: float | None = None) -> None:
        """Navigates to ``url`` and waits until its document has loaded."""
        result = self.call("Page.navigate", {"url": url})
        if result.get("errorText"):
            raise BrowserError(f"cannot open {url}: {result['errorText']}")
        self.wait_for("document.readyState === 'complete'", timeout=timeout)

    def evaluate(self, expression: str):
        """Evaluates a JavaScript expression in the page (awaiting a promise) and returns its
        JSON value.

        Raises:
            BrowserError: if the script throws.
        """
        result = self.call(
            "Runtime.evaluate",
            {"expression": expression, "awaitPromise": True, "returnByValue": True},
        )
        if "exceptionDetails" in result:
            details = result["exceptionDetails"]
            text = details.get("exception", {}).get("description") or details.get("text")
            raise BrowserError(f"script failed: {text}")
        return result["result"].get("value")

    def wait_for(self, predicate: str, *, timeout: float | None = None, poll: float = 0.1):
        """Polls a JavaScript expression until it is truthy and returns its value.

        Raises:
            BrowserError: if it is still falsy after ``timeout`` seconds (default: the
                browser's ``timeout``).
        """
        deadline = time.monotonic() + (self.timeout if timeout is None else timeout)
        while True:
            value = self.evaluate(f"(() => {{ try {{ return {predicate}; }} catch (e) {{}} }})()")
            if value:
                return value
            if time.monotonic() > deadline:
                raise BrowserError(f"timed out waiting for `{predicate}`")
            time.sleep(poll)

    def screenshot(self) -> bytes:
        """Returns the viewport as PNG bytes."""
        data = self.call("Page.captureScreenshot", {"format": "png"})["data"]
        return base64.b64decode(data)

    def _call(self, method, params=None, *, session=None, timeout=None) -> dict:
        self._next_id += 1
        message = {"id": self._next_id, "method": method, "params": params or {}}
        if session is not None:
            message["sessionId"] = session
        try:
            os.write(self._to_browser, json.dumps(message).encode() + b"\0")
        except OSError as e:
            raise BrowserError(f"the browser is gone ({e})") from None
        deadline = time.monotonic() + (self.timeout if timeout is None else timeout)
        while True:
            reply = self._read_message(deadline, method)
            if reply.get("id") == self._next_id:
                if "error" in reply:
                    raise BrowserError(f"{method}: {reply['error'].get('message')}")
                return reply.get("result", {})
            # Anything else is an event, which nothing here listens to.

    def _read_message(self, deadline: float, method: str) -> dict:
        while b"\0" not in self._buffer:
            remaining = deadline - time.monotonic()
            if remaining <= 0:
                raise BrowserError(f"{method}: no answer from the browser in time")
            ready, _, _ = select.select([self._from_browser], [], [], remaining)
            if not ready:
                continue
            chunk = os.read(self._from_browser, 1 << 20)
            if not chunk:
                raise BrowserError(f"{method}: the browser exited")
            self._buffer += chunk
        message, self._buffer = self._buffer.split(b"\0", 1)
        return json.loads(message)


def file_url(path: Path) -> str:
    """Returns the ``file://`` URL of a local file."""
    return Path(path).resolve().as_uri()
