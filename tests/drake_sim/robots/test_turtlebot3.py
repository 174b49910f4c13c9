"""The TurtleBot3's xacro, the model Drake builds from it, and how it drives on a floor
(drake_sim.robots.turtlebot3, models/turtlebot3)."""

import dataclasses as dc
import math
import re

import numpy as np
import pytest
from pydrake.geometry import AddContactMaterial, HalfSpace, ProximityProperties, Role
from pydrake.math import RigidTransform
from pydrake.multibody.plant import (
    AddMultibodyPlant,
    AddMultibodyPlantSceneGraph,
    CoulombFriction,
    MultibodyPlantConfig,
)
from pydrake.multibody.tree import SpatialInertia
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import DiagramBuilder
from pydrake.systems.primitives import LogVectorOutput, MatrixGain, TrajectorySource
from pydrake.trajectories import PiecewisePolynomial

import drake_sim.robots.turtlebot3 as mut
from drake_sim.robots.turtlebot3_params import Turtlebot3Params, load_turtlebot3_params
from drake_sim.systems.control.diff_drive_controller import DiffDriveConfig, DiffDriveController
from drake_sim.systems.estimation.encoder_odometry import (
    EncoderOdometry,
    EncoderOdometryConfig,
    PlanarGroundTruth,
)

LINKS = {"base_footprint", "base_link", "left_wheel", "right_wheel", "left_caster"}
LINKS |= {"right_caster", "imu_link", "camera_rgb_frame", "camera_rgb_optical_frame"}
LINKS |= {"base_scan"}


@pytest.fixture(scope="module")
def params() -> Turtlebot3Params:
    return load_turtlebot3_params(mut.default_turtlebot3_file())


@pytest.fixture(scope="module", params=[1.0, 1.4], ids=["waffle", "scaled"])
def model(request, params):
    robot = params.scaled(length=request.param, mass=request.param)
    builder = DiagramBuilder()
    plant, scene_graph = AddMultibodyPlantSceneGraph(builder, time_step=2e-3)
    instance = mut.add_turtlebot3(plant, robot, name="tb3")
    plant.Finalize()
    diagram = builder.Build()
    return robot, plant, scene_graph, instance, diagram


def test_xacro_renders_cached_and_reads_the_yaml(params):
    urdf = mut.robot_urdf(params)
    assert mut.robot_urdf(params) == urdf  # Cached.
    scaled = mut.robot_urdf(params.scaled(length=2.0))
    assert scaled != urdf
    radii = [float(r) for r in re.findall(r'<drake:ellipsoid a="([^"]+)"', urdf.read_text())]
    assert radii == pytest.approx([params.wheel.radius] * 2)  # The wheels' contact shapes.
    assert "xacro:" not in urdf.read_text()


def test_links_frames_joints_and_motors(model):
    robot, plant, _, instance, _ = model
    assert {plant.get_body(i).name() for i in plant.GetBodyIndices(instance)} == LINKS
    footprint = plant.GetBodyByName(mut.BASE_FOOTPRINT, instance)
    assert footprint.is_floating_base_body()
    context = plant.CreateDefaultContext()
    for side, sign in (("left", 1), ("right", -1)):
        joint = plant.GetJointByName(f"{side}_wheel_joint", instance)
        assert joint.type_name() == "revolute"
        np.testing.assert_allclose(joint.revolute_axis(), [0, 1, 0])
        p_FW = joint.child_body().body_frame().CalcPose(context, footprint.body_frame())
        np.testing.assert_allclose(
            p_FW.translation(), [0, sign * robot.wheel_separation / 2, robot.wheel.radius]
        )
        motor = plant.GetJointActuatorByName(f"{side}_wheel_motor", instance)
        assert motor.joint().index() == joint.index()
        assert motor.effort_limit() == pytest.approx(robot.motor.max_torque)
    actuated = [plant.get_joint_actuator(i).joint().name() for i in plant.GetJointActuatorIndices()]
    assert actuated == list(mut.WHEEL_JOINTS)


def test_masses_and_inertias_come_from_the_dimensions(model):
    robot, plant, _, instance, _ = model
    total = sum(plant.get_body(i).default_mass() for i in plant.GetBodyIndices(instance))
    assert total == pytest.approx(robot.total_mass)
    b = robot.body
    M = plant.GetBodyByName(mut.BASE_LINK, instance).default_spatial_inertia()
    assert M.IsPhysicallyValid()
    # The chassis is a uniform box filling its envelope, centred behind and above the axle.
    p_BCm = [b.offset_x, 0.0, b.ground_clearance + b.height / 2 - robot.wheel.radius]
    np.testing.assert_allclose(M.get_com(), p_BCm, atol=1e-12)
    box = SpatialInertia.SolidBoxWithMass(b.mass, b.length, b.width, b.height)
    I_expected = box.CalcRotationalInertia().CopyToFullMatrix3()
    I_com = M.Shift(M.get_com()).CalcRotationalInertia().CopyToFullMatrix3()
    np.testing.assert_allclose(I_com, I_expected, rtol=1e-9, atol=1e-15)
    for name in mut.WHEEL_LINKS:
        M = plant.GetBodyByName(name, instance).default_spatial_inertia()
        I = M.CalcRotationalInertia().CopyToFullMatrix3()
        assert I[1, 1] == pytest.approx(0.5 * robot.wheel.mass * robot.wheel.radius**2)


def _X_F(plant, instance, name) -> RigidTransform:
    context = plant.CreateDefaultContext()
    footprint = plant.GetBodyByName(mut.BASE_FOOTPRINT, instance).body_frame()
    return plant.GetFrameByName(name, instance).CalcPose(context, footprint)


def test_sensor_frames(model):
    robot, plant, _, instance, _ = model
    for frame, mount in (
        (mut.IMU_FRAME, robot.imu),
        (mut.CAMERA_FRAME, robot.camera),
        (mut.LIDAR_FRAME, robot.lidar),
    ):
        X_FS = _X_F(plant, instance, frame)
        np.testing.assert_allclose(X_FS.translation(), [mount.x, mount.y, mount.z], atol=1e-12)
        np.testing.assert_allclose(X_FS.rotation().matrix(), np.eye(3), atol=1e-12)
    assert _X_F(plant, instance, mut.LIDAR_FRAME).translation()[2] == robot.scan_height
    # The optical frame looks forward (z along F's x), x right, y down.
    R_FC = _X_F(plant, instance, mut.CAMERA_OPTICAL_FRAME).rotation().matrix()
    np.testing.assert_allclose(R_FC, [[0, 0, 1], [-1, 0, 0], [0, -1, 0]], atol=1e-12)


def test_contact_geometry(model):
    """Sensors are visual only; the chassis, wheels and casters collide; the casters are
    frictionless and touch the floor with the wheels."""
    robot, plant, scene_graph, instance, diagram = model
    context = diagram.CreateDefaultContext()
    inspector = (
        scene_graph.get_query_output_port()
        .Eval(scene_graph.GetMyContextFromRoot(context))
        .inspector()
    )

    def geometries(name, role):
        frame = plant.GetBodyFrameIdOrThrow(plant.GetBodyByName(name, instance).index())
        return inspector.GetGeometries(frame, role)

    for name in (mut.IMU_FRAME, mut.CAMERA_FRAME, mut.LIDAR_FRAME):
        assert geometries(name, Role.kProximity) == []
        assert len(geometries(name, Role.kIllustration)) == 1
    assert len(geometries(mut.BASE_LINK, Role.kProximity)) == 2  # Plate and deck.
    for name in mut.CASTER_LINKS:
        (geometry,) = geometries(name, Role.kProximity)
        friction = inspector.GetProximityProperties(geometry).GetProperty(
            "material", "coulomb_friction"
        )
        assert friction.static_friction() == 0.0
        assert _X_F(plant, instance, name).translation()[2] == pytest.approx(robot.caster.radius)


def test_helpers(params):
    X = mut.start_pose(1.0, -2.0, math.pi / 2)
    np.testing.assert_allclose(X.translation(), [1.0, -2.0, mut.START_LIFT])
    np.testing.assert_allclose(X.rotation().matrix()[:, 0], [0, 1, 0], atol=1e-12)
    config = dc.replace(DiffDriveConfig(), **mut.drive_limits(params))
    assert config.max_linear_velocity == 0.26 and config.max_angular_velocity == 1.82
    assert mut.default_turtlebot3_file().name == "turtlebot3.yaml"


@dc.dataclass
class DriveRun:
    times: np.ndarray  # s.
    truth: np.ndarray  # 3 x n: [x, y, yaw] of base_footprint.
    odometry: np.ndarray  # 3 x n: the EncoderOdometry's pose.
    wheel_state: np.ndarray  # 4 x n.


def simulate_drive(
    segments,
    *,
    odometry: EncoderOdometryConfig | None = None,
    seed: int = 0,
    start=(0.0, 0.0, 0.0),
    time_step: float = 2e-3,
    approximation: str = "sap",
) -> DriveRun:
    """Drives the default TurtleBot3 on a flat floor (point contact, ``approximation``) through
    ``segments``, a list of ``(seconds, v, omega)`` cmd_vel commands, with the diff-drive
    controller at 100 Hz and the encoder odometry; logs at 20 Hz."""
    robot = load_turtlebot3_params(mut.default_turtlebot3_file())
    builder = DiagramBuilder()
    plant, _ = AddMultibodyPlant(
        MultibodyPlantConfig(
            time_step=time_step,
            contact_model="point",
            discrete_contact_approximation=approximation,
        ),
        builder,
    )
    floor = ProximityProperties()
    AddContactMaterial(dissipation=10.0, friction=CoulombFriction(1.0, 1.0), properties=floor)
    plant.RegisterCollisionGeometry(
        plant.world_body(), RigidTransform(), HalfSpace(), "floor", floor
    )
    instance = mut.add_turtlebot3(plant, robot)
    plant.Finalize()
    footprint = plant.GetBodyByName(mut.BASE_FOOTPRINT, instance)
    plant.SetDefaultFloatingBaseBodyPose(footprint, mut.start_pose(*start))

    encoders = builder.AddSystem(MatrixGain(mut.wheel_state_selector(plant, instance)))
    builder.Connect(plant.get_state_output_port(), encoders.get_input_port())
    config = dc.replace(DiffDriveConfig(rate=100.0), **mut.drive_limits(robot))
    drive = builder.AddSystem(
        DiffDriveController(robot=robot, config=config, upside_down_aware=False)
    )
    ends = np.cumsum([0.0] + [s[0] for s in segments])
    commands = np.array([[s[1], s[2]] for s in segments] + [[0.0, 0.0]]).T
    cmd_vel = builder.AddSystem(TrajectorySource(PiecewisePolynomial.ZeroOrderHold(ends, commands)))
    builder.Connect(cmd_vel.get_output_port(), drive.GetInputPort("command"))
    builder.Connect(encoders.get_output_port(), drive.GetInputPort("wheel_state"))
    builder.Connect(drive.GetOutputPort("wheel_torques"), plant.get_actuation_input_port())
    odom = builder.AddSystem(
        EncoderOdometry(
            wheel_radius=robot.wheel.radius,
            wheel_separation=robot.wheel_separation,
            config=odometry or EncoderOdometryConfig(),
            initial_pose=start,
            seed=seed,
        )
    )
    builder.Connect(encoders.get_output_port(), odom.GetInputPort("wheel_state"))
    truth = builder.AddSystem(PlanarGroundTruth(plant=plant, body=footprint))
    builder.Connect(plant.get_body_poses_output_port(), truth.GetInputPort("body_poses"))
    logs = [
        LogVectorOutput(port, builder, 0.05)
        for port in (
            truth.GetOutputPort("pose"),
            odom.GetOutputPort("pose"),
            encoders.get_output_port(),
        )
    ]
    diagram = builder.Build()
    simulator = Simulator(diagram)
    simulator.AdvanceTo(ends[-1])
    context = simulator.get_context()
    data = [log.FindLog(context) for log in logs]
    return DriveRun(data[0].sample_times(), data[0].data(), data[1].data(), data[2].data())


def _rates(run: DriveRun, start: float, end: float):
    """Mean speed (m/s) and yaw rate (rad/s) of the truth between two times."""
    keep = (run.times >= start) & (run.times <= end)
    t, pose = run.times[keep], run.truth[:, keep]
    speed = np.linalg.norm(pose[:2, -1] - pose[:2, 0]) / (t[-1] - t[0])
    yaw = np.unwrap(pose[2])
    return speed, (yaw[-1] - yaw[0]) / (t[-1] - t[0]), pose


APPROXIMATIONS = ["sap", "lagged", "tamsi"]


@pytest.mark.parametrize("approximation", APPROXIMATIONS)
def test_drives_straight_at_the_commanded_speed(approximation):
    run = simulate_drive(
        [(4.0, 0.2, 0.0)], start=(1.0, 2.0, math.radians(30)), approximation=approximation
    )
    speed, yaw_rate, pose = _rates(run, 1.0, 4.0)
    assert speed == pytest.approx(0.2, abs=0.005)
    assert abs(yaw_rate) < 0.005
    # It stays on the line it started along.
    heading = np.array([math.cos(math.radians(30)), math.sin(math.radians(30))])
    offsets = (pose[:2].T - [1.0, 2.0]) @ [-heading[1], heading[0]]
    assert np.max(np.abs(offsets)) < 0.005


@pytest.mark.parametrize("approximation", APPROXIMATIONS)
def test_turns_on_the_spot(approximation):
    run = simulate_drive([(4.0, 0.0, 1.0)], approximation=approximation)
    speed, yaw_rate, pose = _rates(run, 1.5, 4.0)
    assert yaw_rate == pytest.approx(1.0, abs=0.03)
    assert np.max(np.linalg.norm(run.truth[:2], axis=0)) < 0.01  # It stays where it was.


def test_speed_is_limited_to_the_waffles():
    run = simulate_drive([(3.0, 1.0, 0.0)])
    speed, _, _ = _rates(run, 1.5, 3.0)
    assert speed == pytest.approx(0.26, abs=0.005)
