"""The ``vamp-planner`` release whose source distribution holds the MotionBenchMaker sets and the
robots' descriptions, and ``download_sdist``: pip downloads it from the package index (the only
network the project uses at run time). ``planning.io.mbm`` takes the sets from it,
``drake_sim.robots.files.vamp_resources`` the descriptions."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

from drake_sim.base.errors import ConfigError

VAMP_PACKAGE = "vamp-planner"

VAMP_VERSION = "0.6.4"
"""The release of ``vamp-planner`` whose source distribution the sets are taken from."""


def download_sdist(
    folder: Path, what: str, hint: str, error: type[ConfigError] = ConfigError
) -> Path:
    """Runs ``pip download`` of the release's source distribution into ``folder``; returns the
    downloaded file. ``what`` and ``hint`` word the error (of class ``error``): what could not be
    had, and how else to give it.

    Raises:
        ConfigError: pip is missing or fails (no network), or gives no source distribution.
    """
    requirement = f"{VAMP_PACKAGE}=={VAMP_VERSION}"
    # --no-binary for this package alone: its sdist holds the sets, its wheels do not (and
    # :all: would build the build tools from source too).
    command = [
        sys.executable,
        "-m",
        "pip",
        "download",
        "--no-deps",
        "--no-binary",
        VAMP_PACKAGE,
        requirement,
        "--dest",
        str(folder),
        "--disable-pip-version-check",
        "--no-input",
        "--quiet",
    ]
    failed = f"cannot download {what}: `pip download {requirement}`"
    try:
        result = subprocess.run(command, capture_output=True, text=True, check=False)
    except OSError as e:
        raise error(f"{failed} did not start ({e.strerror}); {hint}") from None
    if result.returncode != 0:
        lines = [line for line in (result.stderr + result.stdout).splitlines() if line.strip()]
        why = lines[-1].strip() if lines else f"exit code {result.returncode}"
        raise error(f"{failed} failed ({why}); {hint}")
    sdists = sorted(folder.glob("vamp_planner-*.tar.gz"))
    if not sdists:
        raise error(f"{failed} gave no vamp_planner-*.tar.gz; {hint}")
    return sdists[0]
