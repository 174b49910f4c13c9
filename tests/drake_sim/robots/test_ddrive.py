"""The robot's xacro and the model Drake builds from it (drake_sim.robots.ddrive, models/ddrive)."""

import numpy as np
import pytest
from pydrake.geometry import Role
from pydrake.multibody.plant import AddMultibodyPlantSceneGraph
from pydrake.multibody.tree import SpatialInertia
from pydrake.systems.framework import DiagramBuilder

import drake_sim.robots.ddrive as mut
from drake_sim.robots.ddrive_params import load_robot_params

LINKS = ("base_link", "left_wheel", "right_wheel", "bottom_caster", "top_caster")


@pytest.fixture(scope="module")
def default_params():
    return load_robot_params(mut.default_robot_file())


def _build(params):
    builder = DiagramBuilder()
    plant, scene_graph = AddMultibodyPlantSceneGraph(builder, time_step=2e-3)
    instance = mut.add_robot(plant, params)
    plant.Finalize()
    diagram = builder.Build()
    return diagram, plant, scene_graph, instance


@pytest.fixture(
    scope="module", params=[(1.0, 1.0), (1.25, 1.5), (0.8, 0.7)], ids=["default", "big", "small"]
)
def model(request, default_params):
    length, mass = request.param
    params = default_params.scaled(length=length, mass=mass)
    return (params, *_build(params))


def test_xacro_renders_for_default_and_scaled(default_params):
    default_urdf = mut.robot_urdf(default_params)
    scaled_urdf = mut.robot_urdf(default_params.scaled(length=1.25))
    assert default_urdf != scaled_urdf
    assert 'box size="0.4 0.26 0.1"' in default_urdf.read_text()
    assert 'box size="0.5 0.325 0.125"' in scaled_urdf.read_text()
    # Cached: the same inputs give the same file without re-running xacro.
    assert mut.robot_urdf(default_params) == default_urdf


def test_links_joints_and_motors(model):
    params, _, plant, _, instance = model
    names = {plant.get_body(i).name() for i in plant.GetBodyIndices(instance)}
    assert names == set(LINKS)
    for side in ("left", "right"):
        joint = plant.GetJointByName(f"{side}_wheel_joint", instance)
        assert joint.type_name() == "revolute"
        np.testing.assert_allclose(joint.revolute_axis(), [0, 1, 0])
        motor = plant.GetJointActuatorByName(f"{side}_wheel_motor", instance)
        assert motor.joint().index() == joint.index()
        assert motor.effort_limit() == pytest.approx(params.motor.max_torque)
    assert plant.num_actuators() == 2


def test_inertias_are_physical_and_masses_match_yaml(model):
    params, _, plant, _, instance = model
    expected = {
        "base_link": params.body.mass,
        "left_wheel": params.wheel.mass,
        "right_wheel": params.wheel.mass,
        "bottom_caster": params.caster.mass,
        "top_caster": params.caster.mass,
    }
    for name, mass in expected.items():
        body = plant.GetBodyByName(name, instance)
        M = body.default_spatial_inertia()
        assert M.get_mass() == pytest.approx(mass)
        assert M.IsPhysicallyValid()
        I = M.CalcRotationalInertia().CopyToFullMatrix3()
        moments = np.linalg.eigvalsh(I)
        assert moments.min() > 0
        assert moments[0] + moments[1] >= moments[2] * (1 - 1e-12)  # triangle inequality
    total = sum(plant.GetBodyByName(n, instance).default_mass() for n in LINKS)
    assert total == pytest.approx(params.total_mass)


def test_box_inertia_is_computed_from_dimensions(default_params):
    _, plant, _, instance = _build(default_params)
    b = default_params.body
    I = plant.GetBodyByName("base_link", instance).default_spatial_inertia()
    expected = SpatialInertia.SolidBoxWithMass(b.mass, b.length, b.width, b.height)
    np.testing.assert_allclose(
        I.CopyToFullMatrix6(), expected.CopyToFullMatrix6(), rtol=1e-12, atol=1e-15
    )


def _collision_geometry(plant, scene_graph, diagram, body):
    context = diagram.CreateDefaultContext()
    inspector = (
        scene_graph.get_query_output_port()
        .Eval(scene_graph.GetMyContextFromRoot(context))
        .inspector()
    )
    (geometry,) = inspector.GetGeometries(
        plant.GetBodyFrameIdOrThrow(body.index()), Role.kProximity
    )
    return inspector, geometry


def test_casters_frictionless_and_symmetric(model):
    params, diagram, plant, scene_graph, instance = model
    placements = {}
    for side in ("bottom", "top"):
        body = plant.GetBodyByName(f"{side}_caster", instance)
        inspector, geometry = _collision_geometry(plant, scene_graph, diagram, body)
        friction = inspector.GetProximityProperties(geometry).GetProperty(
            "material", "coulomb_friction"
        )
        assert friction.static_friction() == 0.0
        assert friction.dynamic_friction() == 0.0
        assert inspector.GetShape(geometry).radius() == pytest.approx(params.caster.radius)
        joint = plant.GetJointByName(f"{side}_caster_joint", instance)
        placements[side] = joint.frame_on_parent().GetFixedPoseInBodyFrame().translation()
    bottom, top = placements["bottom"], placements["top"]
    np.testing.assert_allclose(top, bottom * [1, 1, -1])
    assert bottom[0] < 0 < bottom[0] + params.body.length  # at the rear
    assert bottom[2] == pytest.approx(-(params.wheel.radius - params.caster.radius))


def test_wheels_have_friction_and_sit_at_the_front(model):
    params, diagram, plant, scene_graph, instance = model
    for side, sign in (("left", 1), ("right", -1)):
        body = plant.GetBodyByName(f"{side}_wheel", instance)
        inspector, geometry = _collision_geometry(plant, scene_graph, diagram, body)
        friction = inspector.GetProximityProperties(geometry).GetProperty(
            "material", "coulomb_friction"
        )
        assert friction.static_friction() >= 0.5
        X_BW = plant.GetJointByName(f"{side}_wheel_joint", instance).frame_on_parent()
        p_BW = X_BW.GetFixedPoseInBodyFrame().translation()
        assert p_BW[0] > 0 and p_BW[2] == 0
        assert sign * p_BW[1] == pytest.approx(params.wheel_separation / 2)
