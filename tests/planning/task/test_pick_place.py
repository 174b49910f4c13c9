"""PickPlaceTask on the Panda station in both modes, and on arms without fingers, in simulated
time."""

import dataclasses as dc

import numpy as np
import pytest

import planning.task.pick_place as mut
from diagrams.pickplace_scenario import load_pickplace_scenario
from diagrams.planning_station import make_planning_station
from drake_sim.base.resources import config_dir
from planning import StepReport, TaskReport
from planning.errors import PlanningError
from planning.io.scene_files import BoxSpec
from planning.task.geometry import boxes_overlap
from tests.pickplace_helpers import random_scene, run_task
from tests.robot_helpers import XARM7_YAML, vamp_robot

STEPS = list(mut.STEPS)


@pytest.fixture(scope="module")
def config():
    return load_pickplace_scenario()


class ObstacleWatch:
    """Records, at every poll, whether the simulated object overlaps the obstacle."""

    def __init__(self, config):
        self.size = config.scene.object.size
        obstacle = config.scene.obstacle
        from diagrams.scene_boxes import box_pose

        self.obstacle = (obstacle.size, box_pose(obstacle))
        self.overlaps, self.lowest = 0, np.inf

    def __call__(self, interface):
        X_WO = interface.object_pose()
        if boxes_overlap(self.size, X_WO, *self.obstacle):
            self.overlaps += 1
        self.lowest = min(self.lowest, X_WO.translation()[2])


@pytest.mark.parametrize("mode", ["kinematic", "physics"])
def test_default_task_succeeds(config, mode):
    watch = ObstacleWatch(config)
    report, _ = run_task(config, mode, monitor=watch)
    assert isinstance(report, TaskReport) and report.success, report.reason
    assert all(isinstance(s, StepReport) for s in report.steps)
    assert [s.name for s in report.steps] == STEPS and all(s.success for s in report.steps)
    assert report.place_error_m <= 0.02
    assert watch.overlaps == 0  # never through the obstacle
    assert watch.lowest > 0.5 * config.scene.object.size[2] - 0.005  # nor through the table
    data = report.to_dict()
    for key in ("success", "place_error_m", "object_final_position", "planning_time_s"):
        assert key in data
    assert data["planning_time_s"] == pytest.approx(
        sum(s["planning_time_s"] for s in data["steps"])
    )


@pytest.mark.parametrize(
    "change,reason",
    [
        ({"object": BoxSpec([0.045, 0.045, 0.08], [1.3, -0.25, 0.04], mass=0.1)}, "out of reach"),
        ({"object": BoxSpec([0.045, 0.045, 0.08], [0.5, 0.0, 0.04], mass=0.1)}, "overlaps"),
        ({"object": BoxSpec([0.09, 0.10, 0.08], [0.5, -0.25, 0.04], mass=0.1)}, "wider"),
    ],
    ids=["out_of_reach", "inside_obstacle", "too_wide"],
)
def test_impossible_scenes_are_reported_not_tried(config, change, reason):
    scene = dc.replace(config.scene, **change)
    report, interface = run_task(dc.replace(config, scene=scene), "kinematic")
    assert report.impossible and not report.success and report.failed_step == "check"
    assert reason in report.reason
    assert [s.name for s in report.steps] == ["check"] and interface.time == 0.0  # no motion


def test_place_inside_the_obstacle_is_impossible(config):
    scene = dc.replace(config.scene, place=dc.replace(config.scene.place, position=[0.5, 0, 0.04]))
    report, _ = run_task(dc.replace(config, scene=scene), "kinematic")
    assert report.impossible and "place target" in report.reason


def run_random(config, mode, count=20, seed=7):
    rng = np.random.default_rng(seed)
    reports = []
    for _ in range(count):
        scene = random_scene(rng, config.scene)
        reports.append(run_task(dc.replace(config, scene=scene), mode)[0])
    return reports


def test_random_scenes_kinematic(config):
    reports = run_random(config, "kinematic")
    failures = [(r.failed_step, r.reason) for r in reports if not r.success]
    assert not failures
    assert max(r.place_error_m for r in reports) < 1e-3


@pytest.mark.slow
def test_random_scenes_physics(config):
    reports = run_random(config, "physics")
    failures = [(r.failed_step, r.reason) for r in reports if not r.success]
    assert len(failures) <= 1, failures
    assert max(r.place_error_m for r in reports if r.success) <= 0.02


def test_options_defaults():
    dut = mut.PickPlaceOptions()
    assert dut.max_object_width < 0.08 and dut.place_tolerance == 0.02


def test_an_arm_without_fingers_picks_with_a_virtual_gripper(tmp_path):
    """The xArm 7 of example-robot-data (no gripper) in the kinematic station: its grasp frame
    5 mm beyond the flange, on the object's top; closing holds the object at the tool."""
    arm = tmp_path / "xarm7.yaml"
    arm.write_text(XARM7_YAML)
    config = load_pickplace_scenario(
        overrides=[
            f"robot.model.description={arm}",
            "initial_configuration=home",
            "mode=kinematic",
            "task.grasp_depth=0.0",
            "task.tool_xyz=[0.0, 0.0, 0.005]",
        ]
    )
    watch = ObstacleWatch(config)
    report, interface = run_task(config, "kinematic", monitor=watch)
    assert report.success, report.reason
    assert [s.name for s in report.steps] == STEPS
    close = report.steps[STEPS.index("close_gripper")]
    assert "virtual gripper at 0.50 (holding an object)" in close.message
    assert report.place_error_m <= 0.02 and watch.overlaps == 0
    # Released on the table: the object's bottom place_clearance above the top (z = 0).
    z = report.object_final_position[2]
    assert z == pytest.approx(
        0.5 * config.scene.object.size[2] + config.task.place_clearance, abs=1e-3
    )
    assert interface.layout.num_fingers == 0


def test_a_virtual_gripper_closes_on_nothing_away_from_the_object(tmp_path):
    arm = tmp_path / "xarm7.yaml"
    arm.write_text(XARM7_YAML)
    sets = [f"robot.model.description={arm}", "initial_configuration=home", "mode=kinematic"]
    interface = make_planning_station(load_pickplace_scenario(overrides=sets))
    result = interface.close_gripper()
    assert result.success and not result.grasped and result.finger_position == 0.0
    with pytest.raises(PlanningError, match=r"outside \[0, 1\]"):
        interface.move_gripper(1.5)
    assert interface.open_gripper().finger_position == 1.0


@pytest.mark.slow
def test_the_ur5_scenario_picks_and_places():
    """``config/pickplace_ur5.yaml``: VAMP's UR5 (fixed Robotiq fingers) on its pedestal, in the
    kinematic station (slow: its description, meshes cut into pieces and clearance tables are
    made on first use)."""
    vamp_robot("ur5")
    config = load_pickplace_scenario(config_dir() / "pickplace_ur5.yaml")
    watch = ObstacleWatch(config)
    report, interface = run_task(config, "kinematic", monitor=watch)
    assert report.success, report.reason
    assert report.place_error_m <= 0.02 and watch.overlaps == 0
    assert interface.layout.robot == "ur5_robotiq85" and interface.layout.num_joints == 6
