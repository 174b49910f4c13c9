"""The default output folders of the apps are ignored by git, and the shipped files beside them
are not: a run with default options never leaves files for ``git status`` to show."""

import shutil
import subprocess
from pathlib import Path

import pytest

from drake_sim.runs import mapping
from drake_sim.sweep import command as sweep_command

ROOT = Path(__file__).resolve().parent.parent

# A sample output of each default output folder (the folders as the apps name them).
OUTPUTS = [
    Path(sweep_command.DEFAULT_OUT) / "flip_imu_noise" / "results.csv",
    Path(sweep_command.DEFAULT_OUT) / "flip_imu_noise" / "summary.json",
    Path(mapping.DEFAULT_OUT) / "room.yaml",
    Path(mapping.DEFAULT_OUT) / "room.pgm",
    Path("out") / "report.json",
]
# Shipped files whose paths look like outputs: never ignored.
SHIPPED = [
    Path("config") / "sweeps" / "flip_imu_noise.yaml",
    Path("drake_sim") / "sweep" / "command.py",
    Path("tests") / "drake_sim" / "sweep" / "test_command.py",
]


def ignored(path: Path) -> bool:
    """Whether git's ignore rules match ``path`` (tracked or not: ``--no-index``)."""
    result = subprocess.run(
        ["git", "check-ignore", "--no-index", "-q", str(path)],
        cwd=ROOT,
        capture_output=True,
        text=True,
    )
    assert result.returncode in (0, 1), result.stderr
    return result.returncode == 0


@pytest.fixture(scope="module", autouse=True)
def git_work_tree():
    if shutil.which("git") is None:
        pytest.skip("git is not installed")
    inside = subprocess.run(
        ["git", "rev-parse", "--show-toplevel"], cwd=ROOT, capture_output=True, text=True
    )
    if inside.returncode != 0 or Path(inside.stdout.strip()).resolve() != ROOT:
        pytest.skip("the project is not a git work tree here")


@pytest.mark.parametrize("path", OUTPUTS, ids=str)
def test_default_outputs_are_ignored(path):
    assert ignored(path), f"{path} is not in .gitignore"


@pytest.mark.parametrize("path", SHIPPED, ids=str)
def test_shipped_files_are_not_ignored(path):
    assert (ROOT / path).is_file()
    assert not ignored(path), f".gitignore hides the shipped file {path}"
