"""Exact clearance proofs (planning.collision.hull_kernel): GJK's separating planes prove a pair
apart exactly when its distance exceeds the threshold (shapes with known distances), and the
robot's shapes never prove free a configuration Drake's checker finds colliding, while proving
most of those the sphere cover cannot decide (MBM and pick-and-place scenes, held objects)."""

import numpy as np
import pytest
from pydrake.math import RigidTransform, RollPitchYaw

import planning.collision.hull_kernel as mut
from planning import PlanningScene
from planning.collision.checker import CheckerAdapter
from planning.collision.sphere_arrays import primitives
from planning.collision.sphere_checker import sphere_model
from planning.collision.sphere_kernel import OBJ_COLUMNS
from planning.collision.spheres import UNKNOWN
from planning.scene_objects import SceneObject

NO_MOTION = np.zeros((0, 7))
CUBE = np.array([[x, y, z] for x in (-0.1, 0.1) for y in (-0.1, 0.1) for z in (-0.1, 0.1)])


def hulls(shapes, world_gap=-1.0, pairs=(), pair_gap=0.0):
    """HullData of (vertices, radius, step) shapes."""
    verts = [np.asarray(v, dtype=float) for v, _, _ in shapes]
    centre = np.array([v.mean(axis=0) for v in verts])
    radius = [r for _, r, _ in shapes]
    bound = [
        np.linalg.norm(v - c, axis=1).max() + r
        for v, c, r in zip(verts, centre, radius, strict=True)
    ]
    return mut.HullData(
        geom_step=np.array([s for _, _, s in shapes], dtype=np.int64),
        vert_start=np.r_[0, np.cumsum([len(v) for v in verts])].astype(np.int64),
        vert=np.ascontiguousarray(np.vstack(verts)),
        geom_radius=np.array([r for _, r, _ in shapes], dtype=float),
        geom_centre=centre,
        geom_bound=np.array(bound),
        geom_world=np.full(len(shapes), world_gap),
        pair=np.array(pairs, dtype=np.int64).reshape(-1, 2),
        pair_gap=np.full(len(pairs), pair_gap),
        geom_body=np.zeros(len(shapes), dtype=np.int64),
        speed=np.zeros((1, 7)),
    )


def posed(*poses):
    """Transforms (J, 3, 4) of RigidTransforms."""
    return np.ascontiguousarray(np.array([X.GetAsMatrix34() for X in poses]))


def proven(h, objects, T):
    none = np.zeros(OBJ_COLUMNS)
    return mut._shapes_free(h, objects, T, np.empty((4, 3)), np.empty(3), none, np.zeros(0))


def world(*objects):
    return np.ascontiguousarray(primitives(objects))


@pytest.mark.parametrize(
    "obj, distance",
    [
        # A sphere beside a cube's edge: the distance from its centre to the edge, less its radius.
        (
            SceneObject("ball", "sphere", (0.05,), RigidTransform([0.3, 0.2, 0.0])),
            np.hypot(0.2, 0.1) - 0.05,
        ),
        # A box face to face, then a cylinder along z beside the cube's face.
        (SceneObject("slab", "box", (0.1, 0.4, 0.4), RigidTransform([0.4, 0.0, 0.0])), 0.25),
        (SceneObject("pole", "cylinder", (0.05, 1.0), RigidTransform([0.0, 0.35, 0.0])), 0.2),
    ],
    ids=["sphere", "box", "cylinder"],
)
def test_a_pair_is_proven_apart_exactly_when_farther_than_its_threshold(obj, distance):
    for X in (RigidTransform(), RigidTransform(RollPitchYaw(0.3, -0.2, 0.5), [0.1, -0.2, 0.3])):
        # The whole scene moved rigidly keeps the distance.
        moved = SceneObject(obj.name, obj.shape, obj.size, X @ obj.X_PO)
        objects, T = world(moved), posed(X)
        assert proven(hulls([(CUBE, 0.0, 0)], distance - 1e-6), objects, T)
        assert not proven(hulls([(CUBE, 0.0, 0)], distance + 1e-6), objects, T)
    # A swept ball (a sphere shape: one vertex) counts its radius.
    ball = SceneObject("b", "sphere", (0.1,), RigidTransform([0.5, 0.0, 0.0]))
    assert proven(
        hulls([(np.zeros((1, 3)), 0.2, 0)], 0.2 - 1e-6), world(ball), posed(RigidTransform())
    )
    assert not proven(
        hulls([(np.zeros((1, 3)), 0.2, 0)], 0.2 + 1e-6), world(ball), posed(RigidTransform())
    )


def test_robot_pairs_and_filtered_shapes():
    T = posed(RigidTransform(), RigidTransform(RollPitchYaw(0.0, 0.0, np.pi / 4), [0.5, 0.0, 0.0]))
    # The turned cube's nearest edge is 0.1 sqrt(2) from its centre: 0.5 - 0.1 - 0.1 sqrt(2) apart.
    gap = 0.4 - 0.1 * np.sqrt(2)
    shapes = [(CUBE, 0.0, 0), (CUBE, 0.0, 1)]
    none = world()
    assert proven(hulls(shapes, pairs=[(0, 1)], pair_gap=gap - 1e-6), none, T)
    assert not proven(hulls(shapes, pairs=[(0, 1)], pair_gap=gap + 1e-6), none, T)
    assert proven(hulls(shapes, pairs=[], pair_gap=gap + 1e-6), none, T)  # pair not checked
    # Overlapping shapes are never proven apart, whatever the threshold.
    inside = SceneObject("in", "box", (0.05, 0.05, 0.05), RigidTransform([0.08, 0.0, 0.0]))
    assert not proven(hulls([(CUBE, 0.0, 0)], 0.0), world(inside), T)
    # A shape filtered against the world (-1) is not checked against it.
    assert proven(hulls([(CUBE, 0.0, 0)], -1.0), world(inside), T)


@pytest.fixture(scope="module")
def scene():
    return PlanningScene()


def check_sound(scene, qs, least_share):
    """No configuration the hulls prove free collides for Drake; of the sphere cover's UNKNOWN
    ones that Drake finds free, at least ``least_share`` are proven."""
    model = sphere_model(scene)
    unknown = qs[model.classify(qs) == UNKNOWN]
    assert len(unknown) >= 20
    free = mut.prove_free(unknown, model.kernel_data(), model.hull_data(), NO_MOTION)
    drake = np.array([scene.is_collision_free(q) for q in unknown])
    assert not np.any(free & ~drake)
    assert free.sum() >= least_share * drake.sum()
    return free, drake


def near(scene, q, n, seed):
    """n configurations about q (0.05 rad spread), within the joint limits."""
    adapter = CheckerAdapter(scene)
    spread = np.random.default_rng(seed).normal(0.0, 0.05, (n, 7))
    return np.clip(q + spread, adapter.lower, adapter.upper)


def test_never_proves_free_what_drake_finds_colliding_in_mbm_scenes(scene, mbm_folder):
    from drake_sim.tools.plan_benchmark import _load
    from planning.io import mbm

    for family in ("cage_panda", "bookshelf_thin_panda", "table_under_pick_panda"):
        problem = next(mbm.iter_problems(mbm_folder, [family], 1))
        start, goal = _load(scene, problem)
        # About the ends, where the arm reaches among the objects.
        qs = np.vstack([near(scene, start, 300, 1), near(scene, goal, 300, 2)])
        check_sound(scene, qs, 0.9)
    scene.clear()
    scene.add_box("table", scene.config.table.size, RigidTransform(scene.config.table.position))


def test_held_objects_are_shapes_too(scene):
    model = sphere_model(scene)
    before = len(model.hull_data().geom_step)
    q = scene.model.named_configurations["ready"]
    for shape, size in (
        ("box", (0.06, 0.06, 0.2)),
        ("cylinder", (0.03, 0.25)),
        ("sphere", (0.05,)),
    ):
        scene.attach_new(SceneObject("held", shape, size, RigidTransform([0.0, 0.0, 0.12])))
        try:
            assert len(model.hull_data().geom_step) == before + 1
            # A block beside the held object, 2 cm from the largest of them at q.
            p_WH = (scene.attachment_pose(q) @ RigidTransform([0.0, 0.0, 0.12])).translation()
            scene.add_box("block", (0.1, 0.1, 0.1), RigidTransform(p_WH + [0.12, 0.0, 0.0]))
            # Held objects may sink 2 mm into the world (a padding below zero), which no
            # separating plane shows: many of the UNKNOWN ones Drake finds free are such.
            free, _ = check_sound(scene, near(scene, q, 1000, 3), 0.0)
            assert free.any()
        finally:
            scene.remove_object("held")
            scene.remove_object("block")
    assert len(model.hull_data().geom_step) == before


def test_non_finite_configurations_are_never_proven_free(scene):
    model = sphere_model(scene)
    q = scene.model.named_configurations["ready"].copy()
    assert mut.prove_free(q[None], model.kernel_data(), model.hull_data(), NO_MOTION)[0]
    q[3] = np.nan
    assert not mut.prove_free(q[None], model.kernel_data(), model.hull_data(), NO_MOTION)[0]
