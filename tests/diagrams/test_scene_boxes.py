"""diagrams.scene_boxes: box_pose, add_scene_box (welded or free) and contact_properties."""

import pytest
from pydrake.geometry import Box, Rgba
from pydrake.math import RigidTransform, RollPitchYaw
from pydrake.multibody.plant import AddMultibodyPlantSceneGraph, CoulombFriction
from pydrake.systems.framework import DiagramBuilder

import diagrams.scene_boxes as mut
from planning.io.scene_files import BoxSpec

BOX = BoxSpec(size=[0.1, 0.2, 0.3], position=[0.5, -0.2, 0.15], yaw=0.5, mass=0.3)
FRICTION = CoulombFriction(0.6, 0.5)
RED = Rgba(1, 0, 0, 1)


def _plant():
    builder = DiagramBuilder()
    plant, scene_graph = AddMultibodyPlantSceneGraph(builder, time_step=1e-3)
    return plant, scene_graph


def test_box_pose_is_centre_and_yaw():
    dut = mut.box_pose(BOX)
    expected = RigidTransform(RollPitchYaw(0.0, 0.0, 0.5), [0.5, -0.2, 0.15])
    assert dut.IsNearlyEqualTo(expected, 1e-15)
    flat = mut.box_pose(BoxSpec(size=[1, 1, 1], position=[1, 2, 3]))
    assert flat.IsNearlyEqualTo(RigidTransform([1.0, 2.0, 3.0]), 0.0)


def test_welded_box_is_world_geometry():
    plant, scene_graph = _plant()
    dut = mut.add_scene_box(plant, "wall", BOX, friction=FRICTION, color=RED, free=False)
    assert dut is None
    assert plant.num_model_instances() == 2  # world and default: no new instance
    plant.Finalize()
    inspector = scene_graph.model_inspector()
    (collision,) = plant.GetCollisionGeometriesForBody(plant.world_body())
    (visual,) = plant.GetVisualGeometriesForBody(plant.world_body())
    for geometry in (collision, visual):
        assert inspector.GetPoseInFrame(geometry).IsNearlyEqualTo(mut.box_pose(BOX), 1e-15)
        shape = inspector.GetShape(geometry)
        assert isinstance(shape, Box)
        assert (shape.width(), shape.depth(), shape.height()) == (0.1, 0.2, 0.3)
    assert inspector.GetName(collision) == "wall"
    assert plant.num_positions() == 0


def test_free_box_is_a_body_in_its_own_instance():
    plant, scene_graph = _plant()
    dut = mut.add_scene_box(
        plant, "object", BOX, friction=FRICTION, color=RED, free=True, point_stiffness=1e4
    )
    assert dut.name() == "object"
    assert plant.GetModelInstanceName(dut.model_instance()) == "object"
    assert dut.default_mass() == pytest.approx(0.3)
    plant.Finalize()
    assert dut.index() in plant.GetFloatingBaseBodies() and plant.num_positions() == 7
    (collision,) = plant.GetCollisionGeometriesForBody(dut)
    inspector = scene_graph.model_inspector()
    assert inspector.GetPoseInFrame(collision).IsNearlyEqualTo(RigidTransform(), 0.0)
    props = inspector.GetProximityProperties(collision)
    friction = props.GetProperty("material", "coulomb_friction")
    assert (friction.static_friction(), friction.dynamic_friction()) == (0.6, 0.5)
    assert props.GetProperty("material", "point_contact_stiffness") == 1e4


def test_free_box_default_pose_is_the_box_pose():
    plant, _ = _plant()
    body = mut.add_scene_box(plant, "object", BOX, friction=FRICTION, color=RED, free=True)
    plant.Finalize()
    X_WB = plant.EvalBodyPoseInWorld(plant.CreateDefaultContext(), body)
    assert X_WB.IsNearlyEqualTo(mut.box_pose(BOX), 1e-12)


def test_contact_properties():
    dut = mut.contact_properties(FRICTION)
    friction = dut.GetProperty("material", "coulomb_friction")
    assert (friction.static_friction(), friction.dynamic_friction()) == (0.6, 0.5)
    assert not dut.HasProperty("material", "point_contact_stiffness")
    stiff = mut.contact_properties(FRICTION, 2.5e4)
    assert stiff.GetProperty("material", "point_contact_stiffness") == 2.5e4
