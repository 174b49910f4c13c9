"""Where the real robot files the model tests read are; a test skips, with the reason, when absent.

- ``../shared/real_ros/moveit/srdf/``: MoveIt's Panda SRDF, its xacro sources and VAMP's SRDF.
- VAMP's ``resources/<robot>/`` (URDF, SRDF, meshes): the cached built-in package
  ``vamp_resources``, else an unpacked ``vamp-planner`` sdist left by pip under the temporary
  folder.
- ``example-robot-data``: the installed wheel's ``robots/`` folder.
"""

import importlib.metadata
from pathlib import Path

import pytest

from tests.robot_helpers import dev_resources

ROOT = Path(__file__).resolve().parents[3]
MOVEIT_SRDF = ROOT.parent / "shared" / "real_ros" / "moveit" / "srdf"
VAMP_ROBOTS = ("panda", "ur5", "fetch", "baxter")


def moveit_srdf_dir() -> Path:
    """The folder of MoveIt's real SRDF files (skips when absent)."""
    if not (MOVEIT_SRDF / "panda.srdf").is_file():
        pytest.skip(f"the real MoveIt SRDF files are not at {MOVEIT_SRDF}")
    return MOVEIT_SRDF


def vamp_robot_dir(robot: str) -> Path:
    """VAMP's ``resources/<robot>/`` (skips when no copy is found)."""
    candidates = []
    try:
        from drake_sim.robots.files.vamp_resources import resources_root

        candidates.append(resources_root() / robot)
    except ImportError:
        pass
    if dev_resources() is not None:
        candidates.append(dev_resources() / robot)
    for folder in candidates:
        if (folder / f"{robot}.urdf").is_file() and (folder / f"{robot}.srdf").is_file():
            return folder
    pytest.skip(f"VAMP's resources/{robot} not found (fetch it with vamp_resources)")


def example_robot_data_dir() -> Path:
    """The installed ``example-robot-data`` ``robots/`` folder (skips when not installed)."""
    try:
        dist = importlib.metadata.distribution("example-robot-data")
    except importlib.metadata.PackageNotFoundError:
        pytest.skip("example-robot-data is not installed")
    return Path(str(dist.locate_file("cmeel.prefix/share/example-robot-data/robots")))
