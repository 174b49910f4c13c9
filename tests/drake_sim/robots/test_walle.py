"""Wall-E's xacro, the model Drake builds from it, and the reduced planar model
(drake_sim.robots.walle, models/walle)."""

import dataclasses as dc
import math
import re

import numpy as np
import pytest
from pydrake.geometry import Role, SceneGraph
from pydrake.math import RigidTransform
from pydrake.multibody.plant import AddMultibodyPlantSceneGraph, MultibodyPlant
from pydrake.multibody.tree import ModelInstanceIndex, SpatialInertia
from pydrake.systems.framework import Diagram, DiagramBuilder

import drake_sim.robots.walle as mut
from drake_sim.robots.walle_params import WalleParams, load_walle_params

LINKS = {"base_link", "left_wheel", "right_wheel", "imu_link", "camera_link"}
LINKS |= {"camera_optical_frame"}


@pytest.fixture(scope="module")
def default_params():
    return load_walle_params(mut.default_robot_file())


@dc.dataclass
class Built:
    params: WalleParams
    diagram: Diagram
    plant: MultibodyPlant
    scene_graph: SceneGraph
    instance: ModelInstanceIndex


def _build(params, support=False) -> Built:
    builder = DiagramBuilder()
    plant, scene_graph = AddMultibodyPlantSceneGraph(builder, time_step=2e-3)
    instance = mut.add_walle(plant, params, support=support)
    plant.Finalize()
    return Built(params, builder.Build(), plant, scene_graph, instance)


SIZES = {"default": (1.0, 1.0), "big": (1.25, 1.5), "small": (0.8, 0.7)}


@pytest.fixture(scope="module", params=SIZES.values(), ids=SIZES.keys())
def model(request, default_params) -> Built:
    return _build(default_params.scaled(length=request.param[0], mass=request.param[1]))


def test_xacro_renders_cached_and_scaled(default_params):
    default_urdf = mut.robot_urdf(default_params)
    scaled_urdf = mut.robot_urdf(default_params.scaled(length=1.25))
    supported = mut.robot_urdf(default_params, support=True)
    assert len({default_urdf, scaled_urdf, supported}) == 3
    for urdf, scale in ((default_urdf, 1.0), (scaled_urdf, 1.25)):
        size = re.search(r'<box size="([^"]+)"', urdf.read_text()).group(1)
        np.testing.assert_allclose(
            [float(v) for v in size.split()], scale * np.r_[0.12, 0.18, 0.36]
        )
    assert '<link name="front_caster">' in supported.read_text()
    assert '<link name="front_caster">' not in default_urdf.read_text()
    assert mut.robot_urdf(default_params) == default_urdf  # Cached.


def test_links_joints_and_motors(model):
    params, plant, instance = model.params, model.plant, model.instance
    assert {plant.get_body(i).name() for i in plant.GetBodyIndices(instance)} == LINKS
    for side, sign in (("left", 1), ("right", -1)):
        joint = plant.GetJointByName(f"{side}_wheel_joint", instance)
        assert joint.type_name() == "revolute"
        np.testing.assert_allclose(joint.revolute_axis(), [0, 1, 0])
        p_BW = joint.frame_on_parent().GetFixedPoseInBodyFrame().translation()
        np.testing.assert_allclose(p_BW, [0, sign * params.wheel_separation / 2, params.axle_z])
        motor = plant.GetJointActuatorByName(f"{side}_wheel_motor", instance)
        assert motor.joint().index() == joint.index()
        assert motor.effort_limit() == pytest.approx(params.motor.max_torque)
    actuated = [plant.get_joint_actuator(i).joint().name() for i in plant.GetJointActuatorIndices()]
    assert actuated == list(mut.WHEEL_JOINTS)


def test_inertias_are_computed_from_the_yaml(model):
    params, plant, instance = model.params, model.plant, model.instance
    b = params.body
    M = plant.GetBodyByName(mut.BODY_LINK, instance).default_spatial_inertia()
    expected = SpatialInertia.SolidBoxWithMass(b.mass, b.length, b.width, b.height)
    np.testing.assert_allclose(M.CopyToFullMatrix6(), expected.CopyToFullMatrix6(), rtol=1e-12)
    for side in ("left", "right"):
        M = plant.GetBodyByName(f"{side}_wheel", instance).default_spatial_inertia()
        assert M.IsPhysicallyValid()
        assert M.get_mass() == pytest.approx(params.wheel.mass)
        I = M.CalcRotationalInertia().CopyToFullMatrix3()
        assert I[1, 1] == pytest.approx(0.5 * params.wheel.mass * params.wheel.radius**2)
    total = sum(plant.get_body(i).default_mass() for i in plant.GetBodyIndices(instance))
    assert total == pytest.approx(params.total_mass)


def _pose_in_body(plant, instance, name) -> RigidTransform:
    context = plant.CreateDefaultContext()
    body = plant.GetBodyByName(mut.BODY_LINK, instance)
    frame = plant.GetBodyByName(name, instance).body_frame()
    return frame.CalcPose(context, body.body_frame())


def test_sensor_mounts_and_camera_conventions(model):
    params, plant, instance = model.params, model.plant, model.instance
    X_BI = _pose_in_body(plant, instance, mut.IMU_LINK)
    np.testing.assert_allclose(X_BI.translation(), [params.imu.x, params.imu.y, params.imu.z])
    X_BL = _pose_in_body(plant, instance, mut.CAMERA_LINK)
    c = params.camera
    np.testing.assert_allclose(X_BL.translation(), [c.x, c.y, c.z], atol=1e-12)
    # camera_link's x axis looks forward and down at the pitch below horizontal.
    pitch = math.radians(c.pitch)
    x_L = X_BL.rotation().matrix()[:, 0]
    np.testing.assert_allclose(x_L, [math.cos(pitch), 0, -math.sin(pitch)], atol=1e-12)
    # The optical frame: z along the optical axis, x right (-y of the link), y down.
    R_LC = (X_BL.inverse() @ _pose_in_body(plant, instance, mut.CAMERA_OPTICAL_FRAME)).rotation()
    np.testing.assert_allclose(R_LC.matrix(), [[0, 0, 1], [-1, 0, 0], [0, -1, 0]], atol=1e-12)
    # Upright, the optical axis meets the floor ahead of the robot.
    height = c.z - (params.axle_z - params.wheel.radius)
    assert c.x + height / math.tan(pitch) > params.body.length


def test_support_variant_stands_on_frictionless_casters(default_params):
    built = _build(default_params, support=True)
    diagram, plant, scene_graph, instance = (
        built.diagram,
        built.plant,
        built.scene_graph,
        built.instance,
    )
    context = diagram.CreateDefaultContext()
    inspector = (
        scene_graph.get_query_output_port()
        .Eval(scene_graph.GetMyContextFromRoot(context))
        .inspector()
    )
    floor_z = default_params.axle_z - default_params.wheel.radius
    xs = []
    for name in mut.CASTER_LINKS:
        body = plant.GetBodyByName(name, instance)
        (geometry,) = inspector.GetGeometries(
            plant.GetBodyFrameIdOrThrow(body.index()), Role.kProximity
        )
        friction = inspector.GetProximityProperties(geometry).GetProperty(
            "material", "coulomb_friction"
        )
        assert friction.static_friction() == 0.0
        p_BC = _pose_in_body(plant, instance, name).translation()
        assert p_BC[2] - default_params.caster.radius == pytest.approx(floor_z)
        xs.append(p_BC[0])
    assert xs[0] > 0 > xs[1]  # One in front of the axle, one behind.


def test_planar_model_matches_the_closed_form(default_params):
    """The linearisation against the textbook wheeled inverted pendulum."""
    A, B = mut.linearize_upright(default_params)
    b, w = default_params.body, default_params.wheel
    l, r = default_params.com_height, w.radius
    m11 = 3 * w.mass + b.mass  # 2 m_w + 2 J_w / r^2 with J_w = m_w r^2 / 2.
    m12 = b.mass * l
    m22 = b.mass * l**2 + b.mass * (b.length**2 + b.height**2) / 12
    det = m11 * m22 - m12**2
    assert A[mut.THETA_DOT, mut.THETA] == pytest.approx(m11 * b.mass * 9.81 * l / det, rel=1e-3)
    assert B[mut.THETA_DOT, 0] == pytest.approx(-(m11 + m12 / r) / det, rel=1e-9)
    assert B[mut.S_DOT, 0] == pytest.approx((m22 / r + m12) / det, rel=1e-9)
    np.testing.assert_allclose(A[: mut.S_DOT], np.hstack([np.zeros((2, 2)), np.eye(2)]))
    # Unstable: one pole at +sqrt(a), the rate a small lean grows.
    assert max(np.linalg.eigvals(A).real) == pytest.approx(math.sqrt(A[3, 1]))


def test_planar_model_matches_the_full_robot(model):
    """The full plant's mass matrix, seen through the rolling constraint (the body turns by
    theta, its origin moves with the axle, each wheel turns at s_dot / r - theta_dot relative
    to the body), is the planar model's."""
    params, plant, instance = model.params, model.plant, model.instance
    context = plant.CreateDefaultContext()
    M_full = plant.CalcMassMatrix(context)
    body = plant.GetBodyByName(mut.BODY_LINK, instance)
    v0 = body.floating_velocities_start_in_v()
    J = np.zeros((plant.num_velocities(), 2))
    J[v0 + 3, 0] = 1.0  # s_dot moves the body's origin along x.
    J[v0 + 1, 1] = 1.0  # theta_dot turns it about y...
    J[v0 + 3, 1] = -params.axle_z  # ... about the axle, below its origin.
    for name in mut.WHEEL_JOINTS:
        index = plant.GetJointByName(name, instance).velocity_start()
        J[index] = [1.0 / params.wheel.radius, -1.0]
    planar = mut.make_planar_model(params)
    M_planar = planar.CalcMassMatrix(planar.CreateDefaultContext())
    np.testing.assert_allclose(J.T @ M_full @ J, M_planar, rtol=1e-9)
