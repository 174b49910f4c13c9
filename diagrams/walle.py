"""Wall-E on a line-following course: the course's floor, the robot at its start, its IMU and
balance (or diff-drive) controls, the line camera, the ``LineDetector`` and ``LineFollower``.

``make_walle_course_diagram`` builds it; a pure builder (nothing is simulated here).
"""

import dataclasses as dc

import numpy as np
from pydrake.geometry import Meshcat
from pydrake.math import RigidTransform
from pydrake.multibody.plant import AddMultibodyPlant
from pydrake.systems.framework import Diagram, DiagramBuilder
from pydrake.systems.primitives import ConstantVectorSource

from diagrams.walle_balance import (
    LOGGED,
    ROBOT_NAME,
    add_walle_controls,
    build_walle_diagram,
    walle_start_pose,
)
from diagrams.walle_balance_scenario import WalleStart
from diagrams.walle_scenario import WalleScenario
from drake_sim.robots.walle import BODY_LINK, CAMERA_OPTICAL_FRAME, add_walle
from drake_sim.robots.walle_params import WalleParams
from drake_sim.systems.control.line_follower import LineFollower
from drake_sim.systems.perception.camera_pose import CameraPoseFromPitch
from drake_sim.systems.perception.line_detector import LineDetector
from drake_sim.systems.sensors.camera import add_camera
from drake_sim.systems.viewer.teleop import MeshcatTeleop, TeleopConfig
from drake_sim.worlds.course import Course
from drake_sim.worlds.course_floor import add_course_floor

COURSE_LOGGED = (*LOGGED, "measurement", "command", "follower_mode")
"""Signals logged in the line-following modes (``follow``, ``both``); ``balance`` logs
``LOGGED``. The diagram has a ``log_<name>`` sink each."""


def _robot_scenario(scenario: WalleScenario, course: Course):
    """The nested robot scenario with the course's start, the mode's driver and controller."""
    start = WalleStart(x=course.start.x, y=course.start.y, yaw=course.start.yaw, pitch=0.0)
    walle = scenario.walle
    return dc.replace(
        walle,
        start=start,
        driver="diff_drive" if scenario.mode == "follow" else "balance",
        balance=dc.replace(walle.balance, controller=scenario.controller),
    )


def make_walle_course_diagram(
    scenario: WalleScenario,
    robot: WalleParams,
    course: Course,
    *,
    meshcat: Meshcat | None = None,
    teleop: bool = False,
) -> Diagram:
    """Builds Wall-E on ``course`` for ``scenario.mode`` (see ``MODES``).

    In ``balance`` mode the ``cmd_vel`` is zero (hold position), or the ``MeshcatTeleop``'s
    command with ``teleop`` (needs ``meshcat``); no camera. In ``follow`` and ``both`` the
    camera on ``camera_optical_frame`` feeds the ``LineDetector`` (posed by the estimated pitch
    when balancing, upright on the follow variant's casters) and its ``LineFollower`` drives
    ``cmd_vel``.

    Exported outputs: ``walle.state`` (the robot's plant state, the ground truth),
    ``pitch_estimate``, ``wheel_torques``, ``status`` (balancing only) and, when following,
    ``measurement``, ``command`` and ``follower_mode``. Loggers ``log_<name>`` record
    ``LOGGED`` (balance) or ``COURSE_LOGGED`` every ``scenario.walle.log_period``.
    """
    walle = _robot_scenario(scenario, course)
    builder = DiagramBuilder()
    plant, scene_graph = AddMultibodyPlant(walle.plant, builder)
    add_course_floor(
        plant, course, mu_static=walle.ground.mu_static, mu_dynamic=walle.ground.mu_dynamic
    )
    instance = add_walle(plant, robot, name=ROBOT_NAME, support=scenario.mode == "follow")
    plant.Finalize()
    body = plant.GetBodyByName(BODY_LINK, instance)
    plant.SetDefaultFloatingBaseBodyPose(body, walle_start_pose(walle.start, robot))
    ports = add_walle_controls(builder, plant, instance, walle, robot)
    ports["state"] = plant.get_state_output_port(instance)
    logged = LOGGED
    if scenario.mode == "balance":
        if teleop:
            source = MeshcatTeleop(meshcat=meshcat, config=TeleopConfig())
            source = builder.AddNamedSystem("teleop", source)
        else:
            source = builder.AddNamedSystem("hold", ConstantVectorSource(np.zeros(2)))
        builder.Connect(source.get_output_port(), ports["cmd_vel"])
    else:
        ports.update(_add_line_following(builder, plant, scene_graph, scenario, robot, ports))
        logged = COURSE_LOGGED
    del ports["cmd_vel"]
    return build_walle_diagram(builder, ports, walle, logged, meshcat, f"{ROBOT_NAME}_course")


def _add_line_following(builder, plant, scene_graph, scenario, robot, ports) -> dict:
    """Adds the camera, the detector and the follower, and connects the follower's command
    to ``ports["cmd_vel"]``. Returns the new output ports by name."""
    instance = plant.GetModelInstanceByName(ROBOT_NAME)
    frame = plant.GetFrameByName(CAMERA_OPTICAL_FRAME, instance)
    camera = add_camera(
        builder,
        plant=plant,
        scene_graph=scene_graph,
        frame=frame,
        X_FC=RigidTransform(),
        config=scenario.camera,
    )
    body = plant.GetBodyByName(BODY_LINK, instance)
    X_BC = plant.CalcRelativeTransform(plant.CreateDefaultContext(), body.body_frame(), frame)
    pose = CameraPoseFromPitch(robot=robot, X_BC=X_BC)
    detector = builder.AddNamedSystem(
        "line_detector",
        LineDetector(camera=scenario.camera, X_GC=pose.pose(0.0), config=scenario.line_detector),
    )
    builder.Connect(camera.color_image_output_port(), detector.GetInputPort("color_image"))
    if scenario.mode == "both":
        builder.AddNamedSystem("camera_pose", pose)
        builder.Connect(ports["pitch_estimate"], pose.get_input_port())
        builder.Connect(pose.get_output_port(), detector.GetInputPort("camera_pose"))
    follower = builder.AddNamedSystem("line_follower", LineFollower(config=scenario.line_follower))
    builder.Connect(detector.GetOutputPort("measurement"), follower.GetInputPort("measurement"))
    builder.Connect(follower.GetOutputPort("command"), ports["cmd_vel"])
    return {
        "measurement": detector.GetOutputPort("measurement"),
        "command": follower.GetOutputPort("command"),
        "follower_mode": follower.GetOutputPort("mode"),
    }


def expected_duration(scenario: WalleScenario, length: float) -> float:
    """Simulated seconds for one lap of a course ``length`` m long at the follower's cruise
    speed: 1.5 x length / speed + ``scenario.duration_margin``."""
    return 1.5 * length / scenario.line_follower.speed + scenario.duration_margin
