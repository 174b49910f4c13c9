"""random_scene: deterministic for a seed, the base table kept, and the object, wall and place
target within the documented ranges: the object on the table in front of the robot on one side
of the wall, the place target on the other, all within the arm's reach."""

import copy
import dataclasses as dc

import numpy as np
import pytest
from pydrake.math import RigidTransform, RollPitchYaw, RotationMatrix

import planning.task.scene_generator as mut
from planning import PlanningScene, RobotState
from planning.io.scene_files import BoxSpec, ObjectSpec, SceneFile, apply_scene_file
from planning.task.geometry import boxes_overlap

TABLE = BoxSpec(size=[1.2, 1.4, 0.04], position=[0.3, 0.0, -0.02])
BASE = SceneFile(table=TABLE)
BASE_BEFORE = copy.deepcopy(BASE)
SEEDS = range(200)


@pytest.fixture(scope="module")
def scenes():
    return [mut.random_scene(np.random.default_rng(seed), BASE) for seed in SEEDS]


def box_pose(box: BoxSpec) -> RigidTransform:
    return RigidTransform(RollPitchYaw(0.0, 0.0, box.yaw), box.position)


def test_same_seed_same_scene_and_the_base_is_kept(scenes):
    again = mut.random_scene(np.random.default_rng(0), BASE)
    assert again == scenes[0]
    assert scenes[0] != scenes[1]
    assert all(s.table is TABLE for s in scenes)
    assert BASE == BASE_BEFORE  # not changed
    can = ObjectSpec(name="can", shape="cylinder", size=[0.03, 0.1], position=[0.3, 0.5, 0.05])
    with_can = dc.replace(BASE, objects=[can])
    assert mut.random_scene(np.random.default_rng(0), with_can).objects == [can]


def test_object_sizes_and_turn_are_within_the_documented_ranges(scenes):
    for scene in scenes:
        obj = scene.object
        width, depth, height = obj.size
        assert 0.03 <= width <= 0.06 and 0.03 <= depth <= 0.06  # the hand holds up to 7.5 cm
        assert 0.05 <= height <= 0.10
        assert abs(obj.yaw) <= np.pi / 4
        assert obj.mass > 0.0


def test_object_and_place_rest_on_the_table_on_either_side_of_the_wall(scenes):
    sides = set()
    for scene in scenes:
        obj, wall, place = scene.object, scene.obstacle, scene.place
        length, thickness, wall_height = wall.size
        assert 0.10 <= length <= 0.30 and 0.10 <= wall_height <= 0.25
        # Resting on the table top (z = 0), in front of the robot (x > 0).
        assert obj.position[2] == pytest.approx(0.5 * obj.size[2])
        assert wall.position[2] == pytest.approx(0.5 * wall_height)
        assert place.position[2] == pytest.approx(obj.position[2])
        assert obj.position[0] > 0.3 and place.position[0] > 0.3
        # The wall lies along x at y = 0 between them; object and place on opposite sides.
        assert wall.position[1] == 0.0
        assert np.sign(obj.position[1]) == -np.sign(place.position[1])
        sides.add(float(np.sign(obj.position[1])))
        X_wall = box_pose(wall)
        assert not boxes_overlap(obj.size, box_pose(obj), wall.size, X_wall)
        X_placed = RigidTransform(RollPitchYaw(0.0, 0.0, obj.yaw), place.position)
        assert not boxes_overlap(obj.size, X_placed, wall.size, X_wall)
        # On the table.
        for p in (obj.position, place.position):
            assert np.all(np.abs(np.subtract(p, TABLE.position)[:2]) < 0.5 * TABLE.size[0])
        # Within reach: the Panda's shoulder is 0.333 m up; its reach about 0.855 m.
        for p in (obj.position, place.position):
            assert np.linalg.norm(np.subtract(p, [0.0, 0.0, 0.333])) < 0.8
    assert sides == {-1.0, 1.0}


def test_scenes_load_and_their_object_can_be_reached_from_above():
    scene = PlanningScene()
    state = RobotState(scene)
    R_down = RotationMatrix.MakeXRotation(np.pi)
    for seed in (0, 1, 2):
        spec = mut.random_scene(np.random.default_rng(seed), BASE)
        apply_scene_file(scene, spec)
        assert sorted(scene.world_objects) == ["object", "obstacle", "table"]
        for p in (spec.object.position, spec.place.position):
            above = np.add(p, [0.0, 0.0, 0.5 * spec.object.size[2] + 0.1])
            result = state.ik(RigidTransform(R_down, above), q_seed=state.named("ready"))
            assert scene.is_collision_free(result.q)
