"""PlanningScene: run-time objects, attaching, queries, replacing the whole scene, objects
queued for the checker until the next query, Meshcat display."""

import numpy as np
import pytest
from pydrake.geometry import Meshcat
from pydrake.math import RigidTransform, RollPitchYaw

import planning as mut
from planning import ErrorCode, PlanningError


@pytest.fixture(scope="module")
def base_scene():
    return mut.PlanningScene()


@pytest.fixture
def dut(base_scene):
    """The shared scene, restored to the table alone after each test."""
    yield base_scene
    table = base_scene.config.table
    base_scene.replace(
        [mut.SceneObject("table", "box", table.size, RigidTransform(table.position))]
    )
    base_scene.other_positions = base_scene.model.default_other


@pytest.fixture
def ready(dut):
    return dut.model.named_configurations["ready"]


def test_new_scene_has_the_table_and_ready_is_free(dut, ready):
    assert list(dut.world_objects) == ["table"]
    assert dut.is_collision_free(ready)
    assert dut.colliding_pairs(ready) == []
    assert 0.05 < dut.clearance(ready) < 1.0


def test_adding_and_removing_boxes_changes_collisions(dut, ready):
    dut.add_box("block", [0.1, 0.1, 0.1], RigidTransform([0.31, 0.0, 0.5]))
    assert not dut.is_collision_free(ready)
    assert ("block", "panda_hand") in dut.colliding_pairs(ready)
    assert "block <-> panda_hand" in dut.describe_collisions(ready)
    assert dut.clearance(ready) < 0.0
    removed = dut.remove_object("block")
    assert removed.name == "block" and dut.is_collision_free(ready)
    dut.add_box("near", [0.1, 0.1, 0.1], RigidTransform([0.31, 0.0, 0.95]))
    assert dut.is_collision_free(ready)
    dut.move_object("near", RigidTransform([0.31, 0.0, 0.5]))
    assert not dut.is_collision_free(ready)


def test_cylinders_spheres_and_rotated_boxes(dut, ready):
    dut.add_sphere("ball", 0.05, RigidTransform([0.31, 0.0, 0.45]))
    assert dut.colliding_pairs(ready)
    dut.remove_object("ball")
    dut.add_cylinder(
        "can", 0.03, 0.3, RigidTransform(RollPitchYaw(np.pi / 2, 0, 0), [0.31, 0, 0.6])
    )
    assert not dut.is_collision_free(ready)
    dut.remove_object("can")
    # A thin plate beside the hand collides only once rotated into it.
    dut.add_box("plate", [0.3, 0.01, 0.3], RigidTransform([0.31, 0.15, 0.5]))
    assert dut.is_collision_free(ready)
    dut.move_object("plate", RigidTransform(RollPitchYaw(0, 0, np.pi / 2), [0.31, 0.15, 0.5]))
    assert not dut.is_collision_free(ready)


def test_edges_and_joint_limits(dut, ready):
    extended = dut.model.named_configurations["extended"]
    assert dut.is_edge_collision_free(ready, extended)
    dut.add_box("wall", [0.02, 1.0, 1.0], RigidTransform([0.55, 0.0, 0.5]))
    assert dut.is_collision_free(ready)
    assert not dut.is_edge_collision_free(ready, extended)
    assert dut.in_joint_limits(ready) and not dut.in_joint_limits(ready + 3.0)


def test_attached_box_moves_with_the_hand_and_collides_with_the_world(dut, ready):
    X_WA = dut.attachment_pose(ready)
    dut.add_box("cube", [0.04, 0.04, 0.04], X_WA @ RigidTransform([0, 0, 0.11]))
    assert dut.is_collision_free(ready)  # held between the fingers: not a collision
    dut.finger_positions = 0.01  # fingers closing through a world cube collide ...
    assert ("cube", "panda_leftfinger") in dut.colliding_pairs(ready)
    dut.attach("cube", ready)  # ... but not once it is held
    assert dut.is_collision_free(ready)
    assert list(dut.attached_objects) == ["cube"] and "cube" not in dut.world_objects
    q = ready.copy()
    q[0] = 1.0
    p_before = dut.object_pose("cube", ready).translation()
    p_after = dut.object_pose("cube", q).translation()
    p_hand = dut.attachment_pose(q).translation()
    assert np.linalg.norm(p_after - p_before) > 0.2
    assert np.linalg.norm(p_after - p_hand) == pytest.approx(0.11, abs=1e-9)
    # Put a post where the cube (not the hand) passes.
    dut.add_box("post", [0.05, 0.05, 0.05], RigidTransform(p_after))
    assert ("cube", "post") in dut.colliding_pairs(q)
    dut.remove_object("post")
    dut.detach("cube", q)
    assert "cube" in dut.world_objects
    np.testing.assert_allclose(dut.world_objects["cube"].X_PO.translation(), p_after, atol=1e-12)


def test_attached_object_collides_with_arm_links(dut, ready):
    """A long held bar is checked against the arm (only the hand and fingers are exempt)."""
    dut.attach_new(mut.SceneObject("bar", "box", (0.04, 0.04, 0.6), RigidTransform([0, 0, -0.2])))
    assert any("bar" in pair for pair in dut.colliding_pairs(ready))


def test_bad_input(dut, ready):
    with pytest.raises(PlanningError) as info:
        dut.remove_object("ghost")
    assert info.value.code == ErrorCode.INVALID_OBJECT_NAME and "table" in info.value.message
    with pytest.raises(PlanningError, match="already"):
        dut.add_box("table", [1, 1, 1], RigidTransform())
    with pytest.raises(PlanningError):
        dut.attach("ghost", ready)
    with pytest.raises(PlanningError):
        dut.detach("table", ready)
    with pytest.raises(ValueError, match="3 size values"):
        dut.add_box("b", [0.1, 0.1], RigidTransform())
    with pytest.raises(ValueError, match="positive"):
        dut.add_sphere("s", -0.1, RigidTransform())
    with pytest.raises(ValueError, match="finite"):
        dut.add_box("n", [0.1, 0.1, 0.1], RigidTransform([np.nan, 0, 0]))
    with pytest.raises(ValueError, match="shape"):
        mut.SceneObject("c", "cone", (1.0,), RigidTransform())
    with pytest.raises(ValueError, match="finite"):
        mut.make_pose([0, 0, 0], [0, 0, np.nan, 1])
    with pytest.raises(ValueError, match="zero"):
        mut.make_pose([0, 0, 0], [0, 0, 0, 0])
    with pytest.raises(ValueError, match="7"):
        dut.is_collision_free([0.0] * 5)
    with pytest.raises(PlanningError):
        dut.allow_collision("panda_hand", "panda_tail")
    assert list(dut.world_objects) == ["table"]


def test_meshcat_shows_attached_objects_in_another_colour(tmp_path):
    meshcat = Meshcat()
    scene = mut.PlanningScene(meshcat=meshcat)
    q = scene.model.named_configurations["ready"]
    scene.attach_new(
        mut.SceneObject("held", "box", (0.04, 0.04, 0.04), RigidTransform([0, 0, 0.11]))
    )
    scene.publish(q)
    assert meshcat.HasPath("planning/objects/world/table")
    assert meshcat.HasPath("planning/objects/attached/held")
    assert meshcat.HasPath("planning/robot")
    from planning import scene_display

    assert scene_display.ATTACHED_COLOR.rgba.tolist() != scene_display.WORLD_COLOR.rgba.tolist()


def test_held_object_may_rest_on_the_table_but_not_sink_into_it(dut, ready):
    """A grasped object still standing on the table touches it: allowed, as MoveIt's touch
    links allow it; pushed 1 cm into the table it collides, and the pair is named."""
    tolerance = dut.config.model.held_object_touch_tolerance
    assert tolerance > 0
    X_WA = dut.attachment_pose(ready)
    height = 0.08
    for sink, free in ((0.0, True), (0.5 * tolerance, True), (0.01, False)):
        # A box hanging below the hand whose bottom is `sink` below the table top (z = 0).
        z_bottom = -sink
        p_WO = [X_WA.translation()[0], X_WA.translation()[1], z_bottom + height / 2]
        dut.attach_new(
            mut.SceneObject(
                "held", "box", (0.04, 0.04, height), X_WA.inverse() @ RigidTransform(p_WO)
            )
        )
        assert dut.is_collision_free(ready) == free, sink
        assert (("held", "table") in dut.colliding_pairs(ready)) == (not free)
        dut.remove_object("held")


# A configuration where only panda_link2 and panda_link5 collide.
SELF_COLLIDING = [2.561, -1.368, 1.56, -3.011, -1.528, 3.264, -0.869]


def test_replace_swaps_the_whole_scene(dut, ready):
    dut.attach_new(mut.SceneObject("old held", "sphere", (0.02,), RigidTransform([0, 0, 0.1])))
    dut.allow_collision("panda_link2", "panda_link5")
    dut.place_position = np.zeros(3)
    assert dut.is_collision_free(SELF_COLLIDING)
    block = mut.SceneObject("block", "box", (0.1, 0.1, 0.1), RigidTransform([0.31, 0.0, 0.5]))
    held = mut.SceneObject("held", "box", (0.02, 0.02, 0.02), RigidTransform([0, 0, 0.1]))
    version = dut.version
    dut.replace([block], [held], [("panda_link1", "panda_link7")])
    assert list(dut.world_objects) == ["block"] and list(dut.attached_objects) == ["held"]
    assert dut.place_position is None and dut.version > version
    assert ("block", "panda_hand") in dut.colliding_pairs(ready)
    assert dut.colliding_pairs(SELF_COLLIDING) == [("panda_link2", "panda_link5")]  # not allowed
    body = dut.plant.GetBodyByName
    assert dut.checker.IsCollisionFilteredBetween(body("panda_link1"), body("panda_link7"))
    assert dut.checker.IsCollisionFilteredBetween(body("panda_hand"), body("panda_link7"))  # SRDF
    for bad in (
        {"world": [block, block]},
        {"world": [block], "attached": [block.with_pose(RigidTransform())]},
        {"allowed": [("panda_link1", "panda_tail")]},
    ):
        with pytest.raises(PlanningError) as info:
            dut.replace(**bad)
        assert info.value.code == ErrorCode.INVALID_OBJECT_NAME
        assert list(dut.world_objects) == ["block"] and list(dut.attached_objects) == ["held"]


def test_objects_wait_for_the_next_query_and_every_query_sees_them(dut, ready):
    """Adds are queued in the checker until it is next used, even through a reference a
    planner kept from before the add."""
    from planning.collision.checker import CheckerAdapter

    adapter, checker = CheckerAdapter(dut), dut.checker
    assert adapter.config_free(ready)
    for i in range(50):  # far away from the robot
        dut.add_sphere(f"s{i}", 0.01, RigidTransform([3.0 + 0.05 * i, 0.0, 0.0]))
    dut.add_box("block", [0.1, 0.1, 0.1], RigidTransform([0.31, 0.0, 0.5]))
    assert checker.pending == 51  # queued
    assert not adapter.config_free(ready)  # the adapter's checker applies the queue first
    assert checker.pending == 0
    dut.add_box("post", [0.1, 0.1, 0.1], RigidTransform([0.31, 0.0, 0.5]))
    assert checker.pending == 1 and dut.checker.pending == 0  # reading ``checker`` applies it
    dut.remove_object("post")
    assert ("block", "panda_hand") in dut.colliding_pairs(ready)
    dut.remove_object("block")
    assert adapter.config_free(ready) and dut.is_collision_free(ready)
    assert len(dut.world_objects) == 51
    dut.clear()
    assert dut.world_objects == {} and dut.is_collision_free(ready)
