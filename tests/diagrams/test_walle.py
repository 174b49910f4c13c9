"""Wall-E on a course: the diagram for each mode, the camera's pose from the pitch, and a short
line-following run (diagrams.walle). Headless, simulated time, seeded IMU noise."""

import dataclasses as dc
import math

import msgpack
import numpy as np
import pytest
from pydrake.common import RandomGenerator
from pydrake.geometry import Meshcat
from pydrake.systems.analysis import Simulator

import diagrams.walle as mut
from diagrams.walle_balance import walle_start_pose
from diagrams.walle_balance_scenario import WalleStart
from diagrams.walle_scenario import course_path
from drake_sim.robots.walle import BODY_LINK, CAMERA_OPTICAL_FRAME, CASTER_LINKS
from drake_sim.systems.control.line_follower import FOLLOW
from drake_sim.systems.perception.line_detection import camera_pose_over_ground
from drake_sim.systems.perception.line_detector import FOUND, OFFSET
from drake_sim.systems.viewer.teleop import BUTTONS
from drake_sim.worlds.course import load_course
from tests.walle_course_helpers import walle_robot_and_scenario

robot, scenario = walle_robot_and_scenario()


@pytest.fixture(scope="module")
def course():
    return load_course(course_path(scenario))


def _outputs(diagram):
    return {diagram.get_output_port(i).get_name() for i in range(diagram.num_output_ports())}


@pytest.mark.parametrize("mode", ["balance", "follow", "both"])
def test_ports_and_systems_for_each_mode(course, mode):
    dut = mut.make_walle_course_diagram(dc.replace(scenario, mode=mode), robot, course)
    base = {"walle.state", "imu", "wheel_state", "pitch_estimate", "wheel_torques"}
    following = {"measurement", "command", "follower_mode"}
    expected = base | ({"status"} if mode != "follow" else set())
    assert _outputs(dut) == expected | (following if mode != "balance" else set())
    assert dut.num_input_ports() == 0  # The command comes from inside: hold, or the follower.
    plant = dut.GetSubsystemByName("plant")
    assert all(plant.HasBodyNamed(name) == (mode == "follow") for name in CASTER_LINKS)
    assert dut.HasSubsystemNamed("camera") == (mode != "balance")
    assert dut.HasSubsystemNamed("camera_pose") == (mode == "both")  # Pitch-corrected pose.
    assert dut.HasSubsystemNamed("diff_drive") == (mode == "follow")


def test_robot_starts_on_the_course_start(tmp_path):
    path = tmp_path / "c.yaml"
    path.write_text("start: {x: 1.0, y: -0.5, yaw: 90.0}\nsegments: [{straight: 1.0}]\n")
    dut = mut.make_walle_course_diagram(scenario, robot, load_course(path))
    plant = dut.GetSubsystemByName("plant")
    context = plant.CreateDefaultContext()
    X_WB = plant.EvalBodyPoseInWorld(context, plant.GetBodyByName(BODY_LINK))
    expected = walle_start_pose(WalleStart(x=1.0, y=-0.5, yaw=90.0), robot)
    assert X_WB.IsNearlyEqualTo(expected, 1e-12)


@pytest.mark.parametrize("pitch", [0.0, 6.0, -10.0])
def test_camera_pose_from_pitch_matches_the_plant(course, pitch):
    """X_GC from the pitch is what the plant's kinematics give for the robot leaning that much
    on its wheels (anywhere on the floor, any heading)."""
    diagram = mut.make_walle_course_diagram(scenario, robot, course)
    plant = diagram.GetSubsystemByName("plant")
    dut = diagram.GetSubsystemByName("camera_pose")
    context = plant.CreateDefaultContext()
    body = plant.GetBodyByName(BODY_LINK)
    X_WB = walle_start_pose(WalleStart(x=0.7, y=-0.3, yaw=35.0, pitch=pitch), robot)
    plant.SetFreeBodyPose(context, body, X_WB)
    X_BC = plant.CalcRelativeTransform(
        context, body.body_frame(), plant.GetFrameByName(CAMERA_OPTICAL_FRAME)
    )
    expected = camera_pose_over_ground(X_WB, X_BC)
    dut_context = dut.CreateDefaultContext()
    dut.get_input_port().FixValue(dut_context, [math.radians(pitch), 0.0])
    X_GC = dut.get_output_port().Eval(dut_context)
    assert X_GC.IsNearlyEqualTo(expected, 1e-9)
    assert X_GC.translation()[2] == pytest.approx(0.35, abs=0.02)  # config/walle.yaml's mount.


def test_expected_duration_is_one_lap_with_margin():
    speed = scenario.line_follower.speed
    assert mut.expected_duration(scenario, 6.0) == pytest.approx(
        1.5 * 6.0 / speed + scenario.duration_margin
    )


def test_balancing_robot_sees_the_line_and_drives_along_it(course):
    """Two seconds on the oval's first straight: the detector sees the line under the robot,
    the follower drives forward along it, the robot stays upright and on the line."""
    dut = mut.make_walle_course_diagram(scenario, robot, course)
    simulator = Simulator(dut)
    context = simulator.get_mutable_context()
    dut.SetRandomContext(context, RandomGenerator(0))
    simulator.AdvanceTo(2.0)
    measurement = dut.GetOutputPort("measurement").Eval(context)
    assert measurement[FOUND] == 1.0
    assert abs(measurement[OFFSET]) < 0.01
    v, omega = dut.GetOutputPort("command").Eval(context)
    assert v > 0.2 and abs(omega) < 0.2
    assert dut.GetOutputPort("follower_mode").Eval(context)[0] == FOLLOW
    state = dut.GetOutputPort("walle.state").Eval(context)
    x, y = state[4:6]  # The body's position after its quaternion.
    assert 0.3 < x < 0.7 and abs(y) < 0.01
    assert np.all(np.isfinite(state))


def test_teleop_drives_the_balancing_robot_in_meshcat(course):
    """In balance mode with teleop, the Meshcat buttons set the command: two presses of W
    (0.1 m/s each) and the robot rolls forward, balancing; the robot is drawn."""
    meshcat = Meshcat()
    dut = mut.make_walle_course_diagram(
        dc.replace(scenario, mode="balance"), robot, course, meshcat=meshcat, teleop=True
    )
    assert not dut.HasSubsystemNamed("camera")
    simulator = Simulator(dut)
    context = simulator.get_mutable_context()
    for _ in range(2):  # What the page sends when W is pressed.
        meshcat._InjectWebsocketMessage(msgpack.packb({"type": "button", "name": BUTTONS[0][0]}))
    simulator.AdvanceTo(2.0)
    state = dut.GetOutputPort("walle.state").Eval(context)
    assert state[4] > 0.05  # The body moved forward along x.
    assert meshcat.HasPath("/drake/illustration/walle/base_link")
