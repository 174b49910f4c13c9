import copy

import numpy as np
import pytest
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import DiagramBuilder, LeafSystem

import diagrams.explore_scenario as mut
from diagrams.lidar_robot import add_lidar_robot
from diagrams.navigation_scenario import NavigationScenario
from drake_sim.base.errors import ConfigError
from drake_sim.base.planar import wrap_angle
from drake_sim.navigation.frontiers import FrontierConfig
from drake_sim.worlds.arena import load_arena
from tests import navigation_helpers as nh


def test_the_shipped_scenario_is_a_navigation_scenario_with_exploration():
    scenario = mut.load_explore_scenario(mut.default_scenario_file())
    assert isinstance(scenario, NavigationScenario)
    assert isinstance(scenario.exploration, FrontierConfig)
    assert scenario.time_limit == 600.0
    assert scenario.no_map_localization == "slam"
    # A turning Waffle sweeps 0.255 m round its axle: the costmap keeps that clear.
    assert scenario.navigator.costmap.robot_radius >= 0.255


def test_overrides_reach_the_exploration_section(tmp_path):
    scenario = mut.load_explore_scenario(
        mut.default_scenario_file(), ["exploration.gain_scale=2.0", "time_limit=30"]
    )
    assert scenario.exploration.gain_scale == 2.0 and scenario.time_limit == 30.0


@pytest.mark.parametrize(
    "text, needle",
    [
        ("time_limit: 0\n", "time_limit"),
        ("exploration: {replan_period: 0}\n", "replan_period"),
        ("exploration: {clearance: -1}\n", "clearance"),
        ("exploration: {colour: red}\n", "colour"),
        ("navigator: {costmap: {robot_radius: -0.2}}\n", "robot_radius"),
    ],
)
def test_bad_values_name_the_key(tmp_path, text, needle):
    path = tmp_path / "scenario.yaml"
    path.write_text(text)
    with pytest.raises(ConfigError, match=needle):
        mut.load_explore_scenario(path)


class _Manoeuvre(LeafSystem):
    """cmd_vel: straight at full speed, a spin on the spot, then an arc."""

    def __init__(self):
        super().__init__()
        self.DeclareVectorOutputPort("cmd_vel", 2, self._calc)

    def _calc(self, context, output):
        t = context.get_time()
        output.SetFromVector([0.22, 0.0] if t < 2.0 else [0.0, 1.8] if t < 3.5 else [0.2, 0.6])


def _drive(scenario, time_step: float) -> np.ndarray:
    """The Waffle's true [x, y, yaw] every 0.1 s through ``_Manoeuvre`` on a plant of
    ``time_step``."""
    scenario = copy.deepcopy(scenario)
    scenario.plant.time_step = time_step
    arena = load_arena(nh.arena_file("room"))
    builder = DiagramBuilder()
    parts = add_lidar_robot(builder, scenario, robot=nh.robot(), world=arena, start=[0, 0, 0])
    manoeuvre = builder.AddSystem(_Manoeuvre())
    builder.Connect(manoeuvre.get_output_port(), parts.cmd_vel)
    builder.ExportOutput(parts.true_pose, "truth")
    diagram = builder.Build()
    simulator = Simulator(diagram)
    poses = []
    for k in range(1, 61):
        simulator.AdvanceTo(0.1 * k)
        poses.append(diagram.GetOutputPort("truth").Eval(simulator.get_context()).copy())
    return np.array(poses)


def test_the_exploring_plant_step_drives_the_robot_as_a_fine_one_does():
    # The scenario's coarser step (for speed) must not change how the robot moves: through a
    # straight, a spin and an arc it stays within 2 mm and 0.5 degrees of a 1 ms plant.
    scenario = mut.load_explore_scenario(mut.default_scenario_file())
    assert scenario.plant.time_step > 0.002
    coarse, fine = _drive(scenario, scenario.plant.time_step), _drive(scenario, 0.001)
    assert np.linalg.norm(np.diff(fine[:, :2], axis=0), axis=1).sum() > 0.6  # it did drive
    assert np.abs(fine[:, 2] - fine[0, 2]).max() > 2.0  # and turn
    assert np.linalg.norm(coarse[:, :2] - fine[:, :2], axis=1).max() < 0.002
    assert np.degrees(np.abs(wrap_angle(coarse[:, 2] - fine[:, 2]))).max() < 0.5
