"""``python -m drake_sim.tools.replay_frames REPLAY.html OUT.gif``: a Meshcat replay as an animated
GIF.

A replay is the self-contained HTML that ``--record`` writes (Meshcat's ``StaticHtml()`` after
``PublishRecording()``). Its page builds ``viewer = new MeshCat.Viewer(...)`` and hands the
recording to ``viewer.animator``, whose ``seek(t)`` poses every animated object at time ``t``
(s) and whose ``pause()`` stops its clock. One headless Chromium (``drake_sim.tools.browser``) opens
the page, pauses the animation, and for each frame seeks, renders and takes a screenshot; the
frames become a looping GIF (Pillow). Meshcat's control panel is hidden; the camera is the one
the recording set (e.g. ``SetCameraPose`` before recording) unless ``--camera`` sets another.

Options: ``--frames N`` (evenly spaced over ``--start``..``--end``, default the whole replay),
``--size WxH`` (pixels), ``--fps F`` (GIF playback rate), ``--camera X,Y,Z,TX,TY,TZ`` (the
camera's position and the point it looks at, m, world frame). Exit codes: 0 done, 1 the browser
failed, 2 bad input (a missing file, no Chromium) with one line on stderr.
"""

from __future__ import annotations

import argparse
import io
import sys
from collections.abc import Sequence
from pathlib import Path

from PIL import Image

from drake_sim.base import cli
from drake_sim.base.errors import ConfigError
from drake_sim.tools.browser import BrowserError, HeadlessBrowser, file_url, find_chromium

# Counts the page's fetch() calls still in flight: a replay loads its scene and recording as
# data: URLs fetched when the page starts. Installed before any of the page's own scripts.
_COUNT_FETCHES = """
window.__pending_fetches = 0;
const __fetch = window.fetch;
window.fetch = (...args) => {
  window.__pending_fetches += 1;
  return __fetch(...args).finally(() => { window.__pending_fetches -= 1; });
};
"""
_LOADED = "typeof viewer !== 'undefined' && window.__pending_fetches === 0"
_HIDE_CONTROLS = """
viewer.gui.domElement.style.display = 'none';
for (const e of document.querySelectorAll('#stats-plot, #status-message')) {
  e.style.display = 'none';
}
"""
_NEXT_FRAMES = "new Promise(r => requestAnimationFrame(() => requestAnimationFrame(r)))"
SETTLE_S = 0.5  # s, after the last fetch, for textures decoded from data: URLs.


def set_camera_script(p_WC: Sequence[float], p_WT: Sequence[float]) -> str:
    """JavaScript that puts Meshcat's camera at ``p_WC`` looking at ``p_WT`` (m, world frame,
    z up), as ``Meshcat.SetCameraPose`` does: three.js's frame is y up, so (x, y, z) is sent as
    (x, z, -y)."""
    cam, target = ([float(p[0]), float(p[2]), -float(p[1])] for p in (p_WC, p_WT))
    return (
        "viewer.set_property(['Cameras', 'default', 'rotated', '<object>'], 'position', "
        f"{cam}); viewer.set_camera_target({target});"
    )


def frame_times(duration: float, frames: int, start: float = 0.0, end: float | None = None):
    """Returns ``frames`` evenly spaced times (s) from ``start`` to ``end`` (default
    ``duration``), both included, clipped to ``[0, duration]``."""
    end = duration if end is None else min(end, duration)
    start = max(0.0, min(start, end))
    if frames == 1:
        return [start]
    return [start + (end - start) * i / (frames - 1) for i in range(frames)]


def capture_replay(
    html: Path,
    *,
    frames: int = 40,
    size: tuple[int, int] = (640, 400),
    start: float = 0.0,
    end: float | None = None,
    camera: Sequence[float] | None = None,
    browser: HeadlessBrowser | None = None,
) -> list[Image.Image]:
    """Screenshots a Meshcat replay at ``frames`` animation times.

    Args:
        html: the replay (``StaticHtml()`` of a published recording).
        frames: how many pictures, evenly spaced from ``start`` to ``end`` (s of the replay).
        size: the page's ``(width, height)`` in pixels.
        start: the first frame's time (s).
        end: the last frame's time (s); the end of the recording when None.
        camera: ``[x, y, z, tx, ty, tz]``, the camera's position and the point it looks at
            (m, world frame); the recording's camera when None.
        browser: reuse this browser (its size is set to ``size``); a new one when None.

    Returns:
        The RGB pictures in time order. A replay without a recording gives ``frames`` copies
        of its one scene.

    Raises:
        BrowserError: no Chromium, or the page did not load.
    """
    own = browser is None
    if own:
        browser = HeadlessBrowser(size=size)
    else:
        browser.set_size(size)
    try:
        script = browser.call("Page.addScriptToEvaluateOnNewDocument", {"source": _COUNT_FETCHES})
        browser.open(file_url(html))
        browser.call("Page.removeScriptToEvaluateOnNewDocument", script)
        browser.wait_for(_LOADED)
        browser.evaluate(f"new Promise(r => setTimeout(r, {SETTLE_S * 1000:.0f}))")
        browser.evaluate(_HIDE_CONTROLS)
        if camera is not None:
            browser.evaluate(set_camera_script(camera[:3], camera[3:]))
        duration = browser.evaluate("viewer.animator.pause(), viewer.animator.duration") or 0.0
        pictures = []
        for t in frame_times(duration, frames, start, end):
            browser.evaluate(f"viewer.animator.seek({t}), viewer.render(), {_NEXT_FRAMES}")
            pictures.append(Image.open(io.BytesIO(browser.screenshot())).convert("RGB"))
        return pictures
    finally:
        if own:
            browser.close()


def save_gif(pictures: Sequence[Image.Image], path: Path, *, fps: float = 10.0) -> None:
    """Writes pictures as a looping GIF shown at ``fps`` frames per second.

    All frames share one 256-colour palette made from a few of them (octree, which keeps small
    bright parts such as the robot in colour), without dithering: the colours stay steady from
    frame to frame and Pillow stores only the region that changed, so files stay small.
    """
    if not pictures:
        raise ValueError("no pictures to write")
    sample = pictures[:: max(1, len(pictures) // 4)][:4]
    strip = Image.new("RGB", (pictures[0].width, pictures[0].height * len(sample)))
    for i, picture in enumerate(sample):
        strip.paste(picture, (0, i * picture.height))
    palette = strip.quantize(colors=256, method=Image.Quantize.FASTOCTREE)
    frames = [p.quantize(palette=palette, dither=Image.Dither.NONE) for p in pictures]
    path.parent.mkdir(parents=True, exist_ok=True)
    frames[0].save(
        path,
        save_all=True,
        append_images=frames[1:],
        duration=round(1000 / fps),
        loop=0,
        optimize=True,
    )


def _size(text: str) -> tuple[int, int]:
    width, sep, height = text.lower().partition("x")
    try:
        size = int(width), int(height)
    except ValueError:
        size = (0, 0)
    if not sep or min(size) < 16 or max(size) > 4096:
        raise argparse.ArgumentTypeError(f"expected WIDTHxHEIGHT in pixels, got {text!r}")
    return size


def _camera(text: str) -> list[float]:
    try:
        values = [float(v) for v in text.split(",")]
    except ValueError:
        values = []
    if len(values) != 6:
        raise argparse.ArgumentTypeError(f"expected six numbers X,Y,Z,TX,TY,TZ, got {text!r}")
    return values


def _parse_args(argv):
    parser = cli.ArgumentParser(
        prog="python -m drake_sim.tools.replay_frames", description=__doc__.split("\n")[0]
    )
    parser.add_argument("replay", type=cli.input_file("replay"), help="a Meshcat replay (--record)")
    parser.add_argument("out", type=cli.output_file("GIF"), help="the GIF to write")
    parser.add_argument("--frames", type=cli.positive_int, default=40, help="pictures (default 40)")
    parser.add_argument("--size", type=_size, default=(640, 400), help="WxH (default 640x400)")
    parser.add_argument("--fps", type=cli.positive_float, default=10.0, help="GIF frame rate")
    parser.add_argument("--start", type=float, default=0.0, help="first frame's time (s)")
    parser.add_argument("--end", type=float, help="last frame's time (s; default the end)")
    parser.add_argument(
        "--camera", type=_camera, help="X,Y,Z,TX,TY,TZ: camera and target (m, world frame)"
    )
    args = parser.parse_args(argv)
    if find_chromium() is None:
        raise ConfigError("no Chromium found: install it (apt-get install chromium)")
    return args


def main(argv=None) -> int:
    args = _parse_args(argv)
    try:
        pictures = capture_replay(
            args.replay,
            frames=args.frames,
            size=args.size,
            start=args.start,
            end=args.end,
            camera=args.camera,
        )
    except BrowserError as e:
        print(f"error: {e}", file=sys.stderr)
        return cli.EXIT_FAILED
    save_gif(pictures, args.out, fps=args.fps)
    kib = args.out.stat().st_size / 1024
    print(f"wrote {args.out} ({len(pictures)} frames, {kib:.0f} KiB)")
    return cli.EXIT_OK


if __name__ == "__main__":
    sys.exit(cli.run(main))
