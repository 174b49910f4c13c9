"""Motion planning for the Franka Panda on Drake.

``from planning import RobotState, PlanningScene, PlanningError, ErrorCode``. The Panda comes
from the installed ``example-robot-data`` package (``panda_assets``), is built for planning by
``panda_model``, and is configured by ``config/panda.yaml`` (``config``).
"""

from planning.config import IkOptions, PandaPlanningConfig, load_panda_config
from planning.errors import ErrorCode, PlanningError
from planning.io.scene_files import load_moveit_scene, load_scene_yaml, save_scene_yaml
from planning.motion_planner import MotionPlanner, MotionPlannerOptions, load_planner_options
from planning.plan import Plan, PlanResult
from planning.planning_scene import PlanningScene
from planning.robot_state import RobotState, RobotStateReader
from planning.scene_objects import SceneObject, describe_scene, make_pose
from planning.search.ik import IkResult

__all__ = [
    "ErrorCode",
    "MotionPlanner",
    "MotionPlannerOptions",
    "Plan",
    "PlanResult",
    "describe_scene",
    "load_planner_options",
    "IkOptions",
    "IkResult",
    "PandaPlanningConfig",
    "PlanningError",
    "PlanningScene",
    "RobotState",
    "RobotStateReader",
    "SceneObject",
    "load_moveit_scene",
    "load_panda_config",
    "load_scene_yaml",
    "make_pose",
    "save_scene_yaml",
]
