"""The scene side of ray casting (drake_sim.systems.sensors.scene_shapes): OBJ files read as
triangles, concavities seen, and the cached static geometry following the context."""

import math

import numpy as np
import pytest
from pydrake.geometry import Box, Convex, Mesh, Role
from pydrake.math import RigidTransform
from pydrake.multibody.plant import AddMultibodyPlantSceneGraph, CoulombFriction
from pydrake.multibody.tree import FixedOffsetFrame, SpatialInertia
from pydrake.systems.framework import DiagramBuilder

import drake_sim.systems.sensors.scene_shapes as mut
from drake_sim.systems.sensors.ray_casting import (
    Fan,
    Primitives,
    Shapes,
    cast_fan,
    polygon_mesh_triangles,
)

FAN = Fan(-math.pi, 2 * math.pi / 360, 360)


def _l_obj(path):
    outline = [(0.0, 0.0), (0.6, 0.0), (0.6, 0.2), (0.2, 0.2), (0.2, 0.6), (0.0, 0.6)]
    n = len(outline)
    lines = [f"v {x} {y} {z}" for z in (-0.5, 0.5) for x, y in outline]
    lines += [f"f {i + 1} {(i + 1) % n + 1} {n + (i + 1) % n + 1} {n + i + 1}" for i in range(n)]
    lines += ["f 4 3 2 1", "f 6 5 4 1", "f 7 8 9 10", "f 7 10 11 12"]
    path.write_text("\n".join(lines) + "\n")
    return path, outline


def test_mesh_files_concave_and_scaled(tmp_path):
    path, outline = _l_obj(tmp_path / "l.obj")
    tri = mut.mesh_triangles(path, (2.0, 3.0, 1.0))
    assert tri.shape == (20, 3, 3)
    np.testing.assert_allclose(tri.reshape(-1, 3).max(axis=0), [1.2, 1.8, 0.5])
    hull = polygon_mesh_triangles(Mesh(str(path), [2.0, 3.0, 1.0]).GetConvexHull())
    assert len(hull) >= 8
    ranges = {}
    for name, t in (("mesh", tri), ("hull", hull)):
        shapes = Shapes(t + np.array([-1.5, -1.5, 0.0]), Primitives.empty())
        ranges[name] = cast_fan(shapes, np.eye(3), np.zeros(3), FAN, 5.0)
    # Beam 45 (-135 degrees) looks into the L's notch and meets its inner wall y = -0.9 at
    # (-0.9, -0.9); the convex hull's face from (-0.3, -0.9) to (-1.1, 0.3) is at (-0.54, -0.54).
    assert ranges["mesh"][45] == pytest.approx(0.9 * math.sqrt(2.0), abs=1e-9)
    assert ranges["hull"][45] == pytest.approx(0.54 * math.sqrt(2.0), abs=1e-9)


def _scene_with_static_and_mesh(tmp_path):
    builder = DiagramBuilder()
    plant, scene_graph = AddMultibodyPlantSceneGraph(builder, time_step=0.0)
    friction = CoulombFriction()
    world = plant.world_body()
    plant.RegisterCollisionGeometry(
        world, RigidTransform([1.0, 0.0, 0.0]), Box(0.2, 1.0, 1.0), "a", friction
    )
    post = plant.AddRigidBody("post", SpatialInertia.SolidBoxWithMass(1.0, 0.1, 0.1, 0.1))
    plant.RegisterCollisionGeometry(post, RigidTransform(), Box(0.2, 0.2, 1.0), "post", friction)
    F = plant.AddFrame(FixedOffsetFrame("F", plant.world_frame(), RigidTransform([0.0, 1.0, 0.0])))
    plant.WeldFrames(F, post.body_frame())
    path, _ = _l_obj(tmp_path / "l.obj")
    plant.RegisterCollisionGeometry(
        world, RigidTransform([-1.0, -1.0, 0.0]), Convex(str(path)), "l", friction
    )
    plant.Finalize()
    diagram = builder.Build()
    static = [plant.GetBodyFrameIdOrThrow(post.index())]
    return diagram, plant, scene_graph, F, static


def test_scene_caster_follows_the_context(tmp_path):
    """The cached static geometry follows a moved weld and a removed role, in a new context
    as in the same one; Convex shapes are read from their file (concavity seen)."""
    diagram, plant, scene_graph, F, static = _scene_with_static_and_mesh(tmp_path)
    caster = mut.SceneRayCaster(static_frames=static)
    context = diagram.CreateDefaultContext()

    def scan(ctx):
        query = scene_graph.get_query_output_port().Eval(scene_graph.GetMyContextFromRoot(ctx))
        return caster.cast(query, RigidTransform(), FAN, 5.0)

    ranges = scan(context)
    assert ranges[180] == pytest.approx(0.9)  # +x: the anchored box
    assert ranges[270] == pytest.approx(0.9)  # +y: the welded post
    # -136 degrees, into the notch of the L at (-1, -1): its inner wall x = -0.8, not its hull
    assert ranges[44] == pytest.approx(-0.8 / math.cos(math.radians(-136.0)), abs=1e-9)
    F.SetPoseInParentFrame(plant.GetMyMutableContextFromRoot(context), RigidTransform([0, 2.0, 0]))
    assert scan(context)[270] == pytest.approx(1.9)
    fresh = diagram.CreateDefaultContext()
    assert scan(fresh)[270] == pytest.approx(0.9)
    sg_context = scene_graph.GetMyMutableContextFromRoot(fresh)
    box_id = plant.GetCollisionGeometriesForBody(plant.world_body())[0]
    scene_graph.RemoveRole(sg_context, plant.get_source_id(), box_id, Role.kProximity)
    assert np.isinf(scan(fresh)[180])
    assert scan(context)[180] == pytest.approx(0.9)  # the first context still has it


def test_ignored_and_dynamic_frames():
    builder = DiagramBuilder()
    plant, scene_graph = AddMultibodyPlantSceneGraph(builder, time_step=0.0)
    inertia = SpatialInertia.SolidBoxWithMass(1.0, 0.1, 0.1, 0.1)
    mine = plant.AddRigidBody("mine", inertia)
    other = plant.AddRigidBody("other", inertia)
    for body in (mine, other):
        plant.RegisterCollisionGeometry(
            body, RigidTransform(), Box(0.2, 0.2, 0.2), body.name(), CoulombFriction()
        )
    plant.Finalize()
    diagram = builder.Build()
    context = diagram.CreateDefaultContext()
    plant_context = plant.GetMyMutableContextFromRoot(context)
    plant.SetFreeBodyPose(plant_context, other, RigidTransform([1.0, 0.0, 0.0]))
    caster = mut.SceneRayCaster(ignore_frames=[plant.GetBodyFrameIdOrThrow(mine.index())])
    query = scene_graph.get_query_output_port().Eval(scene_graph.GetMyContextFromRoot(context))
    ranges = caster.cast(query, RigidTransform(), FAN, 5.0)
    assert ranges[180] == pytest.approx(0.9)
    assert np.isinf(ranges[0])
    plant.SetFreeBodyPose(plant_context, other, RigidTransform([-2.0, 0.0, 0.0]))
    query = scene_graph.get_query_output_port().Eval(scene_graph.GetMyContextFromRoot(context))
    ranges = caster.cast(query, RigidTransform(), FAN, 5.0)
    assert np.isinf(ranges[180]) and ranges[0] == pytest.approx(1.9)
