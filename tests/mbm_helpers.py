"""The MotionBenchMaker Panda problems for the tests, from one place.

The problems are third-party data and not in the repository. The tests take the copy in the
project's ``shared/`` folder beside the checkout (``<checkout>/../shared/benchmarks/mbm_panda``,
as laid for developers and CI) when it is there, else whatever ``planning.io.mbm.find_problems``
finds (``$DRAKE_SIM_MBM``, the cache, or a download with pip into the cache, which under pytest is
the session's own: ``tests/conftest.py``). A test that needs them and cannot have them skips and
says why.

Call these from fixtures or tests, never at import time: the session's cache folder is set by a
fixture.
"""

from __future__ import annotations

import io
import subprocess
import tarfile
from pathlib import Path

import pytest

from planning.io import mbm

SHARED_ARCHIVE = (
    Path(__file__).resolve().parents[1] / ".." / "shared" / "benchmarks" / "mbm_panda"
).resolve() / "problems.tar.bz2"
"""The copy in ``shared/`` beside the checkout (the same file as vamp-planner 0.6.4's)."""

_FOUND: dict = {}  # "result": the folder, or the error, of the first try in this process


def find_mbm_problems() -> Path:
    """Returns the unpacked Panda problems folder: the shared copy when present, else the
    library's finder.

    Raises:
        mbm.MbmDataError: neither can be had (no shared copy, and no network for the download).
    """
    if isinstance(_FOUND.get("result"), mbm.MbmDataError):
        raise _FOUND["result"]
    if "result" not in _FOUND:
        try:
            _FOUND["result"] = (
                mbm.find_problems(SHARED_ARCHIVE)
                if SHARED_ARCHIVE.is_file()
                else mbm.find_problems()
            )
        except mbm.MbmDataError as e:
            _FOUND["result"] = e
            raise
    return _FOUND["result"]


def mbm_problems() -> Path:
    """``find_mbm_problems`` for a test: skips it, saying why, when the problems cannot be had.
    A failure is remembered, so a missing network costs one try per test session."""
    try:
        return find_mbm_problems()
    except mbm.MbmDataError as e:
        pytest.skip(f"MotionBenchMaker problems not available: {e}")


# ------------------------------------------------ small fake sets, for the finder's tests ----
def make_problems_archive(path: Path, families=("box_panda",), count: int = 2) -> Path:
    """Writes a tiny ``problems.tar.bz2`` at ``path``: ``problems/<family>/sceneNNNN.yaml`` and
    ``requestNNNN.yaml`` for ``count`` problems of each family; returns ``path``."""
    path.parent.mkdir(parents=True, exist_ok=True)
    with tarfile.open(path, "w:bz2") as tar:
        for family in families:
            for number in range(1, count + 1):
                for kind in ("scene", "request"):
                    _add(tar, f"problems/{family}/{kind}{number:04d}.yaml", f"{kind}: {family}\n")
    return path


def make_sdist(folder: Path, archives: dict[str, bytes], version: str = mbm.VAMP_VERSION) -> Path:
    """Writes a fake ``vamp_planner-<version>.tar.gz`` into ``folder`` holding each robot's
    ``resources/<robot>/problems.tar.bz2`` (bytes of ``archives``); returns its path."""
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / f"vamp_planner-{version}.tar.gz"
    top = f"vamp_planner-{version}"
    with tarfile.open(path, "w:gz") as tar:
        _add(tar, f"{top}/PKG-INFO", f"Name: vamp-planner\nVersion: {version}\n")
        for robot, data in archives.items():
            _add(tar, f"{top}/resources/{robot}/problems.tar.bz2", data)
    return path


def _add(tar: tarfile.TarFile, name: str, data: str | bytes) -> None:
    payload = data.encode() if isinstance(data, str) else data
    info = tarfile.TarInfo(name)
    info.size = len(payload)
    tar.addfile(info, io.BytesIO(payload))


class FakePip:
    """Stands in for ``subprocess.run`` of ``pip download``: records each command, then writes
    ``sdist`` (bytes, or nothing when ``None``) into its ``--dest`` folder and returns
    ``returncode`` with ``stderr``; or raises ``error`` after writing half of ``sdist``."""

    def __init__(self, sdist=None, *, returncode=0, stderr="", error=None):
        self.sdist, self.returncode, self.stderr, self.error = sdist, returncode, stderr, error
        self.commands: list[list[str]] = []

    def __call__(self, command, **kwargs):
        self.commands.append(list(command))
        dest = Path(command[command.index("--dest") + 1])
        dest.mkdir(parents=True, exist_ok=True)
        target = dest / f"vamp_planner-{mbm.VAMP_VERSION}.tar.gz"
        if self.error is not None:
            target.write_bytes((self.sdist or b"")[: len(self.sdist or b"") // 2])
            raise self.error
        if self.sdist is not None:
            target.write_bytes(self.sdist)
        return subprocess.CompletedProcess(command, self.returncode, "", self.stderr)
