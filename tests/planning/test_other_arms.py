"""Planning for an arm other than the Panda, described only by a YAML naming the files of an
installed package (example-robot-data's xArm 7): random problems are solved, every path is free
when re-checked by Drake every 0.01 rad, plans record the robot, and the compiled search made
for the Panda serves it without compiling again."""

import numpy as np
import pytest

from planning import MotionPlanner, PlanningConfig, PlanningScene
from planning.model.model_config import RobotModelConfig
from planning.search import compiled_rrt
from planning.task.random_problems import random_problems, workspace_of
from tests.robot_helpers import XARM7_YAML


@pytest.fixture(scope="module")
def xarm(tmp_path_factory):
    path = tmp_path_factory.mktemp("arms") / "xarm7.yaml"
    path.write_text(XARM7_YAML)
    config = PlanningConfig(model=RobotModelConfig(description=str(path)), table=None)
    return PlanningScene(config)


def _free_every(scene, path, step=0.01) -> bool:
    for a, b in zip(path[:-1], path[1:], strict=True):
        n = max(1, int(np.ceil(np.linalg.norm(b - a) / step)))
        if not all(scene.is_collision_free(a + s * (b - a)) for s in np.linspace(0, 1, n + 1)):
            return False
    return True


def test_random_problems_for_an_arm_from_a_yaml_are_solved_and_free(xarm):
    panda = MotionPlanner(PlanningScene())  # the compiled search, as the Panda uses it
    panda.plan_path(np.array(panda.scene.model.home), panda.scene.model.home + 0.1)
    before = {name: len(getattr(compiled_rrt, name).signatures) for name in ("plan", "solve")}
    assert before["solve"] > 0  # the Panda's request ran the compiled search
    planner = MotionPlanner(xarm)
    assert xarm.model.robot.name == "UF_ROBOT" and xarm.model.num_joints == 7
    solved = 0
    for problem in random_problems(xarm, 4, seed=3, workspace=workspace_of(xarm)):
        assert not isinstance(problem, Exception), problem
        xarm.replace(world=problem.objects)
        result = planner.plan_to_joints(problem.q_goal, q_start=problem.q_start)
        assert result.success, result.message
        plan = result.trajectory
        assert plan.robot["name"] == "UF_ROBOT" and plan.robot["joints"] == xarm.model.joint_names
        np.testing.assert_allclose(plan.waypoints[0], problem.q_start)
        np.testing.assert_allclose(plan.waypoints[-1], problem.q_goal)
        assert _free_every(xarm, plan.waypoints)
        solved += 1
    assert solved == 4
    after = {name: len(getattr(compiled_rrt, name).signatures) for name in ("plan", "solve")}
    assert after == before  # one compile serves both robots
