"""Wall-E on a flat floor: the plant, its IMU, pitch estimator, encoders, a driver, pushes.

``add_walle_controls`` wires the sensors and controllers to a robot already in a plant (for a
diagram that brings its own floor, a course, a camera); ``make_walle_diagram`` builds the
whole thing on a flat floor (``drake_sim.runs.walle_track.run_walle`` simulates it headless and
measures what it did).
"""

import math

import numpy as np
from pydrake.geometry import Meshcat
from pydrake.math import RigidTransform, RollPitchYaw
from pydrake.multibody.plant import AddMultibodyPlant, MultibodyPlant
from pydrake.systems.framework import Diagram, DiagramBuilder
from pydrake.systems.primitives import ConstantVectorSource, LogVectorOutput, MatrixGain
from pydrake.visualization import ApplyVisualizationConfig

from diagrams.ddrive_world import add_ground
from diagrams.walle_balance_scenario import WalleBalanceScenario, WalleStart
from drake_sim.robots.walle import BODY_LINK, WHEEL_JOINTS, add_walle
from drake_sim.robots.walle_params import WalleParams
from drake_sim.systems.control.balance_controller import BalanceController
from drake_sim.systems.control.diff_drive_controller import DiffDriveController
from drake_sim.systems.estimation.pitch_estimator import PitchEstimator
from drake_sim.systems.pushes import PushSchedule
from drake_sim.systems.sensors.imu import add_imu

ROBOT_NAME = "walle"
"""The robot's model instance name."""
LOGGED = ("state", "pitch_estimate", "wheel_torques")
"""Signals logged every ``scenario.log_period``: the diagram has a ``log_<name>`` sink each
(``state`` is the robot's plant state: the ground truth)."""


def walle_start_pose(start: WalleStart, robot: WalleParams) -> RigidTransform:
    """X_WB of the robot with its wheels on the floor at ``start`` (leaning ``start.pitch``
    about its axle). The axle is lifted 1 mm so the first step does not start in contact."""
    R_WB = RollPitchYaw(0.0, math.radians(start.pitch), math.radians(start.yaw)).ToRotationMatrix()
    p_WA = np.array([start.x, start.y, robot.wheel.radius])  # The axle's midpoint.
    return RigidTransform(R_WB, p_WA - R_WB @ np.array([0.0, 0.0, robot.axle_z]))


def wheel_encoders(plant: MultibodyPlant, instance) -> np.ndarray:
    """The 4 x (nq + nv) matrix that picks [q_left, q_right, v_left, v_right] (rad, rad/s)
    from the plant's full state."""
    joints = [plant.GetJointByName(name, instance) for name in WHEEL_JOINTS]
    rows = [j.position_start() for j in joints]
    rows += [plant.num_positions() + j.velocity_start() for j in joints]
    return np.eye(plant.num_multibody_states())[rows]


def add_walle_controls(
    builder: DiagramBuilder,
    plant: MultibodyPlant,
    instance,
    scenario: WalleBalanceScenario,
    robot: WalleParams,
) -> dict:
    """Adds the IMU, wheel encoders, pitch estimator, pushes and ``scenario.driver`` for the
    robot ``instance`` of the finalised ``plant`` (added with ``add_walle``), and connects the
    driver's torques to the plant.

    Returns:
        The ports by name: ``cmd_vel`` (the driver's ``[v, omega]`` input, m/s and rad/s;
        None with no driver), and outputs ``imu``, ``wheel_state``, ``pitch_estimate``
        (``[theta, theta_dot]``, rad, rad/s), ``wheel_torques`` (N m) and ``status`` (the
        balance controller's, or None).
    """
    body = plant.GetBodyByName(BODY_LINK, instance)
    p_BS = np.array([robot.imu.x, robot.imu.y, robot.imu.z])
    imu = add_imu(builder, plant, body, scenario.imu, p_BS=p_BS)
    encoders = builder.AddNamedSystem("wheel_encoders", MatrixGain(wheel_encoders(plant, instance)))
    builder.Connect(plant.get_state_output_port(), encoders.get_input_port())
    estimator = builder.AddNamedSystem(
        "pitch_estimator",
        PitchEstimator(wheel_radius=robot.wheel.radius, config=scenario.pitch_estimator),
    )
    builder.Connect(imu.GetOutputPort("imu"), estimator.GetInputPort("imu"))
    builder.Connect(encoders.get_output_port(), estimator.GetInputPort("wheel_state"))
    if scenario.pushes:  # Evaluated at every plant step: only when there is something to do.
        pushes = builder.AddNamedSystem(
            "pushes",
            PushSchedule(
                body_index=body.index(), p_BoBq_B=[0.0, 0.0, robot.top_z], pushes=scenario.pushes
            ),
        )
        builder.Connect(pushes.get_output_port(), plant.get_applied_spatial_force_input_port())

    ports = {"cmd_vel": None, "status": None}
    if scenario.driver == "balance":
        driver = builder.AddNamedSystem(
            "balance_controller", BalanceController(robot=robot, config=scenario.balance)
        )
        builder.Connect(estimator.get_output_port(), driver.GetInputPort("pitch"))
        ports["status"] = driver.GetOutputPort("status")
    elif scenario.driver == "diff_drive":
        driver = builder.AddNamedSystem(
            "diff_drive", DiffDriveController(robot=robot, config=scenario.drive)
        )
        builder.Connect(imu.GetOutputPort("imu"), driver.GetInputPort("imu"))
    else:
        driver = builder.AddNamedSystem("motors_off", ConstantVectorSource(np.zeros(2)))
    if scenario.driver != "none":
        builder.Connect(encoders.get_output_port(), driver.GetInputPort("wheel_state"))
        ports["cmd_vel"] = driver.GetInputPort("command")
    torques = driver.get_output_port(0)
    builder.Connect(torques, plant.get_actuation_input_port(instance))
    ports.update(
        imu=imu.GetOutputPort("imu"),
        wheel_state=encoders.get_output_port(),
        pitch_estimate=estimator.get_output_port(),
        wheel_torques=torques,
    )
    return ports


def make_walle_diagram(
    scenario: WalleBalanceScenario, robot: WalleParams, *, meshcat: Meshcat | None = None
) -> Diagram:
    """Builds Wall-E on a flat floor with its sensors, ``scenario.driver`` and the pushes.

    The follow variant (support casters) is built when the driver is ``"diff_drive"``.

    Exported ports: input ``cmd_vel`` (``[v, omega]``, m/s and rad/s, ROS's ``cmd_vel``; not
    there when the driver is ``"none"``); outputs ``walle.state`` (the robot's plant state,
    the ground truth), ``imu``, ``wheel_state``, ``pitch_estimate``, ``wheel_torques`` and
    ``status`` (balance controller only). Loggers ``log_<name>`` record ``LOGGED``.
    """
    builder = DiagramBuilder()
    plant, _ = AddMultibodyPlant(scenario.plant, builder)
    add_ground(plant, scenario.ground)
    instance = add_walle(plant, robot, name=ROBOT_NAME, support=scenario.driver == "diff_drive")
    plant.Finalize()
    plant.SetDefaultFloatingBaseBodyPose(
        plant.GetBodyByName(BODY_LINK, instance), walle_start_pose(scenario.start, robot)
    )
    ports = add_walle_controls(builder, plant, instance, scenario, robot)
    if ports["cmd_vel"] is not None:
        builder.ExportInput(ports.pop("cmd_vel"), "cmd_vel")
    ports["state"] = plant.get_state_output_port(instance)
    return build_walle_diagram(builder, ports, scenario, LOGGED, meshcat, f"{ROBOT_NAME}_balance")


def build_walle_diagram(
    builder: DiagramBuilder,
    ports: dict,
    scenario: WalleBalanceScenario,
    logged,
    meshcat: Meshcat | None,
    name: str,
) -> Diagram:
    """Exports ``ports`` (by name; ``state`` as ``walle.state``; None ones skipped), logs the
    ``logged`` ones every ``scenario.log_period`` (sinks ``log_<name>``), draws in ``meshcat``
    (if any) with ``scenario.visualization``, and builds the diagram called ``name``."""
    for key, port in ports.items():
        if port is not None:
            builder.ExportOutput(port, f"{ROBOT_NAME}.state" if key == "state" else key)
    for key in logged:
        LogVectorOutput(ports[key], builder, scenario.log_period).set_name(f"log_{key}")
    if meshcat is not None:
        ApplyVisualizationConfig(scenario.visualization, builder, meshcat=meshcat)
    diagram = builder.Build()
    diagram.set_name(name)
    return diagram
