"""Reads what a Meshcat ``StaticHtml()`` replay holds, for tests that check a recording."""

import base64
import re

_COMMAND = re.compile(r'"data:application/octet-binary;base64,([A-Za-z0-9+/=]+)"')
_PATH = re.compile(rb"/drake/[A-Za-z0-9_/.\-]+|/odometry/[A-Za-z0-9_/.\-]+")


def scene_paths(html: str) -> set[str]:
    """Returns the Meshcat scene paths (``/drake/...``, ``/odometry/...``) that the replay's
    embedded commands mention."""
    paths = set()
    for blob in _COMMAND.findall(html):
        paths.update(p.decode() for p in _PATH.findall(base64.b64decode(blob)))
    return paths
