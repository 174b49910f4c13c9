"""What MoveIt scenes hold besides boxes, cylinders and spheres: meshes (inline, or files by a
relative path or a package:// URI, scaled) checked as their convex hulls, planes as a box behind
them, cones and prisms as hulls, object colours, subframes as frames (objects placed on them
too), the robot state as a start configuration, MoveIt's fixed-frame convention, a moved robot
base, and a scene written for another robot (its link frames and joints left out with a warning
each, or an error when strict)."""

import logging

import numpy as np
import pytest
import trimesh
import yaml

import planning.io.moveit_scene as mut
from planning import ErrorCode, PlanningError
from planning.model.panda import ARM_JOINTS
from planning.scene_objects import subframe_pose

CUBE = [[x, y, z] for x in (-0.05, 0.05) for y in (-0.05, 0.05) for z in (-0.05, 0.05)]
TRIANGLES = [[0, 1, 2], [1, 2, 3], [4, 5, 6], [5, 6, 7], [0, 1, 4], [1, 4, 5], [2, 3, 6]]
TRIANGLES += [[3, 6, 7], [0, 2, 4], [2, 4, 6], [1, 3, 5], [3, 5, 7]]


@pytest.fixture
def scene(table_scene):
    return table_scene


def load(scene, write, *objects, name="scene.yaml", **keys):
    data = {"world": {"collision_objects": list(objects)}, **keys}
    return mut.load_moveit_scene(scene, write(yaml.safe_dump(data), name))


def mesh_object(name, mesh, position=(0.5, 0.0, 0.5), **extra) -> dict:
    return {"id": name, "meshes": [mesh], "mesh_poses": [{"position": list(position)}], **extra}


def hull_extent(obj) -> np.ndarray:
    points = np.asarray(obj.vertices)
    return points.max(axis=0) - points.min(axis=0)


def test_inline_meshes_are_their_convex_hull(scene, write):
    # A cube of 12 triangles, its vertices as lists and as mappings, and a vertex in its
    # middle that no triangle uses.
    vertices = [*CUBE, [0.0, 0.0, 0.0]]
    as_maps = [dict(zip("xyz", v, strict=True)) for v in vertices]
    triangles = [{"vertex_indices": t} for t in TRIANGLES]
    load(
        scene,
        write,
        mesh_object("cube", {"vertices": vertices, "triangles": triangles}),
        mesh_object("cube2", {"vertices": as_maps, "triangles": triangles}, (0.5, 0.3, 0.5)),
    )
    cube, cube2 = scene.world_objects["cube"], scene.world_objects["cube2"]
    assert cube.shape == "convex" and sorted(cube.vertices) == sorted(map(tuple, CUBE))
    assert sorted(cube2.vertices) == sorted(cube.vertices)
    np.testing.assert_allclose(cube.X_PO.translation(), [0.5, 0.0, 0.5])
    # Checked by Drake: a configuration whose hand is in the cube collides.
    q = hand_at(scene, [0.5, 0.0, 0.5])
    assert ("cube", "panda_hand") in scene.colliding_pairs(q)
    scene.remove_object("cube")
    assert ("cube", "panda_hand") not in scene.colliding_pairs(q)


def hand_at(scene, p_W) -> np.ndarray:
    """A configuration whose hand origin is at p_W (from the IK the scene's model offers)."""
    from pydrake.multibody.inverse_kinematics import InverseKinematics
    from pydrake.solvers import Solve

    plant = scene.plant
    ik = InverseKinematics(plant)
    hand = plant.GetFrameByName("panda_hand")
    ik.AddPositionConstraint(hand, [0, 0, 0], plant.world_frame(), p_W, p_W)
    seed = scene.full_q(scene.model.named_configurations["ready"])
    result = Solve(ik.prog(), seed)
    assert result.is_success()
    return result.GetSolution(ik.q())


def test_mesh_files_by_path_and_package_uri(scene, write, tmp_path):
    (tmp_path / "meshes").mkdir()
    box = trimesh.creation.box(extents=(0.1, 0.2, 0.3))
    box.export(tmp_path / "meshes" / "crate.stl")
    box.export(tmp_path / "meshes" / "crate.obj")
    loaded = load(
        scene,
        write,
        mesh_object("by_path", {"resource": "meshes/crate.stl"}),
        mesh_object("scaled", {"resource": "meshes/crate.obj", "dimensions": [2, 1, 0.5]}),
        mesh_object("by_uri", {"resource": "package://my_pkg/meshes/crate.stl"}),
        mesh_object("file_url", {"resource": f"file://{tmp_path}/meshes/crate.stl"}),
    )
    assert loaded.skipped == ["by_uri"]  # no package map: left out, with a warning
    assert "unknown package 'my_pkg'" in loaded.warnings[0]
    objects = scene.world_objects
    np.testing.assert_allclose(hull_extent(objects["by_path"]), [0.1, 0.2, 0.3], atol=1e-9)
    np.testing.assert_allclose(hull_extent(objects["scaled"]), [0.2, 0.2, 0.15], atol=1e-9)
    np.testing.assert_allclose(hull_extent(objects["file_url"]), [0.1, 0.2, 0.3], atol=1e-9)
    path = write(
        yaml.safe_dump(
            {
                "world": {
                    "collision_objects": [
                        mesh_object("by_uri", {"resource": "package://my_pkg/meshes/crate.stl"})
                    ]
                }
            }
        )
    )
    loaded = mut.load_moveit_scene(scene, path, package_paths={"my_pkg": str(tmp_path)})
    assert loaded.warnings == [] and list(scene.world_objects) == ["by_uri"]


def test_planes_are_a_box_behind_them(scene, write):
    floor = {"id": "floor", "planes": [{"coef": [0, 0, 1, -0.1]}]}  # z = 0.1, normal up
    floor["plane_poses"] = [{"position": [0, 0, 0]}]
    wall = {  # x = 0.8 in the world, given in a frame turned about z: its normal is -x
        "id": "wall",
        "pose": {"position": [0.8, 0, 0], "orientation": [0, 0, 1, 0]},
        "planes": [{"coef": [1, 0, 0, 0]}],
        "plane_poses": [{"position": [0, 0, 0]}],
    }
    load(scene, write, floor, wall)
    box, wall_box = scene.world_objects["floor"], scene.world_objects["wall"]
    assert box.shape == "box" and box.size == (20.0, 20.0, 10.0)
    np.testing.assert_allclose(box.X_PO.translation(), [0, 0, 0.1 - 5.0], atol=1e-12)
    np.testing.assert_allclose(wall_box.X_PO.rotation().col(2), [-1, 0, 0], atol=1e-12)
    np.testing.assert_allclose(wall_box.X_PO.translation(), [0.8 + 5.0, 0, 0], atol=1e-12)
    ready = scene.model.named_configurations["ready"]
    assert scene.is_collision_free(ready)
    assert not scene.is_collision_free(hand_at(scene, [0.5, 0.0, 0.05]))  # below the floor
    assert not scene.is_collision_free(hand_at(scene, [0.82, 0.0, 0.4]))  # through the wall


def test_cones_and_prisms_are_hulls(scene, write):
    square = {"points": [{"x": 0, "y": 0}, {"x": 0.2, "y": 0}, {"x": 0.2, "y": 0.1}, {"x": 0}]}
    square["points"][3]["y"] = 0.1
    objects = {
        "id": "shapes",
        "primitives": [
            {"type": "cone", "dimensions": [0.4, 0.1]},
            {"type": 5, "dimensions": [0.3], "polygon": square},
        ],
        "primitive_poses": [{"position": [0.5, 0, 0.2]}, {"position": [0.5, 0.5, 0.2]}],
    }
    load(scene, write, objects)
    cone, prism = scene.world_objects["shapes"], scene.world_objects["shapes#1"]
    assert cone.shape == prism.shape == "convex"
    np.testing.assert_allclose(hull_extent(cone)[2], 0.4)
    assert 0.2 <= hull_extent(cone)[0] <= 0.202  # the base's 24-gon holds the circle
    np.testing.assert_allclose(hull_extent(prism), [0.2, 0.1, 0.3])


def test_colours_are_kept_for_display(scene, write):
    box = {
        "id": "crate",
        "primitives": [{"type": "box", "dimensions": [0.1, 0.1, 0.1]}] * 2,
        "primitive_poses": [{"position": [0.5, 0, 0.1]}, {"position": [0.5, 0, 0.3]}],
    }
    held = {"id": "held", "primitives": [{"type": 2, "dimensions": [0.02]}]}
    held["primitive_poses"] = [{"position": [0, 0, 0.1]}]
    state = {"attached_collision_objects": [{"link_name": "panda_hand", "object": held}]}
    colors = [
        {"id": "crate", "color": {"r": 1.0, "g": 0.0, "b": 0.0, "a": 1.0}},
        {"id": "held", "color": [0, 0, 1, 0.5]},
        {"id": "nothing", "color": [0, 1, 0, 1]},  # an object not there: no matter
    ]
    load(scene, write, box, robot_state=state, object_colors=colors)
    assert scene.world_objects["crate"].color == (1.0, 0.0, 0.0, 1.0)
    assert scene.world_objects["crate#1"].color == (1.0, 0.0, 0.0, 1.0)  # every shape
    assert scene.attached_objects["held"].color == (0.0, 0.0, 1.0, 0.5)


def test_subframes_are_frames_of_the_object(scene, write):
    tray = {
        "id": "tray",
        "pose": {"position": [0.5, 0.0, 0.2], "orientation": [0, 0, 0.7071068, 0.7071068]},
        "primitives": [{"type": "box", "dimensions": [0.3, 0.2, 0.02]}],
        "primitive_poses": [{"position": [0, 0, -0.01]}],
        "subframe_names": ["corner", "centre"],
        "subframe_poses": [{"position": [0.15, 0.1, 0]}, {"position": [0, 0, 0]}],
    }
    # Objects placed on the tray's frame and on its corner (MoveIt's "object/subframe").
    on_corner = {
        "id": "peg",
        "header": {"frame_id": "tray/corner"},
        "primitives": [{"type": "cylinder", "dimensions": [0.1, 0.01]}],
        "primitive_poses": [{"position": [0, 0, 0.05]}],
    }
    on_tray = {**on_corner, "id": "lid", "header": {"frame_id": "tray"}}
    load(scene, write, tray, on_corner, on_tray)
    corner = subframe_pose(scene, "tray/corner").translation()
    np.testing.assert_allclose(corner, [0.4, 0.15, 0.2], atol=1e-6)  # (0.15, 0.1) turned 90
    np.testing.assert_allclose(subframe_pose(scene, "tray/centre").translation(), [0.5, 0, 0.2])
    np.testing.assert_allclose(subframe_pose(scene, "tray").translation(), [0.5, 0, 0.19])
    peg = scene.world_objects["peg"].X_PO.translation()
    np.testing.assert_allclose(peg, [0.4, 0.15, 0.25], atol=1e-6)
    lid = scene.world_objects["lid"].X_PO.translation()
    np.testing.assert_allclose(lid, [0.5, 0, 0.25], atol=1e-6)
    with pytest.raises(KeyError, match="no frame 'edge'"):
        subframe_pose(scene, "tray/edge")
    with pytest.raises(KeyError, match="no object named 'shelf'"):
        subframe_pose(scene, "shelf/edge")


def test_the_robot_state_is_the_start_configuration(scene, write):
    q = [0.3, -0.5, 0.2, -2.0, 0.1, 1.8, 0.4]
    state = {"joint_state": {"name": list(ARM_JOINTS[:5]), "position": q[:5]}}
    loaded = load(scene, write, robot_state=state, name="start.yaml")
    assert loaded.joint_positions == dict(zip(ARM_JOINTS[:5], q[:5], strict=True))
    default = mut.SceneFrames({}, scene, mut.Issues("x")).q
    np.testing.assert_allclose(loaded.start[:5], q[:5])
    np.testing.assert_allclose(loaded.start[5:], default[5:])  # MoveIt's defaults
    base = scene.full_q(scene.model.named_configurations["ready"])
    path = write(yaml.safe_dump({"robot_state": state}), "start.yaml")
    again = mut.load_moveit_scene(scene, path, base=base)
    np.testing.assert_allclose(again.start[:5], q[:5])
    np.testing.assert_allclose(again.start[5:], base[5:])  # the joints not named keep theirs
    assert scene.arm_q(again.start).shape == (7,)


def test_fixed_frames_as_moveit_writes_them(scene, write):
    """MoveIt writes a frame F as header F, child the planning frame, the pose of F in it."""
    fixed = [
        {
            "header": {"frame_id": "shelf"},
            "child_frame_id": "world",
            "transform": {"translation": [1.0, 2.0, 0.0], "rotation": [0, 0, 0, 1]},
        },
        {  # a frame relative to a link, as tf writes it
            "header": {"frame_id": "panda_link0"},
            "child_frame_id": "base_link",
            "transform": {"translation": [0.0, 0.0, 0.5]},
        },
    ]
    box = {"id": "b", "header": {"frame_id": "shelf"}}
    box.update(primitives=[{"type": 1, "dimensions": [0.1] * 3}])
    box["primitive_poses"] = [{"position": [0.5, 0, 0.1]}]
    other = {**box, "id": "c", "header": {"frame_id": "base_link"}}
    load(scene, write, box, other, fixed_frame_transforms=fixed)
    np.testing.assert_allclose(scene.world_objects["b"].X_PO.translation(), [1.5, 2.0, 0.1])
    np.testing.assert_allclose(scene.world_objects["c"].X_PO.translation(), [0.5, 0.0, 0.6])


def test_a_moved_base_moves_the_world_instead(caplog, scene, write):
    box = {"id": "b", "primitives": [{"type": 1, "dimensions": [0.1] * 3}]}
    box["primitive_poses"] = [{"position": [1.5, 0.0, 0.1]}]
    held = {**box, "id": "h", "header": {"frame_id": "world"}}
    base = {"translation": [1.0, 0.0, 0.0], "rotation": [0, 0, 0, 1]}
    state = {
        "multi_dof_joint_state": {"joint_names": ["virtual_joint"], "transforms": [base]},
        "attached_collision_objects": [{"link_name": "panda_hand", "object": held}],
    }
    with caplog.at_level(logging.WARNING):
        load(scene, write, box, robot_state=state)
    assert "the robot's base is at [1.0, 0.0, 0.0]" in caplog.text
    np.testing.assert_allclose(scene.world_objects["b"].X_PO.translation(), [0.5, 0.0, 0.1])
    q = mut.SceneFrames({}, scene, mut.Issues("x")).q
    np.testing.assert_allclose(scene.object_pose("h", q).translation(), [0.5, 0, 0.1], atol=1e-9)


OTHER_ROBOT = {
    "robot_model_name": "ur5",
    "robot_state": {
        "joint_state": {
            "name": ["shoulder_pan_joint", "elbow_joint", "panda_joint1"],
            "position": [0.1, 0.2, 0.3],
        }
    },
    "world": {
        "collision_objects": [
            {
                "id": "on_base",
                "header": {"frame_id": "base_link"},
                "primitives": [{"type": 1, "dimensions": [0.1, 0.1, 0.1]}],
                "primitive_poses": [{"position": [0.5, 0, 0.1]}],
            },
            {
                "id": "in_world",
                "header": {"frame_id": "world"},
                "primitives": [{"type": 1, "dimensions": [0.1, 0.1, 0.1]}],
                "primitive_poses": [{"position": [0.5, 0, 0.1]}],
            },
        ]
    },
    "allowed_collision_matrix": {
        "entry_names": ["base_link", "shoulder_link", "panda_link1", "panda_link7"],
        "entry_values": [[False, True, False, False], [True, False, False, False]]
        + [[False, False, False, True], [False, False, True, False]],
    },
}


def test_a_scene_for_another_robot_loads_what_this_one_can_hold(caplog, scene, write):
    """The links and joints are the plant's: base_link and the UR5's joints are not the
    Panda's, so the object on base_link, the joints and the UR5's allowed pair are left out,
    one warning each; panda_joint1 and the Panda's allowed pair are kept."""
    path = write(yaml.safe_dump(OTHER_ROBOT), "ur5.yaml")
    with caplog.at_level(logging.WARNING):
        loaded = mut.load_moveit_scene(scene, path)
    assert list(scene.world_objects) == ["in_world"] and loaded.skipped == ["on_base"]
    assert loaded.joint_positions == {"panda_joint1": 0.3}
    assert len(loaded.warnings) == 3 and len(caplog.records) == 3
    assert (
        "2 joints that panda does not have left out (shoulder_pan_joint, elbow_joint)"
        in (loaded.warnings[0])
    )
    assert "object 'on_base' skipped: unknown frame 'base_link'" in loaded.warnings[1]
    assert "base_link <-> shoulder_link" in loaded.warnings[2]
    body = scene.plant.GetBodyByName
    assert scene.checker.IsCollisionFilteredBetween(body("panda_link1"), body("panda_link7"))
    with pytest.raises(PlanningError) as info:
        mut.load_moveit_scene(scene, path, strict=True)
    assert info.value.code == ErrorCode.INVALID_SCENE
    assert "joints that panda does not have" in info.value.message
    assert "strict" in info.value.message


def test_a_diff_applies_to_an_empty_scene(scene, write):
    box = {"id": "b", "primitives": [{"type": 1, "dimensions": [0.1] * 3}]}
    box["primitive_poses"] = [{"position": [0.5, 0.0, 0.1]}]
    loaded = load(scene, write, box, is_diff=True, robot_state={"is_diff": True})
    assert list(scene.world_objects) == ["b"] and loaded.warnings == []


def test_shapes_of_one_object_in_order_primitives_meshes_planes(scene, write):
    everything = {
        "id": "all",
        "primitives": [{"type": 2, "dimensions": [0.05]}],
        "primitive_poses": [{"position": [0.5, 0, 0.5]}],
        "meshes": [{"vertices": CUBE, "triangles": [{"vertex_indices": t} for t in TRIANGLES]}],
        "mesh_poses": [{"position": [0.5, 0.2, 0.5]}],
        "planes": [{"coef": [0, 0, 1, 0]}],
        "plane_poses": [{"position": [0, 0, -0.5]}],
    }
    load(scene, write, everything)
    shapes = [(n, o.shape) for n, o in scene.world_objects.items()]
    assert shapes == [("all", "sphere"), ("all#1", "convex"), ("all#2", "box")]
    top = scene.world_objects["all#2"].X_PO @ np.array([0, 0, 5.0])
    np.testing.assert_allclose(top, [0, 0, -0.5], atol=1e-12)
