"""Shared set-up for the headless-Chromium tests: skip without a browser, find the robot."""

import re

import numpy as np
import pytest
from PIL import Image

from drake_sim.base.resources import models_dir
from drake_sim.tools.browser import find_chromium

# A page expression: the number of meshes in the Meshcat scene.
COUNT_MESHES = "(() => { let n = 0; viewer.scene.traverse(o => { n += !!o.isMesh; }); return n })()"


def require_chromium() -> str:
    """Returns the browser's path, or skips the test with the reason."""
    path = find_chromium()
    if path is None:
        pytest.skip("no Chromium found (apt-get install chromium; .ci/run installs it as root)")
    return path


def body_rgb() -> np.ndarray:
    """The robot body's colour (RGB in 0..1) as ``models/ddrive/ddrive.urdf.xacro`` sets it."""
    text = (models_dir() / "ddrive" / "ddrive.urdf.xacro").read_text()
    match = re.search(r'name="base_link".*?color="([\d.]+) ([\d.]+) ([\d.]+)', text, re.S)
    return np.array([float(v) for v in match.groups()])


def robot_pixels(picture: Image.Image, *, tolerance: float = 0.05) -> int:
    """Counts the pixels that look like the robot's body: their chromaticity (r, g, b over
    r + g + b, which shading leaves nearly unchanged) within ``tolerance`` of the body colour's,
    and not too dark to tell."""
    rgb = np.asarray(picture.convert("RGB"), dtype=float)
    total = rgb.sum(axis=-1)
    chroma = rgb / np.maximum(total, 1.0)[..., None]
    body = body_rgb()
    reference = body / body.sum()
    close = np.abs(chroma - reference).max(axis=-1) < tolerance
    return int(np.count_nonzero(close & (total > 150)))


def assert_not_blank(picture: Image.Image) -> None:
    """The picture has content: its pixels vary and it has many colours."""
    rgb = np.asarray(picture.convert("RGB"), dtype=float)
    assert rgb.reshape(-1, 3).std(axis=0).min() > 5.0
    assert len(picture.convert("RGB").getcolors(maxcolors=1 << 20) or []) > 100
