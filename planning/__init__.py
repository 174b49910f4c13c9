"""Motion planning for the Franka Panda on Drake: the public API.

``from planning import RobotState, PlanningScene, MotionPlanner, MotionPlanningInterface,
PlanningError, Plan, PickPlaceTask``. Everything a user needs is here; the rooms below are the
library's own:

* ``planning.model``: the Panda's assets, its planning plant, and its state layout and gripper
  constants (``planning.model.layout``).
* ``planning.collision``: Drake's checker behind an adapter, and the sphere model that answers
  first. ``planning.search``: IK, RRT-Connect, shortcutting, Cartesian paths, GCS, KTO.
  ``planning.timing``: time parameterisation. ``planning.io``: scene files and MotionBenchMaker.
* ``planning.execution``: the commander systems and action handles of the interface.
* ``planning.task``: pick-and-place built on the API.

Its tools are apps and stand outside it: ``python -m planning.benchmark`` (a name that forwards
to ``drake_sim.tools.plan_benchmark``) and ``python -m drake_sim.tools.regions``.
"""

from planning.config import IkOptions, PlanningConfig, load_planning_config
from planning.errors import ErrorCode, PlanningError
from planning.execution.options import InterfaceOptions
from planning.interface import MotionPlanningInterface
from planning.io.scene_files import load_moveit_scene, load_scene_yaml, save_scene_yaml
from planning.motion_planner import MotionPlanner, MotionPlannerOptions, load_planner_options
from planning.plan import Plan, PlanResult
from planning.planning_scene import PlanningScene
from planning.robot_state import RobotState, RobotStateReader
from planning.scene_objects import SceneObject, describe_scene, make_pose
from planning.search.ik import IkResult
from planning.task.options import PickPlaceOptions
from planning.task.pick_place import PickPlaceTask, StepReport, TaskReport

__all__ = [
    "ErrorCode",
    "IkOptions",
    "IkResult",
    "InterfaceOptions",
    "MotionPlanner",
    "MotionPlannerOptions",
    "MotionPlanningInterface",
    "PlanningConfig",
    "PickPlaceOptions",
    "PickPlaceTask",
    "Plan",
    "PlanResult",
    "PlanningError",
    "PlanningScene",
    "RobotState",
    "RobotStateReader",
    "SceneObject",
    "StepReport",
    "TaskReport",
    "describe_scene",
    "load_moveit_scene",
    "load_planning_config",
    "load_planner_options",
    "load_scene_yaml",
    "make_pose",
    "save_scene_yaml",
]
