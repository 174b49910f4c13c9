"""MotionBenchMaker (MBM) Panda problems: locating, unpacking and reading them.

A problem folder (``problems/<family>/``) holds ``sceneNNNN.yaml`` (a MoveIt PlanningScene) and
``requestNNNN.yaml`` (a MoveIt MotionPlanRequest with a start state and one joint-space goal).
The repository ships the 700 problems as ``benchmarks/data/mbm_panda/problems.tar.bz2``
(``default_dataset``); that folder's README.md says where they come from.
"""

from __future__ import annotations

import shutil
import tarfile
import tempfile
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import yaml

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

# The checkout's root, found as drake_sim.base.resources finds models/ and config/: the data is
# not part of the installed packages, so the project is installed from its checkout (-e).
_ROOT = Path(__file__).resolve().parents[2]


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


def default_dataset() -> Path:
    """Returns the repository's copy of the problems, the folder ``benchmarks/data/mbm_panda``
    holding ``problems.tar.bz2`` (the default of ``python -m planning.benchmark``).

    Raises:
        FileNotFoundError: the archive is not there (the project is not run from its checkout).
    """
    folder = _ROOT / "benchmarks" / "data" / "mbm_panda"
    if not (folder / "problems.tar.bz2").is_file():
        raise FileNotFoundError(
            f"MBM problems not found (looked for {folder / 'problems.tar.bz2'}); "
            "install the project with `pip install -e .` from its checkout"
        )
    return folder


def unpack(archive: Path | str, destination: Path | str) -> Path:
    """Unpacks ``problems.tar.bz2`` into ``destination`` (once) and returns its problems folder.

    The archive is unpacked beside the folder and renamed into place, so processes running at
    the same time never see a half-unpacked folder."""
    destination = Path(destination)
    folder = destination / "problems"
    if (folder / FAMILIES[0]).is_dir():
        return folder
    destination.mkdir(parents=True, exist_ok=True)
    scratch = Path(tempfile.mkdtemp(prefix=".unpacking-", dir=destination))
    try:
        with tarfile.open(archive, "r:bz2") as tar:
            tar.extractall(scratch, filter="data")
        try:
            (scratch / "problems").rename(folder)
        except OSError:  # another process put it there first
            if not (folder / FAMILIES[0]).is_dir():
                raise
    finally:
        shutil.rmtree(scratch, ignore_errors=True)
    return folder


def iter_problems(
    folder: Path | str, families=None, limit: int | None = None
) -> Iterator[MbmProblem]:
    """Yields the problems of a ``problems`` folder, family by family, in number order."""
    folder = Path(folder)
    for family in families or FAMILIES:
        scenes = sorted((folder / family).glob("scene*.yaml"))
        if not scenes:
            raise FileNotFoundError(f"no MBM scenes in {folder / family}")
        for scene_file in scenes[:limit]:
            number = int(scene_file.stem.removeprefix("scene"))
            request = scene_file.with_name(f"request{number:04d}.yaml")
            yield MbmProblem(family, number, scene_file, request)


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
