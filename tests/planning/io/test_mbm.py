"""MotionBenchMaker problems: every Panda scene loads into a PlanningScene and matches its file;
the finder takes a given path, then $DRAKE_SIM_MBM, then the cache, then downloads (pip mocked,
with small fake sets built here), and never leaves a half set behind."""

import collections
import hashlib
import subprocess
import tarfile

import numpy as np
import pytest
import yaml

import planning as mut
from planning.io import mbm
from tests.mbm_helpers import SHARED_ARCHIVE, FakePip, make_problems_archive, make_sdist


@pytest.fixture(scope="module")
def scene():
    return mut.PlanningScene()


@pytest.fixture
def fresh(tmp_path, monkeypatch):
    """An empty cache of its own, no $DRAKE_SIM_MBM, and pip that must not be run."""
    monkeypatch.setenv("DRAKE_SIM_CACHE", str(tmp_path / "cache"))
    monkeypatch.delenv(mbm.ENV_VAR, raising=False)
    monkeypatch.setattr(subprocess, "run", FakePip(error=AssertionError("pip was run")))
    return tmp_path / "cache"


def use_pip(monkeypatch, fake: FakePip) -> FakePip:
    monkeypatch.setattr(subprocess, "run", fake)
    return fake


def fake_sdist(tmp_path, monkeypatch, robots=("panda",), families=("box_panda",)) -> bytes:
    """A fake sdist's bytes with a small set per robot, whose hashes the finder then expects."""
    archives = {}
    for robot in robots:
        archive = make_problems_archive(tmp_path / "src" / robot / "problems.tar.bz2", families)
        archives[robot] = archive.read_bytes()
        digest = hashlib.sha256(archives[robot]).hexdigest()
        monkeypatch.setitem(mbm.ARCHIVE_SHA256, robot, digest)
    return make_sdist(tmp_path / "sdist", archives).read_bytes()


def leftovers(cache):
    """Everything under the cache's mbm/ folder (scratch folders included)."""
    return sorted(p.name for p in (cache / "mbm").iterdir()) if (cache / "mbm").is_dir() else []


def one_line_error(call, *match) -> str:
    with pytest.raises(mbm.MbmDataError) as info:
        call()
    text = str(info.value)
    assert "\n" not in text and text.strip() == text
    for part in match:
        assert part in text, text
    return text


def expected_objects(scene_file):
    data = yaml.load(scene_file.read_text(), Loader=getattr(yaml, "CSafeLoader", yaml.SafeLoader))
    return {o["id"]: o for o in data["world"]["collision_objects"]}


def test_every_scene_loads_and_matches_its_file(mbm_folder, scene):
    valid = collections.Counter()
    count = collections.Counter()
    for problem in mbm.iter_problems(mbm_folder):
        scene.load_moveit(problem.scene_file)
        objects = scene.world_objects
        expected = expected_objects(problem.scene_file)
        assert sorted(objects) == sorted(expected), problem.scene_file
        for name, entry in expected.items():
            obj = objects[name]
            (primitive,) = entry["primitives"]
            (pose,) = entry["primitive_poses"]
            assert obj.shape == primitive["type"]
            dims = primitive["dimensions"]
            size = dims if obj.shape == "box" else [dims[1], dims[0]]
            np.testing.assert_allclose(obj.size, size)
            np.testing.assert_allclose(obj.X_PO.translation(), pose["position"], atol=1e-12)
            x, y, z, w = pose["orientation"]
            q = obj.X_PO.rotation().ToQuaternion()
            assert abs(np.dot([q.x(), q.y(), q.z(), q.w()], [x, y, z, w])) == pytest.approx(
                np.linalg.norm([x, y, z, w]), abs=1e-9
            )
        request = mbm.load_request(problem.request_file)
        count[problem.family] += 1
        valid[problem.family] += scene.is_collision_free(
            request.q_start
        ) and scene.is_collision_free(request.q_goal)
    assert set(count) == set(mbm.FAMILIES) and all(n == 100 for n in count.values())
    print("valid start and goal per family:", dict(valid))
    assert sum(valid.values()) >= 690


def test_allowed_collision_matrix_becomes_filters(mbm_folder, scene):
    problem = next(mbm.iter_problems(mbm_folder, families=["box_panda"], limit=1))
    scene.load_moveit(problem.scene_file)
    plant = scene.plant
    body = plant.GetBodyByName
    assert scene.checker.IsCollisionFilteredBetween(body("panda_link5"), body("panda_link7"))
    assert not scene.checker.IsCollisionFilteredBetween(body("panda_link1"), body("panda_link7"))


def test_request_reading(mbm_folder):
    problem = next(mbm.iter_problems(mbm_folder, families=["cage_panda"], limit=1))
    request = mbm.load_request(problem.request_file)
    assert request.q_start.shape == (9,) and request.q_goal.shape == (9,)
    np.testing.assert_array_equal(request.q_goal[7:], request.q_start[7:])


def test_the_shared_copy_is_the_archive_the_download_checks_for():
    if not SHARED_ARCHIVE.is_file():
        pytest.skip(f"no shared copy of the MBM problems at {SHARED_ARCHIVE}")
    assert hashlib.sha256(SHARED_ARCHIVE.read_bytes()).hexdigest() == mbm.ARCHIVE_SHA256["panda"]


def test_a_given_path_may_be_the_archive_its_folder_or_the_problems(tmp_path, fresh):
    archive = make_problems_archive(tmp_path / "set" / "problems.tar.bz2", ["box_panda"], 3)
    folder = mbm.find_problems(archive)
    digest = hashlib.sha256(archive.read_bytes()).hexdigest()
    assert folder == fresh / "mbm" / "unpacked" / digest[:16]
    assert sorted(p.name for p in (folder / "box_panda").iterdir()) == [
        f"{kind}{n:04d}.yaml" for kind in ("request", "scene") for n in (1, 2, 3)
    ]
    assert mbm.find_problems(archive.parent) == folder  # the folder holding the archive
    assert mbm.find_problems(str(folder)) == folder  # the problems folder itself
    (tmp_path / "unpacked").mkdir()
    (folder).rename(tmp_path / "unpacked" / "problems")
    moved = tmp_path / "unpacked" / "problems"
    assert mbm.find_problems(moved.parent) == moved  # a folder holding problems/
    assert mbm.problems_folder(moved) == moved


@pytest.mark.parametrize(
    ("make", "match"),
    [
        (lambda d: d / "nowhere", "does not exist"),
        (lambda d: d, "neither a folder of MBM problems nor problems.tar.bz2"),
        (lambda d: (d / "problems.tar.bz2").write_bytes(b"not bz2") and d, "not a readable"),
        (lambda d: d / "other.tar.bz2", "holds no problems/ folder"),
    ],
)
def test_a_given_path_that_is_no_set_is_a_one_line_error(tmp_path, fresh, make, match):
    folder = tmp_path / "given"
    folder.mkdir()
    with tarfile.open(folder / "other.tar.bz2", "w:bz2") as tar:
        tar.add(__file__, arcname="elsewhere/file.py")
    one_line_error(lambda: mbm.find_problems(make(folder)), match)
    assert not (fresh / "mbm" / "unpacked").is_dir() or not any(
        (fresh / "mbm" / "unpacked").iterdir()
    )


def test_the_environment_variable_comes_after_a_given_path_and_before_the_cache(
    tmp_path, fresh, monkeypatch
):
    given = make_problems_archive(tmp_path / "given" / "problems.tar.bz2", ["box_panda"])
    named = make_problems_archive(tmp_path / "named" / "problems.tar.bz2", ["cage_panda"])
    cached = mbm.unpack(
        make_problems_archive(tmp_path / "c" / "problems.tar.bz2", ["table_pick_panda"]),
        mbm.cached_folder("panda"),
    )
    assert cached == fresh / "mbm" / "panda"
    assert mbm.find_problems() == cached  # the cache, with no download
    monkeypatch.setenv(mbm.ENV_VAR, str(named))
    assert (mbm.find_problems() / "cage_panda").is_dir()
    assert (mbm.find_problems(given) / "box_panda").is_dir()
    monkeypatch.setenv(mbm.ENV_VAR, str(tmp_path / "nowhere"))
    text = one_line_error(mbm.find_problems, "nowhere", "does not exist")
    assert text.startswith(f"{mbm.ENV_VAR}: ")


def test_a_download_fills_the_cache_once(tmp_path, fresh, monkeypatch, capsys):
    pip = use_pip(monkeypatch, FakePip(fake_sdist(tmp_path, monkeypatch)))
    folder = mbm.find_problems()
    assert folder == mbm.cached_folder("panda") == fresh / "mbm" / "panda"
    assert (folder / "box_panda" / "scene0002.yaml").read_text() == "scene: box_panda\n"
    assert leftovers(fresh) == ["panda"]  # no scratch folder left
    (command,) = pip.commands
    assert command[:3] == [mbm.sys.executable, "-m", "pip"]
    assert command[3:7] == ["download", "--no-deps", "--no-binary", "vamp-planner"]
    assert f"vamp-planner=={mbm.VAMP_VERSION}" in command and ":all:" not in command
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("note: downloading the MotionBenchMaker panda")
    assert str(folder) in err
    assert mbm.find_problems() == folder and len(pip.commands) == 1  # from the cache now
    assert capsys.readouterr().err == ""


def test_another_robot_downloads_its_own_set(tmp_path, fresh, monkeypatch):
    sdist = fake_sdist(tmp_path, monkeypatch, robots=("panda", "ur5"), families=["box_ur5"])
    use_pip(monkeypatch, FakePip(sdist))
    folder = mbm.find_problems(robot="ur5")
    assert folder == fresh / "mbm" / "ur5" and (folder / "box_ur5").is_dir()
    assert leftovers(fresh) == ["ur5"]
    one_line_error(lambda: mbm.find_problems(robot="pr2"), "unknown MBM robot 'pr2'", "panda")
    one_line_error(lambda: mbm.download("pr2"), "unknown MBM robot")


def _truncated(data: bytes) -> bytes:
    return data[: len(data) // 2]


@pytest.mark.parametrize(
    ("case", "match"),
    [
        ("pip fails", "No matching distribution found for vamp-planner==0.6.4"),
        ("pip missing", "did not start"),
        ("no sdist", "gave no vamp_planner-*.tar.gz"),
        ("corrupt sdist", "not a readable source distribution"),
        ("no archive for the robot", "holds no vamp_planner-0.6.4/resources/panda/"),
        ("another archive", "has SHA-256"),
        ("corrupt archive", "not a readable problems.tar.bz2"),
    ],
)
def test_a_failed_download_is_a_one_line_error_and_leaves_no_set(
    tmp_path, fresh, monkeypatch, capsys, case, match
):
    good = fake_sdist(tmp_path, monkeypatch)
    archive = (tmp_path / "src" / "panda" / "problems.tar.bz2").read_bytes()
    fake = {
        "pip fails": FakePip(
            returncode=1,
            stderr="WARNING: Retrying\nERROR: No matching distribution found for "
            "vamp-planner==0.6.4\n",
        ),
        "no sdist": FakePip(),
        "corrupt sdist": FakePip(_truncated(good)),
        "no archive for the robot": FakePip(
            make_sdist(tmp_path / "other", {"ur5": archive}).read_bytes()
        ),
        "another archive": FakePip(
            make_sdist(tmp_path / "other", {"panda": archive + b"\0"}).read_bytes()
        ),
        "corrupt archive": FakePip(
            make_sdist(tmp_path / "other", {"panda": _truncated(archive)}).read_bytes()
        ),
    }.get(case)
    if case == "pip missing":
        fake = FakePip(error=FileNotFoundError(2, "No such file or directory"))
    if case == "corrupt archive":  # its hash is the expected one: the unpacking finds it bad
        digest = hashlib.sha256(_truncated(archive)).hexdigest()
        monkeypatch.setitem(mbm.ARCHIVE_SHA256, "panda", digest)
    use_pip(monkeypatch, fake)
    text = one_line_error(mbm.find_problems, match)
    if case in ("pip fails", "pip missing"):
        assert "--dataset" in text and mbm.ENV_VAR in text  # says what to do instead
    assert leftovers(fresh) == []
    assert not mbm.cached_folder("panda").exists()
    capsys.readouterr()


def test_an_interrupted_download_leaves_no_set(tmp_path, fresh, monkeypatch):
    sdist = fake_sdist(tmp_path, monkeypatch)
    use_pip(monkeypatch, FakePip(sdist, error=KeyboardInterrupt()))
    with pytest.raises(KeyboardInterrupt):
        mbm.find_problems()
    assert leftovers(fresh) == []
    # Stopped while unpacking, after the files were written but before the rename.
    use_pip(monkeypatch, FakePip(sdist))
    extractall = tarfile.TarFile.extractall

    def stopped(self, *args, **kwargs):
        extractall(self, *args, **kwargs)
        raise KeyboardInterrupt

    monkeypatch.setattr(tarfile.TarFile, "extractall", stopped)
    with pytest.raises(KeyboardInterrupt):
        mbm.find_problems()
    assert leftovers(fresh) == []
    monkeypatch.setattr(tarfile.TarFile, "extractall", extractall)
    assert (mbm.find_problems() / "box_panda").is_dir()  # the next run downloads it whole


def test_unpack_once_into_a_fresh_folder(tmp_path):
    archive = make_problems_archive(tmp_path / "problems.tar.bz2", ["box_panda", "cage_panda"])
    folder = mbm.unpack(archive, tmp_path / "out" / "set")
    assert folder == tmp_path / "out" / "set"
    assert sorted(p.name for p in folder.iterdir()) == ["box_panda", "cage_panda"]
    assert [p.name for p in (tmp_path / "out").iterdir()] == ["set"]  # no scratch folder left
    marker = folder / "box_panda" / "marker"
    marker.touch()
    assert mbm.unpack(archive, folder) == folder and marker.is_file()  # not unpacked again


def test_bad_request_names_the_missing_joint(tmp_path):
    path = tmp_path / "request.yaml"
    path.write_text(
        "start_state: {joint_state: {name: [panda_joint1], position: [0]}}\n"
        "goal_constraints: [{joint_constraints: [{joint_name: panda_joint1, position: 0}]}]\n"
    )
    with pytest.raises(ValueError, match="panda_joint2"):
        mbm.load_request(path)
