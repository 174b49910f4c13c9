"""MotionBenchMaker (MBM) problems: finding, downloading, unpacking and reading them.

A problems folder holds one folder per scene family (``box_panda/``, ...), each with
``sceneNNNN.yaml`` (a MoveIt PlanningScene) and ``requestNNNN.yaml`` (a MoveIt
MotionPlanRequest with a start state and one joint-space goal). The sets are third-party data
(Chamzas et al., "MotionBenchMaker", IEEE RA-L 2022) and are not part of this repository:
``find_problems`` takes them, in this order, from

1. a path the caller gives (``--dataset``): a problems folder, a folder holding ``problems/``
   or ``problems.tar.bz2``, or the archive itself;
2. the environment variable ``DRAKE_SIM_MBM``, in the same forms;
3. the cache, ``<cache_dir()>/mbm/<robot>/`` (``drake_sim.base.resources.cache_dir``);
4. else the source distribution of the ``vamp-planner`` package (Apache-2.0; VAMP ships the
   MBM sets of the Panda, UR5, Fetch and Baxter as ``resources/<robot>/problems.tar.bz2``),
   downloaded once with pip from the package index and unpacked into the cache.

Archives are unpacked beside their destination and renamed into place, so neither processes
running at the same time nor a run stopped half-way ever see a half-unpacked set. A set that
cannot be had raises ``MbmDataError``, one line naming what failed.

The same source distribution holds the robots' descriptions:
``drake_sim.robots.files.vamp_resources`` takes them from it
(``drake_sim.robots.files.vamp_sdist.download_sdist``).
"""

from __future__ import annotations

import hashlib
import os
import shutil
import sys
import tarfile
import tempfile
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import yaml

from drake_sim.base.errors import ConfigError
from drake_sim.base.resources import cache_dir
from drake_sim.robots.files.vamp_sdist import VAMP_PACKAGE, VAMP_VERSION, download_sdist
from planning.model.panda import ARM_JOINTS, FINGER_JOINTS

FAMILIES = (
    "table_pick_panda",
    "table_under_pick_panda",
    "box_panda",
    "bookshelf_small_panda",
    "bookshelf_tall_panda",
    "bookshelf_thin_panda",
    "cage_panda",
)
"""The Panda's scene families, 100 problems each."""

ENV_VAR = "DRAKE_SIM_MBM"
"""The environment variable that names a problems folder or ``problems.tar.bz2``."""


ARCHIVE_SHA256 = {
    "panda": "4e1509e99c53da769ee6a338cf1173ecf601e4ec16f24081d3894ef358243b69",
    "ur5": "576c199b30a0150d176362207494e6f3e409eb74c55f5225e671a00decfcb5b0",
    "fetch": "8f5d7a38acbd56326ba75b48c2a0058abc8ec7eaf0f5ea9786a881d1efbfacce",
    "baxter": "2326af3f436c4312b175617b8388a701994da5e4fabd19b84b66acd4d88b61ff",
}
"""SHA-256 of each robot's ``problems.tar.bz2`` in that release (the robots it has sets of)."""

_HINT = f"give a problems folder or problems.tar.bz2 with --dataset or {ENV_VAR}"


class MbmDataError(ConfigError):
    """An MBM set cannot be found, downloaded or unpacked: the message is one line naming the
    path, the robot or the step that failed (a ``ConfigError``, so a command-line entry point
    prints it and exits with code 2)."""

    def __init__(self, message: str):
        super().__init__(" ".join(str(message).split()))


@dataclass
class MbmProblem:
    """One MBM problem.

    Attributes:
        family: the scene family, e.g. "box_panda".
        number: the problem number (1-based, as in the file names).
        scene_file: the MoveIt PlanningScene YAML.
        request_file: the MoveIt MotionPlanRequest YAML.
    """

    family: str
    number: int
    scene_file: Path
    request_file: Path


@dataclass
class MbmRequest:
    """A request's start and goal: 9 positions each (7 arm joints in rad, 2 fingers in m);
    the goal keeps the start's fingers."""

    q_start: np.ndarray
    q_goal: np.ndarray


def find_problems(dataset: Path | str | None = None, *, robot: str = "panda") -> Path:
    """Returns the folder of a robot's MBM problems, found, downloaded or unpacked as needed.

    Args:
        dataset: a problems folder, a folder holding ``problems/`` or ``problems.tar.bz2``,
            or the archive itself; ``None`` looks at ``$DRAKE_SIM_MBM``, then the cache, then
            downloads (see the module docstring).
        robot: the robot whose set the cache holds or the download brings: one of
            ``ARCHIVE_SHA256`` ("panda", "ur5", "fetch", "baxter"). A given path or
            ``$DRAKE_SIM_MBM`` is used as it is.

    Raises:
        MbmDataError: an unknown robot, a path that is no set, a corrupt archive, or a download
            that failed (pip missing, no network).
    """
    _check_robot(robot)
    if dataset is not None:
        return problems_folder(dataset)
    if os.environ.get(ENV_VAR):
        try:
            return problems_folder(os.environ[ENV_VAR])
        except MbmDataError as e:
            raise MbmDataError(f"{ENV_VAR}: {e}") from None
    cached = cached_folder(robot)
    if _is_problems_folder(cached):
        return cached
    return download(robot)


def cached_folder(robot: str = "panda") -> Path:
    """Returns where the cache keeps a robot's downloaded set, ``<cache_dir()>/mbm/<robot>``
    (which may not exist yet)."""
    return cache_dir() / "mbm" / robot


def problems_folder(dataset: Path | str) -> Path:
    """Returns the problems folder of a path: the folder itself, its ``problems/``, or the
    unpacked ``problems.tar.bz2`` it holds or is (unpacked once into the cache, under a hash of
    the archive's contents).

    Raises:
        MbmDataError: the path does not exist, is none of those, or its archive is unreadable.
    """
    dataset = Path(dataset)
    if not dataset.exists():
        raise MbmDataError(f"MBM problems not found: {dataset} does not exist")
    for folder in (dataset, dataset / "problems"):
        if _is_problems_folder(folder):
            return folder
    archive = dataset / "problems.tar.bz2" if dataset.is_dir() else dataset
    if not archive.is_file():
        raise MbmDataError(
            f"{dataset}: neither a folder of MBM problems nor problems.tar.bz2 "
            "(nor a folder holding problems/ or problems.tar.bz2)"
        )
    try:
        digest = hashlib.sha256(archive.read_bytes()).hexdigest()
    except OSError as e:
        raise MbmDataError(f"{archive} cannot be read ({e.strerror})") from None
    return unpack(archive, cache_dir() / "mbm" / "unpacked" / digest[:16])


def download(robot: str = "panda") -> Path:
    """Downloads the ``vamp-planner`` source distribution with pip into a temporary folder,
    checks the robot's ``problems.tar.bz2`` in it against ``ARCHIVE_SHA256`` and unpacks it into
    ``cached_folder(robot)``; returns that folder. Does nothing when the cache holds the set.

    Prints one line on stderr when it downloads (about 65 MB, a few seconds). A failure or an
    interruption at any step leaves no set in the cache.

    Raises:
        MbmDataError: an unknown robot, pip missing or failing (no network), or an archive
            that is missing from the distribution, corrupt or not the expected one.
    """
    _check_robot(robot)
    target = cached_folder(robot)
    if _is_problems_folder(target):
        return target
    print(
        f"note: downloading the MotionBenchMaker {robot} problems ({VAMP_PACKAGE} "
        f"{VAMP_VERSION} sdist, ~65 MB) into {target}",
        file=sys.stderr,
        flush=True,
    )
    with tempfile.TemporaryDirectory(prefix="drake_sim-vamp-") as scratch:
        sdist = download_sdist(Path(scratch) / "sdist", "the MBM problems", _HINT, MbmDataError)
        archive = Path(scratch) / "problems.tar.bz2"
        _extract_archive(sdist, robot, archive)
        digest = hashlib.sha256(archive.read_bytes()).hexdigest()
        if digest != ARCHIVE_SHA256[robot]:
            raise MbmDataError(
                f"{sdist.name}: resources/{robot}/problems.tar.bz2 has SHA-256 {digest}, "
                f"expected {ARCHIVE_SHA256[robot]}"
            )
        return unpack(archive, target)


def unpack(archive: Path | str, destination: Path | str) -> Path:
    """Unpacks the ``problems/`` folder of a ``problems.tar.bz2`` as ``destination`` (once) and
    returns ``destination``.

    The archive is unpacked into a temporary folder beside ``destination`` and renamed into
    place, so processes running at the same time, or a run stopped half-way, never see a
    half-unpacked folder; the temporary folder is removed on any error.

    Raises:
        MbmDataError: the archive cannot be read or holds no ``problems/`` folder of scenes.
    """
    archive, destination = Path(archive), Path(destination)
    if _is_problems_folder(destination):
        return destination
    destination.parent.mkdir(parents=True, exist_ok=True)
    scratch = Path(tempfile.mkdtemp(prefix=f".{destination.name}-", dir=destination.parent))
    try:
        try:
            with tarfile.open(archive, "r:bz2") as tar:
                tar.extractall(scratch, filter="data")
        except (tarfile.TarError, OSError, EOFError) as e:
            raise MbmDataError(f"{archive}: not a readable problems.tar.bz2 ({e})") from None
        if not _is_problems_folder(scratch / "problems"):
            raise MbmDataError(f"{archive}: holds no problems/ folder of MBM scenes")
        try:
            (scratch / "problems").rename(destination)
        except OSError as e:  # another process may have put it there first
            if not _is_problems_folder(destination):
                raise MbmDataError(f"cannot unpack into {destination} ({e.strerror})") from None
    finally:
        shutil.rmtree(scratch, ignore_errors=True)
    return destination


def _check_robot(robot: str) -> None:
    if robot not in ARCHIVE_SHA256:
        raise MbmDataError(f"unknown MBM robot {robot!r} (known: {', '.join(ARCHIVE_SHA256)})")


def _is_problems_folder(folder: Path) -> bool:
    """Whether ``folder`` holds at least one family folder with scenes."""
    return folder.is_dir() and next(folder.glob("*/scene*.yaml"), None) is not None


def _extract_archive(sdist: Path, robot: str, out: Path) -> None:
    """Copies ``resources/<robot>/problems.tar.bz2`` out of the source distribution."""
    name = f"vamp_planner-{VAMP_VERSION}/resources/{robot}/problems.tar.bz2"
    try:
        with tarfile.open(sdist, "r:gz") as tar:
            try:
                member = tar.getmember(name)
            except KeyError:
                raise MbmDataError(f"{sdist.name} holds no {name}") from None
            source = tar.extractfile(member)
            if source is None:
                raise MbmDataError(f"{sdist.name}: {name} is not a file")
            with source, out.open("wb") as sink:
                shutil.copyfileobj(source, sink)
    except (tarfile.TarError, OSError, EOFError) as e:
        raise MbmDataError(f"{sdist.name}: not a readable source distribution ({e})") from None


def families_in(folder: Path | str) -> list[str]:
    """The scene families a problems folder holds (its folders with scenes), sorted."""
    folder = Path(folder)
    return sorted(p.name for p in folder.iterdir() if p.is_dir() and _is_family(p))


def _is_family(folder: Path) -> bool:
    return next(folder.glob("scene*.yaml"), None) is not None


def iter_problems(
    folder: Path | str, families=None, limit: int | None = None
) -> Iterator[MbmProblem]:
    """Yields the problems of a ``problems`` folder, family by family, in number order
    (``families``: the Panda's ``FAMILIES`` when None)."""
    folder = Path(folder)
    for family in families or FAMILIES:
        scenes = sorted((folder / family).glob("scene*.yaml"))
        if not scenes:
            raise FileNotFoundError(f"no MBM scenes in {folder / family}")
        for scene_file in scenes[:limit]:
            number = int(scene_file.stem.removeprefix("scene"))
            request = scene_file.with_name(f"request{number:04d}.yaml")
            yield MbmProblem(family, number, scene_file, request)


def read_request(filename: Path | str, joint_names) -> tuple[np.ndarray, np.ndarray, dict]:
    """Reads a MotionPlanRequest YAML for a planning group: ``(q_start, q_goal, others)``, the
    start and the goal over ``joint_names`` and the start's other joints by name (MoveIt keeps
    them where the start state has them).

    Raises:
        ValueError: a joint of the group is missing or a value is not finite.
    """
    loader = getattr(yaml, "CSafeLoader", yaml.SafeLoader)
    data = yaml.load(Path(filename).read_text(), Loader=loader)
    joint_state = data["start_state"]["joint_state"]
    start = dict(zip(joint_state["name"], map(float, joint_state["position"]), strict=True))
    constraints = data["goal_constraints"][0]["joint_constraints"]
    goal = {c["joint_name"]: float(c["position"]) for c in constraints}
    names = list(joint_names)
    missing = [n for n in names if n not in start] + [n for n in names if n not in goal]
    if missing:
        raise ValueError(f"{filename}: missing joints {sorted(set(missing))}")
    q_start = np.array([start[n] for n in names])
    q_goal = np.array([goal[n] for n in names])
    others = {n: v for n, v in start.items() if n not in names}
    values = [*q_start, *q_goal, *others.values()]
    if not np.all(np.isfinite(values)):
        raise ValueError(f"{filename}: non-finite joint values")
    return q_start, q_goal, others


def load_request(filename: Path | str) -> MbmRequest:
    """Reads a MotionPlanRequest YAML's start state and joint-space goal.

    Raises:
        ValueError: a joint is missing or a value is not finite.
    """
    loader = getattr(yaml, "CSafeLoader", yaml.SafeLoader)
    data = yaml.load(Path(filename).read_text(), Loader=loader)
    joint_state = data["start_state"]["joint_state"]
    start = dict(zip(joint_state["name"], joint_state["position"], strict=True))
    constraints = data["goal_constraints"][0]["joint_constraints"]
    goal = {c["joint_name"]: c["position"] for c in constraints}
    names = [*ARM_JOINTS, *FINGER_JOINTS]
    missing = [n for n in names if n not in start] + [n for n in ARM_JOINTS if n not in goal]
    if missing:
        raise ValueError(f"{filename}: missing joints {missing}")
    q_start = np.array([start[n] for n in names], dtype=float)
    q_goal = np.array([goal[n] for n in ARM_JOINTS] + [start[n] for n in FINGER_JOINTS])
    if not (np.all(np.isfinite(q_start)) and np.all(np.isfinite(q_goal))):
        raise ValueError(f"{filename}: non-finite joint values")
    return MbmRequest(q_start, q_goal)
