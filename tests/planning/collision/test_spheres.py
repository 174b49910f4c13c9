"""Sphere models of the Panda (planning.collision.spheres): the model's spheres cover every
collision mesh in any configuration, its verdicts agree with Drake's checker in MBM and
pick-and-place scenes, scene changes made at run time are seen, unsupported geometry and
non-finite configurations are left to Drake. The parts have their own tests: test_sphere_cover,
test_sphere_robot, test_sphere_fk, test_sphere_kernel and test_sphere_checker."""

import gc
import weakref

import numpy as np
import pytest
from pydrake.math import RigidTransform
from pydrake.multibody.tree import BodyIndex

import planning.collision.spheres as mut
from drake_sim.base.resources import config_dir
from planning import PlanningScene
from planning.collision.checker import CheckerAdapter
from planning.collision.sphere_checker import SphereCheckerAdapter, sphere_model
from planning.collision.sphere_robot import shape_polytope


@pytest.fixture(scope="module")
def scene():
    return PlanningScene()


@pytest.fixture
def dut(scene):
    model = sphere_model(scene)
    yield model
    for name in list(scene.attached_objects):
        scene.remove_object(name)
    for name in set(scene.world_objects) - {"table"}:
        scene.remove_object(name)


def random_q(scene, n, seed=0):
    adapter = CheckerAdapter(scene)
    return np.random.default_rng(seed).uniform(adapter.lower, adapter.upper, (n, 7))


def drake_free(scene, qs):
    full = np.tile(scene.full_q(np.zeros(7)), (len(qs), 1))
    full[:, scene.model.arm_indices] = qs
    return np.asarray(scene.checker.CheckConfigsCollisionFree(list(full)), dtype=bool)


def test_spheres_cover_every_collision_mesh_vertex(scene, dut):
    """Every hull vertex of every collision geometry (and points on the finger boxes' faces)
    lies in one of its body's outer spheres, in random configurations."""
    plant = scene.plant
    inspector = scene.checker.MakeStandaloneModelContext().GetQueryObject().inspector()
    qs = random_q(scene, 5, seed=1)
    centres, radii = dut.sphere_centres(qs)
    owner = np.array(dut._bodies)[dut._slot]
    for n, q in enumerate(qs):
        context = scene.plant_context(q)
        for body in set(owner):
            X_WB = plant.EvalBodyPoseInWorld(context, plant.get_body(BodyIndex(int(body))))
            mine = owner == body
            for g in plant.GetCollisionGeometriesForBody(plant.get_body(BodyIndex(int(body)))):
                v, polygons, _, _ = shape_polytope(inspector.GetShape(g))
                points = [v] + [v[f].mean(axis=0, keepdims=True) for f in polygons]
                p_W = (X_WB @ inspector.GetPoseInFrame(g)).multiply(np.vstack(points).T).T
                d = np.linalg.norm(p_W[:, None, :] - centres[n, mine][None], axis=2)
                assert (d <= radii[mine][None, :] + 1e-9).any(axis=1).all()


def check_agreement(scene, qs):
    """Sphere verdicts never contradict Drake's; the adapter's answers equal Drake's."""
    model = sphere_model(scene)
    state = model.classify(qs)
    free = drake_free(scene, qs)
    assert not np.any((state == mut.FREE) & ~free)
    assert not np.any((state == mut.COLLIDING) & free)
    assert np.mean(state != mut.UNKNOWN) > 0.8  # the spheres decide most configurations
    np.testing.assert_array_equal(SphereCheckerAdapter(scene).configs_free(qs), free)


def test_agrees_with_drake_in_mbm_scenes(scene, dut, mbm_folder):
    from planning.io import mbm

    for family in ("cage_panda", "bookshelf_thin_panda"):
        problem = next(mbm.iter_problems(mbm_folder, [family], 1))
        scene.load_moveit(problem.scene_file)
        check_agreement(scene, random_q(scene, 1000, seed=2))
    scene.clear()
    scene.add_box("table", scene.config.table.size, RigidTransform(scene.config.table.position))


def test_agrees_with_drake_in_the_pick_and_place_scene(scene, dut):
    scene.load_yaml(config_dir() / "pickplace.yaml")
    qs = random_q(scene, 1000, seed=3)
    check_agreement(scene, qs)
    # Holding the object: attached at a configuration where the hand is around it.
    scene.attach_new(
        type(scene.world_objects["object"])(
            "held", "box", (0.045, 0.045, 0.08), RigidTransform([0.0, 0.0, 0.1034])
        )
    )
    check_agreement(scene, qs)


def test_objects_added_removed_and_attached_at_run_time_are_seen(scene, dut):
    q = scene.model.named_configurations["ready"]
    assert dut.classify(q[None])[0] == mut.FREE
    p_WH = scene.attachment_pose(q).translation()
    scene.add_sphere("ball", 0.05, RigidTransform(p_WH))
    assert dut.classify(q[None])[0] != mut.FREE
    assert not SphereCheckerAdapter(scene).config_free(q)
    scene.move_object("ball", RigidTransform(p_WH + [0.0, 0.0, 0.5]))
    assert dut.classify(q[None])[0] == mut.FREE
    scene.remove_object("ball")
    # A held rod reaching down through the table.
    scene.attach_new(
        type(scene.world_objects["table"])(
            "rod", "cylinder", (0.02, 2.0), RigidTransform([0.0, 0.0, 0.1])
        )
    )
    assert dut.classify(q[None])[0] != mut.FREE
    assert not SphereCheckerAdapter(scene).config_free(q)
    scene.remove_object("rod")
    assert dut.classify(q[None])[0] == mut.FREE
    # The fingers move with the scene's finger positions.
    before = dut.sphere_centres(q[None])[0]
    scene.finger_positions = 0.0
    try:
        assert not np.allclose(dut.sphere_centres(q[None])[0], before)
    finally:
        scene.other_positions = scene.model.default_other


def test_objects_stay_alive_while_the_model_names_them(scene, dut):
    """The model tells objects apart by identity: it keeps those its last sync saw alive, so
    that no new object takes the id of a removed one (a held object removed and another
    attached under its name between two syncs would otherwise look unchanged; seen with held
    objects replaced in turn, ``test_hull_kernel``)."""
    q = scene.model.named_configurations["ready"]
    held = type(scene.world_objects["table"])(
        "held", "cylinder", (0.02, 2.0), RigidTransform([0.0, 0.0, 0.1])
    )
    scene.attach_new(held)
    assert dut.classify(q[None])[0] != mut.FREE  # the rod through the table
    scene.remove_object("held")
    ref = weakref.ref(held)
    del held
    gc.collect()
    assert ref() is not None
    assert dut.classify(q[None])[0] == mut.FREE


def test_unsupported_geometry_falls_back_to_drake(scene, dut, monkeypatch):
    monkeypatch.setattr(dut, "supported", False)
    qs = random_q(scene, 50, seed=4)
    assert np.all(dut.classify(qs) == mut.UNKNOWN)
    np.testing.assert_array_equal(
        SphereCheckerAdapter(scene).configs_free(qs), drake_free(scene, qs)
    )
    # Segments too: everything goes to Drake (from free starts), or blocks before the fallback.
    qa, qb = qs[:25][drake_free(scene, qs[:25])], qs[25:][drake_free(scene, qs[:25])]
    expected = CheckerAdapter(scene, 0.05).free_prefixes(qa, qb)
    np.testing.assert_allclose(SphereCheckerAdapter(scene, 0.05).free_prefixes(qa, qb), expected)
    waiting = SphereCheckerAdapter(scene, 0.05, fallback_after=10**9)
    assert not waiting.free_prefixes(qa, qb).any()


def test_non_finite_configurations_are_never_proven_free(scene, dut):
    q = scene.model.named_configurations["ready"].copy()
    q[2] = np.nan
    assert dut.classify(q[None])[0] == mut.UNKNOWN
    qs = np.vstack([scene.model.named_configurations["ready"], q])
    first, n, edge, local = dut.prefixes(qs[:1], qs[1:], 0.1, stop_at_unknown=True)
    assert first[0] < n[0]  # the NaN end blocks the segment


def test_held_objects_against_the_arm_agree_with_drake(scene, dut):
    scene.attach_new(
        type(scene.world_objects["table"])(
            "crate", "box", (0.1, 0.1, 0.1), RigidTransform([0.0, 0.0, 0.15])
        )
    )
    qs = random_q(scene, 200, seed=8)
    state = dut.classify(qs)
    assert not np.any((state == mut.FREE) & ~drake_free(scene, qs))


def test_packed_data_is_packed_once_per_change(dut, scene):
    first = dut.packed_data()
    assert dut.packed_data() is first  # no change: the same buffers
    np.testing.assert_array_equal(first[0], mut._kernel.pack(dut.kernel_data())[0])
    scene.add_box("packed", [0.1, 0.1, 0.1], RigidTransform([0.5, 0.3, 0.3]))
    again = dut.packed_data()
    assert again is not first and len(again[0]) > len(first[0])  # one more object's row


def test_a_sync_told_not_to_remake_the_robot_part_says_when_it_is_out_of_date(scene, dut):
    """``sync(rebuild_robot=False)`` follows the world's objects (a cheap change) but leaves the
    model as it is, and says so, when held objects changed; a full sync then catches up."""
    q = scene.model.named_configurations["ready"]
    assert dut.sync(rebuild_robot=False)
    scene.add_box("seen", [0.1, 0.1, 0.1], RigidTransform([0.5, -0.3, 0.3]))
    assert dut.sync(rebuild_robot=False) and "seen" in scene.world_objects
    before = dut.kernel_data()
    assert len(before.objects) == len(scene.world_objects)
    scene.attach_new(
        type(scene.world_objects["table"])(
            "rod", "cylinder", (0.02, 2.0), RigidTransform([0.0, 0.0, 0.1])
        )
    )
    assert not dut.sync(rebuild_robot=False)
    assert not dut.sync(rebuild_robot=False)  # the same version: no second look
    assert dut.sync()  # remade: the held rod through the table collides
    assert dut.classify(q[None])[0] != mut.FREE
