"""VAMP's robot descriptions taken into the cache: from a folder, an sdist or a download (pip
mocked, with small fake descriptions built here), checked against their pins, placed whole or
not at all, never taken twice; the real release's files match the pins."""

import io
import subprocess
import tarfile

import pytest

import drake_sim.robots.files.vamp_resources as mut
from drake_sim.base.errors import ConfigError
from drake_sim.robots.files import vamp_sdist as mbm
from drake_sim.robots.files.robot_files import resolve_uri
from tests.mbm_helpers import FakePip
from tests.robot_helpers import dev_resources

ROBOTS = ("panda", "ur5", "fetch", "baxter")


@pytest.fixture
def cache(tmp_path, monkeypatch):
    """An empty cache of its own, and pip that must not be run."""
    monkeypatch.setenv("DRAKE_SIM_CACHE", str(tmp_path / "cache"))
    monkeypatch.setattr(subprocess, "run", FakePip(error=AssertionError("pip was run")))
    return tmp_path / "cache"


def fake_files(robot: str) -> dict[str, bytes]:
    return {
        f"{robot}.urdf": f'<robot name="{robot}"><link name="base"/></robot>'.encode(),
        f"{robot}.srdf": f'<robot name="{robot}"/>'.encode(),
        "meshes/part.stl": b"solid part\nendsolid part\n",
        "problems.tar.bz2": b"not copied",
    }


@pytest.fixture
def fake(tmp_path, monkeypatch):
    """A fake ``resources/`` folder and the sdist holding it; the pins are theirs."""
    folder = tmp_path / "resources"
    for robot in ROBOTS:
        for name, data in fake_files(robot).items():
            (folder / robot / name).parent.mkdir(parents=True, exist_ok=True)
            (folder / robot / name).write_bytes(data)
        monkeypatch.setitem(mut.RESOURCES_SHA256, robot, mut.tree_digest(folder / robot))
    sdist = tmp_path / f"vamp_planner-{mbm.VAMP_VERSION}.tar.gz"
    with tarfile.open(sdist, "w:gz") as tar:
        for path in sorted(folder.rglob("*")):
            if path.is_file():
                name = f"vamp_planner-{mbm.VAMP_VERSION}/resources/{path.relative_to(folder)}"
                info = tarfile.TarInfo(name)
                info.size = path.stat().st_size
                tar.addfile(info, io.BytesIO(path.read_bytes()))
    return folder, sdist


def placed(cache) -> list[str]:
    root = cache / "packages" / "vamp_resources"
    return sorted(p.name for p in root.iterdir()) if root.is_dir() else []


@pytest.mark.parametrize("form", ["folder", "parent", "sdist"])
def test_every_robot_is_placed_from_a_source(cache, fake, form):
    folder, sdist = fake
    source = {"folder": folder, "parent": folder.parent, "sdist": sdist}[form]
    found = mut.vamp_resources("ur5", source)
    assert found == cache / "packages" / "vamp_resources" / "ur5"
    assert placed(cache) == sorted(ROBOTS)  # all four at once, no scratch folder left
    assert (found / "ur5.urdf").read_bytes() == fake_files("ur5")["ur5.urdf"]
    assert not (found / "problems.tar.bz2").exists()
    assert resolve_uri("package://vamp_resources/ur5/ur5.urdf", cache) == found / "ur5.urdf"


def test_a_placed_robot_is_not_taken_again(cache, fake):
    folder, _ = fake
    first = mut.vamp_resources("fetch", folder)
    stamp = (first / "fetch.urdf").stat().st_mtime_ns
    assert mut.vamp_resources("fetch") == first  # no source, no pip: the cache holds it
    assert (first / "fetch.urdf").stat().st_mtime_ns == stamp


def test_the_download_is_one_pip_run(cache, fake, monkeypatch):
    _, sdist = fake
    pip = FakePip(sdist.read_bytes())
    monkeypatch.setattr(subprocess, "run", pip)
    mut.vamp_resources("baxter")
    mut.vamp_resources("panda")
    assert len(pip.commands) == 1 and f"{mbm.VAMP_PACKAGE}=={mbm.VAMP_VERSION}" in pip.commands[0]
    assert placed(cache) == sorted(ROBOTS)


def test_pip_failing_is_one_line_naming_the_download(cache, monkeypatch):
    monkeypatch.setattr(subprocess, "run", FakePip(returncode=1, stderr="ERROR: no network"))
    with pytest.raises(ConfigError, match="VAMP robot descriptions") as info:
        mut.vamp_resources("ur5")
    assert "no network" in str(info.value) and "\n" not in str(info.value)
    assert placed(cache) == []


def test_other_files_are_refused_and_nothing_is_placed(cache, fake, monkeypatch):
    folder, _ = fake
    (folder / "fetch" / "fetch.urdf").write_text("<robot name='changed'/>")
    with pytest.raises(ConfigError, match="resources/fetch/ has SHA-256"):
        mut.vamp_resources("panda", folder)
    assert "fetch" not in placed(cache) and not [n for n in placed(cache) if n.startswith(".")]


def test_another_release_is_replaced(cache, fake):
    folder, _ = fake
    target = mut.vamp_resources("ur5", folder)
    (target / ".sha256").write_text("an older release")
    (target / "stale.txt").write_text("old")
    assert mut.vamp_resources("ur5", folder) == target
    assert not (target / "stale.txt").exists() and (target / "ur5.urdf").is_file()


def test_bad_sources_and_robots(cache, tmp_path):
    with pytest.raises(ConfigError, match="unknown VAMP robot 'pr2'"):
        mut.vamp_resources("pr2")
    with pytest.raises(ConfigError, match="does not exist"):
        mut.vamp_resources("ur5", tmp_path / "nothing")
    (tmp_path / "empty").mkdir()
    with pytest.raises(ConfigError, match="resources/"):
        mut.vamp_resources("ur5", tmp_path / "empty")


@pytest.mark.skipif(dev_resources() is None, reason="no unpacked vamp sdist left by pip download")
@pytest.mark.parametrize("robot", ROBOTS)
def test_the_release_matches_the_pins(robot):
    assert mut.tree_digest(dev_resources() / robot) == mut.RESOURCES_SHA256[robot]
