"""ROS parameter files (nav2, ROS 1 YAML and launch XML) as the navigation scenario's AMCL keys."""

from pathlib import Path

import pytest

import diagrams.ros_params as mut
from diagrams.navigation_scenario import default_scenario_file, load_navigation_scenario
from drake_sim.base.errors import ConfigError

NAV2 = """amcl:
  ros__parameters:
    alpha1: 0.3
    alpha5: 0.1
    max_beams: 45
    z_hit: 0.6
    z_rand: 0.4
    sigma_hit: 0.15
    pf_err: 0.04
    pf_z: 0.98
    min_particles: 300
    robot_model_type: "nav2_amcl::OmniMotionModel"
    initial_pose: {x: 1.0, y: -0.5, z: 0.0, yaw: 0.25}
    tf_broadcast: true
controller_server:
  ros__parameters:
    controller_frequency: 15.0
    general_goal_checker: {xy_goal_tolerance: 0.08, stateful: true}
    FollowPath: {plugin: "dwb_core::DWBLocalPlanner", max_vel_x: 0.26}
local_costmap:
  local_costmap:
    ros__parameters:
      width: 4
      resolution: 0.05
      robot_radius: 0.2
      footprint: "[[0.1, 0.1], [-0.1, 0.1], [-0.1, -0.1], [0.1, -0.1]]"
      inflation_layer: {inflation_radius: 0.6, cost_scaling_factor: 4.0}
      obstacle_layer: {scan: {obstacle_max_range: 2.0, raytrace_max_range: 2.5}}
planner_server:
  ros__parameters:
    GridBased: {plugin: "nav2_navfn_planner::NavfnPlanner", tolerance: 0.3, use_astar: false}
"""

ROS1_YAML = "odom_model_type: diff\nodom_alpha3: 0.8\nlaser_z_max: 0.05\nkld_err: 0.03\n"

LAUNCH = """<launch>
  <arg name="scan_topic" default="scan"/>
  <arg name="beams" default="40"/>
  <node pkg="amcl" type="amcl" name="amcl">
    <param name="odom_model_type" value="omni"/>
    <param name="laser_max_beams" value="$(arg beams)"/>
    <param name="selective_resampling" value="true"/>
    <param name="gui_publish_rate" value="10.0"/>
    <remap from="scan" to="$(arg scan_topic)"/>
  </node>
  <node pkg="map_server" type="map_server" name="map_server">
    <param name="frame_id" value="map"/>
  </node>
</launch>
"""


def write(tmp_path, name: str, text: str) -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


def test_nav2_names_become_the_scenario_amcl_keys(tmp_path, caplog):
    path = write(tmp_path, "nav2_params.yaml", NAV2)
    with caplog.at_level("WARNING"):
        overrides = dict(o.split("=", 1) for o in mut.ros_overrides(path))
    assert overrides == {
        "amcl.odom_alpha1": "0.3",
        "amcl.odom_alpha5": "0.1",
        "amcl.laser_max_beams": "45",
        "amcl.laser_z_hit": "0.6",
        "amcl.laser_z_rand": "0.4",
        "amcl.laser_sigma_hit": "0.15",
        "amcl.kld_err": "0.04",
        "amcl.kld_z": "0.98",
        "amcl.min_particles": "300",
        "amcl.odom_model_type": '"omni-corrected"',
        "amcl.initial_pose_x": "1.0",
        "amcl.initial_pose_y": "-0.5",
        "amcl.initial_pose_a": "0.25",
        "navigator.controller.controller_frequency": "15.0",
        "navigator.local_planner": '"dwa"',  # FollowPath's plugin: DWB
        "navigator.controller.xy_goal_tolerance": "0.08",
        "navigator.controller.max_vel_x": "0.26",
        "navigator.costmap.local_width": "4",
        "navigator.costmap.footprint": "[[0.1, 0.1], [-0.1, 0.1], [-0.1, -0.1], [0.1, -0.1]]",
        "navigator.costmap.robot_radius": "0.1",  # the footprint's inscribed radius
        "navigator.costmap.inflation_radius": "0.6",
        "navigator.costmap.cost_scaling_factor": "4.0",
        "navigator.costmap.obstacle_max_range": "2.0",
        "navigator.costmap.raytrace_max_range": "2.5",
        "navigator.planner.tolerance": "0.3",
        "navigator.planner.use_astar": "false",
    }
    (record,) = caplog.records
    message = record.getMessage()
    assert message.startswith(f"{path}: ignored keys ")
    for key in ("amcl.tf_broadcast", "amcl.initial_pose.z", "local_costmap.resolution"):
        assert key in message
    assert "general_goal_checker.stateful" in message and "max_vel_x" not in message


def test_ros1_costmap_and_dwa_files(tmp_path):
    costmap = "obstacle_range: 3.0\nraytrace_range: 3.5\ninflation_radius: 1.0\nmap_type: costmap\n"
    assert mut.ros_overrides(write(tmp_path, "costmap.yaml", costmap)) == [
        "navigator.costmap.obstacle_max_range=3.0",
        "navigator.costmap.raytrace_max_range=3.5",
        "navigator.costmap.inflation_radius=1.0",
    ]
    dwa = "DWAPlannerROS:\n  max_vel_x: 0.26\n  vth_samples: 40\n  max_vel_y: 0.0\n"
    dwa += "GlobalPlanner: {use_dijkstra: true}\n"
    assert mut.ros_overrides(write(tmp_path, "dwa.yaml", dwa)) == [
        "navigator.controller.max_vel_x=0.26",
        "navigator.controller.vtheta_samples=40",
        "navigator.planner.use_astar=false",
    ]


def test_dwb_critics_and_progress_checkers_map_to_their_scenario_keys(tmp_path, caplog):
    text = """controller_server:
  ros__parameters:
    progress_checker: {plugin: "nav2_controller::SimpleProgressChecker",
                       required_movement_radius: 0.5, movement_time_allowance: 12.0}
    FollowPath:
      plugin: "dwb_core::DWBLocalPlanner"
      PathAlign.scale: 30.0
      PathAlign.forward_point_distance: 0.1
      GoalAlign.scale: 24.0
      PathDist: {scale: 31.0}
      GoalDist.scale: 23.0
      BaseObstacle.scale: 0.03
"""
    overrides = mut.ros_overrides(write(tmp_path, "nav2.yaml", text))
    assert sorted(overrides) == [
        "navigator.controller.forward_point_distance=0.1",
        "navigator.controller.goal_distance_bias=23.0",
        "navigator.controller.occdist_scale=0.03",
        "navigator.controller.path_align_bias=30.0",
        "navigator.controller.path_distance_bias=31.0",
        'navigator.local_planner="dwa"',
        "navigator.recovery.progress_distance=0.5",
        "navigator.recovery.progress_timeout=12.0",
    ]
    assert "FollowPath.GoalAlign.scale" in caplog.text  # no goal-align critic here
    move_base = "oscillation_timeout: 0.0\noscillation_distance: 0.2\n"  # 0: never
    assert mut.ros_overrides(write(tmp_path, "move_base.yaml", move_base)) == [
        "navigator.recovery.progress_distance=0.2"
    ]
    assert "oscillation_timeout" in caplog.text.splitlines()[-1]
    bad = write(tmp_path, "bad.yaml", "oscillation_timeout: -3.0\n")
    with pytest.raises(ConfigError, match="progress_timeout"):
        load_navigation_scenario(default_scenario_file(), [f"params=[{bad}]"])


def test_global_planner_plugins(tmp_path, caplog):
    smac = """planner_server:
  ros__parameters:
    GridBased: {plugin: "nav2_smac_planner/SmacPlanner2D", tolerance: 0.125,
                allow_unknown: false, cost_travel_multiplier: 2.0, max_iterations: 1000000}
"""
    overrides = mut.ros_overrides(write(tmp_path, "smac.yaml", smac))
    assert overrides == [
        "navigator.planner.use_astar=true",
        "navigator.planner.tolerance=0.125",
        "navigator.planner.allow_unknown=false",
        f"navigator.planner.cost_factor={2.0 * 50.0 / 252}",
    ]
    assert caplog.text.splitlines()[-1].endswith(
        "ignored keys planner_server.GridBased.max_iterations (no meaning here yet)"
    )
    theta = smac.replace("nav2_smac_planner/SmacPlanner2D", "nav2_theta_star_planner/ThetaStar")
    assert mut.ros_overrides(write(tmp_path, "theta.yaml", theta))[0].endswith("tolerance=0.125")
    assert "planner_server.GridBased.plugin" in caplog.text.splitlines()[-1]


def test_another_controller_s_keys_are_not_taken_for_dwb(tmp_path):
    mppi = '{plugin: "nav2_mppi_controller::MPPIController", max_vel_x: 9.0}'
    text = f"controller_server:\n  ros__parameters:\n    FollowPath: {mppi}\n"
    assert mut.ros_overrides(write(tmp_path, "mppi.yaml", text)) == []  # all of it ignored


def test_ros1_yaml_and_launch_files(tmp_path):
    assert mut.ros_overrides(write(tmp_path, "amcl.yaml", ROS1_YAML)) == [
        'amcl.odom_model_type="diff"',
        "amcl.odom_alpha3=0.8",
        "amcl.kld_err=0.03",
    ]
    assert mut.ros_overrides(write(tmp_path, "amcl.launch", LAUNCH)) == [
        'amcl.odom_model_type="omni"',
        "amcl.laser_max_beams=40",
        "amcl.selective_resampling=true",
    ]


@pytest.mark.parametrize(
    "name, text, needle",
    [
        ("a.yaml", "amcl: [1, 2\n", "malformed YAML"),
        ("a.yaml", "- 1\n", "expected a mapping"),
        ("a.launch", "<launch><node pkg='amcl'>", "malformed launch XML"),
        ("a.launch", LAUNCH.replace('default="40"', ""), r"\$\(arg beams\) has no value"),
        ("a.yaml", NAV2.replace("OmniMotionModel", "Tricycle"), "robot_model_type"),
        ("a.yaml", NAV2.replace("[-0.1, -0.1], ", "[-0.1], "), "'footprint' must be a list"),
    ],
)
def test_malformed_files_are_one_config_error(tmp_path, name, text, needle):
    with pytest.raises(ConfigError, match=needle):
        mut.ros_overrides(write(tmp_path, name, text))


def test_the_scenario_takes_a_parameter_file_under_its_overrides(tmp_path):
    path = write(tmp_path, "nav2_params.yaml", NAV2)
    scenario = load_navigation_scenario(default_scenario_file(), [f"params=[{path}]"])
    assert scenario.amcl.odom_alpha1 == 0.3 and scenario.amcl.odom_model_type == "omni-corrected"
    assert scenario.amcl.laser_max_beams == 45
    # A --set of the same key wins over the file, in any order.
    sets = ["amcl.laser_max_beams=90", f"params=[{path}]"]
    assert load_navigation_scenario(default_scenario_file(), sets).amcl.laser_max_beams == 90
    bad = write(tmp_path, "bad.yaml", NAV2.replace("alpha1: 0.3", "alpha1: -1.0"))
    with pytest.raises(ConfigError, match=f"{bad}: 'amcl.odom_alpha1' must be non-negative"):
        load_navigation_scenario(default_scenario_file(), [f"params=[{bad}]"])


def test_several_files_apply_in_order(tmp_path):
    first = write(tmp_path, "costmap.yaml", "inflation_radius: 0.9\nrobot_radius: 0.2\n")
    second = write(tmp_path, "more.yaml", "inflation_radius: 0.7\n")
    sets = [f"params=[{first}, {second}]"]
    costmap = load_navigation_scenario(default_scenario_file(), sets).navigator.costmap
    assert (costmap.inflation_radius, costmap.robot_radius) == (0.7, 0.2)


REAL = Path(__file__).resolve().parents[3] / "shared" / "real_ros" / "params"


@pytest.mark.parametrize(
    "name",
    [
        "nav2_main/nav2_params.yaml",
        "nav2_humble/nav2_params.yaml",
        "turtlebot3_humble/waffle.yaml",
        "turtlebot3_main/waffle.yaml",
        "turtlebot3_noetic/costmap_common_params_waffle.yaml",
        "turtlebot3_noetic/dwa_local_planner_params_waffle.yaml",
        "turtlebot3_noetic/local_costmap_params.yaml",
        "turtlebot3_noetic/global_costmap_params.yaml",
        "turtlebot3_noetic/move_base_params.yaml",
        "ros1_navigation/amcl_diff.launch",
        "ros1_navigation/amcl_omni.launch",
        "turtlebot3_noetic/amcl.launch",
    ],
)
def test_real_parameter_files_load_into_the_scenario(name):
    path = REAL / name
    if not path.is_file():
        pytest.skip(f"no {path} (third-party files beside the checkout, not in the repository)")
    scenario = load_navigation_scenario(default_scenario_file(), [f"params=[{path}]"])
    assert scenario.amcl.min_particles >= 1
    if name.endswith("move_base_params.yaml"):  # move_base's own key, at the top level
        assert "navigator.controller.controller_frequency=10.0" in mut.ros_overrides(path)


def test_move_base_with_teb_chooses_it_and_maps_its_keys(tmp_path):
    """The workshop's move_base: global_planner with teb_local_planner."""
    text = "base_local_planner: teb_local_planner/TebLocalPlannerROS\n"
    text += "TebLocalPlannerROS:\n  max_vel_x: 0.2\n  max_vel_x_backwards: 0.15\n"
    text += "  min_obstacle_dist: 0.1\n  dt_ref: 0.25\n  weight_obstacle: 40\n"
    text += "  xy_goal_tolerance: 0.04\n  enable_homotopy_class_planning: true\n"
    overrides = mut.ros_overrides(write(tmp_path, "teb.yaml", text))
    assert overrides == [
        'navigator.local_planner="teb"',
        "navigator.controller.max_vel_x=0.2",
        "navigator.controller.min_vel_x=-0.15",
        "navigator.teb.min_obstacle_dist=0.1",
        "navigator.teb.dt_ref=0.25",
        "navigator.teb.weight_obstacle=40",
        "navigator.controller.xy_goal_tolerance=0.04",
    ]
    scenario = load_navigation_scenario(default_scenario_file(), [f"params=[{tmp_path}/teb.yaml]"])
    assert scenario.navigator.local_planner == "teb"
    assert scenario.navigator.teb.dt_ref == 0.25
    dwa = "base_local_planner: dwa_local_planner/DWAPlannerROS\n"
    assert mut.ros_overrides(write(tmp_path, "dwa.yaml", dwa)) == ['navigator.local_planner="dwa"']
