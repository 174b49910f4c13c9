"""MotionBenchMaker (MBM) Panda problems: locating, unpacking and reading them.

A problem folder (``problems/<family>/``) holds ``sceneNNNN.yaml`` (a MoveIt PlanningScene) and
``requestNNNN.yaml`` (a MoveIt MotionPlanRequest with a start state and one joint-space goal).
See ``../shared/benchmarks/mbm_panda/README.md``.
"""

from __future__ import annotations

import tarfile
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


def unpack(archive: Path | str, destination: Path | str) -> Path:
    """Unpacks ``problems.tar.bz2`` into ``destination`` (once) and returns its problems folder."""
    destination = Path(destination)
    folder = destination / "problems"
    if not (folder / FAMILIES[0]).is_dir():
        destination.mkdir(parents=True, exist_ok=True)
        with tarfile.open(archive, "r:bz2") as tar:
            tar.extractall(destination, filter="data")
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
