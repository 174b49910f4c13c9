"""Planning problems as MoveIt writes them: ``sceneNNNN.yaml`` and ``requestNNNN.yaml``.

A problem is a ``moveit_msgs/PlanningScene`` (world objects, each one primitive at its pose in
the world frame) and a ``moveit_msgs/MotionPlanRequest`` (the group's name, a start state of
named joints, one goal of joint constraints), written as MotionBenchMaker writes its sets, so
that ``planning.io.moveit_scene.load_moveit_scene`` and ``planning.io.mbm.load_request`` read
them back, MoveIt's own tools too. Problems go into ``<folder>/<family>/``, the layout of an
MBM problems folder (``planning.io.mbm.iter_problems``).

Each problem's two files are written as one (``drake_sim.base.files.write_atomic_many``): a
stopped run never leaves a scene without its request, nor half a file.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from pathlib import Path

import numpy as np
import yaml

from drake_sim.base.files import write_atomic_many
from planning.scene_objects import SceneObject

_PRIMITIVE_TYPES = {"box": "box", "sphere": "sphere", "cylinder": "cylinder"}


def problem_paths(folder: Path | str, family: str, number: int) -> tuple[Path, Path]:
    """Returns ``(scene, request)`` paths of problem ``number`` (1-based) of a family."""
    base = Path(folder) / family
    return base / f"scene{number:04d}.yaml", base / f"request{number:04d}.yaml"


def scene_message(objects: Iterable[SceneObject], name: str = "") -> dict:
    """Returns a PlanningScene (as YAML data) holding ``objects`` as world collision objects,
    each with one primitive at its pose ``X_PO`` in the world (ADD, ``frame_id: world``)."""
    return {
        "name": name,
        "world": {"collision_objects": [_collision_object(o) for o in objects]},
    }


def request_message(
    group: str,
    start: Mapping[str, float],
    goal: Mapping[str, float],
    *,
    planning_time: float = 5.0,
) -> dict:
    """Returns a MotionPlanRequest (as YAML data).

    Args:
        group: the planning group's name (``group_name``).
        start: every joint of the start state by name (the group's and the others', such as
            fingers), in the order to write them.
        goal: the group's joints at the goal, by name: one ``goal_constraints`` entry of joint
            constraints (zero tolerances, weight 1).
        planning_time: ``allowed_planning_time``, s.
    """
    return {
        "group_name": group,
        "num_planning_attempts": 1,
        "allowed_planning_time": float(planning_time),
        "start_state": {
            "joint_state": {
                "name": list(start),
                "position": [float(v) for v in start.values()],
            }
        },
        "goal_constraints": [
            {
                "joint_constraints": [
                    {
                        "joint_name": name,
                        "position": float(value),
                        "tolerance_above": 0.0,
                        "tolerance_below": 0.0,
                        "weight": 1.0,
                    }
                    for name, value in goal.items()
                ]
            }
        ],
    }


def write_problem(
    folder: Path | str, family: str, number: int, scene: dict, request: dict
) -> tuple[Path, Path]:
    """Writes a problem's scene and request messages (``scene_message``, ``request_message``)
    as ``<folder>/<family>/sceneNNNN.yaml`` and ``requestNNNN.yaml``, atomically; returns the
    two paths.

    Raises:
        ConfigError: a file cannot be written (one line naming it); neither is then replaced.
    """
    scene_file, request_file = problem_paths(folder, family, number)
    write_atomic_many([(scene_file, _dump(scene)), (request_file, _dump(request))], "problem file")
    return scene_file, request_file


def _collision_object(obj: SceneObject) -> dict:
    if obj.shape == "cylinder":
        radius, length = obj.size
        dimensions: Sequence[float] = (length, radius)  # SolidPrimitive: [height, radius]
    else:
        dimensions = obj.size
    q = obj.X_PO.rotation().ToQuaternion()
    return {
        "id": obj.name,
        "header": {"frame_id": "world"},
        "operation": 0,
        "primitives": [
            {"type": _PRIMITIVE_TYPES[obj.shape], "dimensions": [float(d) for d in dimensions]}
        ],
        "primitive_poses": [
            {
                "position": [float(v) for v in obj.X_PO.translation()],
                "orientation": [float(q.x()), float(q.y()), float(q.z()), float(q.w())],
            }
        ],
    }


def _dump(data: dict) -> str:
    return yaml.safe_dump(_plain(data), sort_keys=False, default_flow_style=None, width=100)


def _plain(value):
    """Numpy scalars and arrays as Python numbers and lists, for ``yaml.safe_dump``."""
    if isinstance(value, dict):
        return {k: _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple, np.ndarray)):
        return [_plain(v) for v in value]
    if isinstance(value, np.generic):
        return value.item()
    return value
