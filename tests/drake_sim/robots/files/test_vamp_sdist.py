"""drake_sim.robots.files.vamp_sdist: pip downloads the pinned vamp-planner sdist; failures are one
ConfigError line of the caller's class, naming what could not be had and how else to give it."""

import subprocess

import pytest

import drake_sim.robots.files.vamp_sdist as mut
from drake_sim.base.errors import ConfigError
from tests.mbm_helpers import FakePip


class MineError(ConfigError):
    pass


def test_the_sdist_of_the_pinned_release(tmp_path, monkeypatch):
    pip = FakePip(b"sdist bytes")
    monkeypatch.setattr(subprocess, "run", pip)
    found = mut.download_sdist(tmp_path / "d", "the things", "give them yourself")
    assert found.read_bytes() == b"sdist bytes"
    (command,) = pip.commands
    assert f"{mut.VAMP_PACKAGE}=={mut.VAMP_VERSION}" in command and "--no-deps" in command


@pytest.mark.parametrize(
    "pip, why",
    [
        (FakePip(None, returncode=1, stderr="ERROR: no network\n"), "no network"),
        (FakePip(None), "gave no vamp_planner"),
        (FakePip(error=OSError(2, "No such file")), "did not start"),
    ],
)
def test_failures_name_what_and_how_else(tmp_path, monkeypatch, pip, why):
    monkeypatch.setattr(subprocess, "run", pip)
    with pytest.raises(MineError, match=why) as info:
        mut.download_sdist(tmp_path / "d", "the things", "give them yourself", MineError)
    message = str(info.value)
    assert "cannot download the things" in message and message.endswith("give them yourself")
