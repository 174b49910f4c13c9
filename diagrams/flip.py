"""The flipping robot: world, IMU, odometry and either the flip controller or teleop."""

import numpy as np
from pydrake.geometry import Meshcat
from pydrake.multibody.plant import MultibodyPlant
from pydrake.systems.framework import Diagram, DiagramBuilder
from pydrake.systems.primitives import LogVectorOutput, MatrixGain
from pydrake.visualization import ApplyVisualizationConfig

from diagrams.ddrive_world import ROBOT_NAME, add_ddrive_world, robot_start_pose
from diagrams.flip_scenario import FlipScenario
from drake_sim.robots.ddrive import BODY_LINK, LEFT_WHEEL_JOINT, RIGHT_WHEEL_JOINT
from drake_sim.robots.ddrive_params import RobotParams
from drake_sim.systems.control.diff_drive_controller import DiffDriveController
from drake_sim.systems.control.flip_controller import FlipController
from drake_sim.systems.control.wheel_drivers import make_wheel_drivers
from drake_sim.systems.estimation.odometry import AxleGroundTruth, WheelOdometry, axle_pose
from drake_sim.systems.sensors.imu import add_imu
from drake_sim.systems.viewer.teleop import MeshcatTeleop
from drake_sim.systems.viewer.trails import TrailVisualizer

LOGGED = (
    "true_pose",
    "odometry_pose",
    "naive_pose",
    "status",
    "wheel_torques",
    "wheel_state",
    "distance",
)
"""Signals logged every ``scenario.log_period``: the diagram has a ``log_<name>`` sink each."""


def wheel_state_selector(plant: MultibodyPlant, instance) -> np.ndarray:
    """The 4 x (nq + nv) matrix that picks [q_left, q_right, v_left, v_right] from the plant's
    full state: the wheel encoders."""
    nq = plant.num_positions()
    S = np.zeros((4, nq + plant.num_velocities()))
    for i, name in enumerate((LEFT_WHEEL_JOINT, RIGHT_WHEEL_JOINT)):
        joint = plant.GetJointByName(name, instance)
        S[i, joint.position_start()] = 1.0
        S[2 + i, nq + joint.velocity_start()] = 1.0
    return S


CONTROLLERS = ("flip", "teleop", "cmd_vel")
"""What drives the robot: the flip controller; a diff-drive controller following Meshcat keys;
or a diff-drive controller following the exported ``cmd_vel`` input port."""


def make_flip_diagram(
    scenario: FlipScenario,
    robot: RobotParams,
    *,
    meshcat: Meshcat | None = None,
    controller: str = "flip",
) -> Diagram:
    """Builds the robot in its world with its sensors and a controller.

    ``controller`` is one of ``CONTROLLERS``: "flip", the ``FlipController`` (one torque,
    fanned out to both wheels); "teleop", a ``DiffDriveController`` following Meshcat keyboard
    buttons (needs ``meshcat``); "cmd_vel", a ``DiffDriveController`` following the exported
    input port ``cmd_vel`` (``[v, omega]``, m/s and rad/s, in the body frame).

    Exported outputs: ``imu``, ``wheel_state``, ``odometry_pose``, ``odometry_twist``,
    ``odometry_covariance``, ``naive_pose``, ``distance``, ``true_pose``, ``wheel_torques``,
    and ``status`` (flip controller only). Loggers ``log_<name>`` record ``LOGGED``.
    """
    if controller not in CONTROLLERS:
        raise ValueError(f"unknown controller {controller!r}; expected one of {CONTROLLERS}")
    if controller == "teleop" and meshcat is None:
        raise ValueError("teleop needs a Meshcat for its keyboard buttons")
    builder = DiagramBuilder()
    world = add_ddrive_world(builder, scenario.scene, robot)
    plant, instance = world.plant, world.robot
    body = plant.GetBodyByName(BODY_LINK, instance)

    # The IMU sits on the axle's midpoint, so it feels the acceleration the odometry tracks.
    imu = add_imu(builder, plant, body, scenario.imu, p_BS=np.array([robot.axle_x, 0.0, 0.0]))
    encoders = builder.AddNamedSystem(
        "wheel_encoders", MatrixGain(wheel_state_selector(plant, instance))
    )
    builder.Connect(plant.get_state_output_port(), encoders.get_input_port())
    start = axle_pose(robot_start_pose(scenario.scene.robot_pose, robot), robot)
    odometry = builder.AddNamedSystem(
        "odometry",
        WheelOdometry(robot=robot, config=scenario.odometry, initial_pose=start),
    )
    builder.Connect(encoders.get_output_port(), odometry.GetInputPort("wheel_state"))
    builder.Connect(imu.GetOutputPort("imu"), odometry.GetInputPort("imu"))
    for name in ("delta_velocity", "delta_angle"):
        builder.Connect(imu.GetOutputPort(name), odometry.GetInputPort(name))
    truth = builder.AddNamedSystem(
        "ground_truth", AxleGroundTruth(plant=plant, body=body, robot=robot)
    )
    builder.Connect(plant.get_state_output_port(), truth.GetInputPort("plant_state"))

    status = None
    if controller == "flip":
        flipper = builder.AddNamedSystem(
            "flip_controller", FlipController(robot=robot, config=scenario.flip)
        )
        builder.Connect(imu.GetOutputPort("imu"), flipper.GetInputPort("imu"))
        builder.Connect(encoders.get_output_port(), flipper.GetInputPort("wheel_state"))
        # One torque command for both wheels; their drivers keep them at the same speed.
        drivers = builder.AddSystem(
            make_wheel_drivers(robot, sync_response_time=scenario.flip.wheel_sync_response_time)
        )
        builder.Connect(
            flipper.GetOutputPort("wheel_torque"), drivers.GetInputPort("torque_command")
        )
        builder.Connect(encoders.get_output_port(), drivers.GetInputPort("wheel_state"))
        torques = drivers.GetOutputPort("wheel_torques")
        status = flipper.GetOutputPort("status")
    else:
        drive = builder.AddNamedSystem(
            "diff_drive", DiffDriveController(robot=robot, config=scenario.drive)
        )
        builder.Connect(encoders.get_output_port(), drive.GetInputPort("wheel_state"))
        builder.Connect(imu.GetOutputPort("imu"), drive.GetInputPort("imu"))
        if controller == "teleop":
            keys = builder.AddNamedSystem(
                "teleop", MeshcatTeleop(meshcat=meshcat, config=scenario.teleop)
            )
            builder.Connect(keys.GetOutputPort("command"), drive.GetInputPort("command"))
        else:
            builder.ExportInput(drive.GetInputPort("command"), "cmd_vel")
        torques = drive.GetOutputPort("wheel_torques")
    builder.Connect(torques, plant.get_actuation_input_port(instance))

    outputs = {
        "imu": imu.GetOutputPort("imu"),
        "wheel_state": encoders.get_output_port(),
        "odometry_pose": odometry.GetOutputPort("pose"),
        "odometry_twist": odometry.GetOutputPort("twist"),
        "odometry_covariance": odometry.GetOutputPort("covariance"),
        "naive_pose": odometry.GetOutputPort("naive_pose"),
        "distance": odometry.GetOutputPort("distance"),
        "true_pose": truth.GetOutputPort("pose"),
        "wheel_torques": torques,
    }
    if status is not None:
        outputs["status"] = status
    for name, port in outputs.items():
        builder.ExportOutput(port, name)
    for name in LOGGED:
        if name in outputs:
            logger = LogVectorOutput(outputs[name], builder, scenario.log_period)
            logger.set_name(f"log_{name}")

    if meshcat is not None:
        ApplyVisualizationConfig(scenario.scene.visualization, builder, meshcat=meshcat)
        trails = builder.AddNamedSystem(
            "trails", TrailVisualizer(meshcat=meshcat, period=scenario.trail_period)
        )
        builder.Connect(odometry.GetOutputPort("pose"), trails.GetInputPort("odometry_pose"))
        builder.Connect(truth.GetOutputPort("pose"), trails.GetInputPort("true_pose"))
    diagram = builder.Build()
    diagram.set_name(f"{ROBOT_NAME}_flip")
    return diagram
