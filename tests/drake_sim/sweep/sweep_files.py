"""Small sweep files for the sweep tests: real runners, rollouts of a fraction of a second."""

import os
from pathlib import Path

TINY_FLIP = """\
name: tiny
runner: flip
options: {{duration: {duration}}}
seed: 3
repeats: {repeats}
parameters:
  flip.drive_speed: {{grid: [0.6, 0.8]}}
metrics: [flips, travel_extent_m, odometry_error_m]
success: [finite]
"""


def write_sweep(folder: Path, text: str, name: str = "sweep.yaml") -> Path:
    path = folder / name
    path.write_text(text)
    return path


def tiny_flip(folder: Path, *, duration: float = 0.3, repeats: int = 1) -> Path:
    """A flip sweep of ``2 * repeats`` rollouts of ``duration`` simulated seconds."""
    return write_sweep(folder, TINY_FLIP.format(duration=duration, repeats=repeats))


def crash_on_odd_index(job: dict, rollout: dict) -> dict:
    """A worker task for the backend tests: kills its worker process on odd indices (as a
    segfault would), and returns a plain row otherwise."""
    if rollout["index"] % 2:
        os._exit(3)
    return {"index": rollout["index"], "status": "ok", "worker": str(os.getpid())}
