"""Every real MoveIt scene file in ``../shared/real_ros/moveit/`` (scene_text/, yaml/, derived/;
see its SOURCES.md) loads onto the Panda's scene: what it holds, with one warning for each thing
left out, and an error for each of those when strict. Scenes written for Fetch and the UR5 name
links and joints the Panda does not have: those objects and joints are left out, warned. The
MotionBenchMaker sets of the UR5, Fetch and Baxter (in the cache) load too. A test skips, with
the reason, where the files are absent."""

import collections
from pathlib import Path

import pytest

import planning.io.moveit_scene as mut
from planning import ErrorCode, PlanningError
from planning.io.mbm import cached_folder

ROOT = Path(__file__).resolve().parents[3].parent / "shared" / "real_ros" / "moveit"
USER_CACHE = Path.home() / ".cache" / "drake_sim"
"""The default cache, read where the test session's own (empty) cache lacks something: the
MotionBenchMaker sets and VAMP's resources are downloads, never fetched by these tests."""

# file: (world objects, held objects, warnings, objects left out, shapes loaded)
EXPECTED = {
    "derived/p01_object_colors.yaml": (7, 0, 0, 0, "box 6, cylinder 1"),
    "derived/p02_remove_op.yaml": (6, 0, 0, 0, "box 6"),
    "derived/p03_mesh.yaml": (7, 0, 1, 1, "box 6, cylinder 1"),  # robowflex_resources
    "derived/p04_plane.yaml": (8, 0, 0, 0, "box 7, cylinder 1"),  # the plane: a box
    "derived/p05_frame_panda_link0.yaml": (7, 0, 0, 0, "box 6, cylinder 1"),
    "derived/p06_attached.yaml": (7, 1, 0, 0, "box 6, cylinder 1"),
    "derived/p07_ros2_echo_style_int_op.yaml": (7, 0, 0, 0, "box 6, cylinder 1"),
    "derived/p08_ros2_echo_byte_op.yaml": (7, 0, 0, 0, "box 6, cylinder 1"),
    "derived/p09_mbm_template_plus_fixed_frame.yaml": (7, 0, 0, 0, "box 6, cylinder 1"),
    "derived/p10_cone.yaml": (8, 0, 0, 0, "box 6, convex 1, cylinder 1"),
    "derived/p11_is_diff.yaml": (7, 0, 0, 0, "box 6, cylinder 1"),
    "derived/s01_obstacle_example_plus_dot.scene": (1, 0, 0, 0, "box 1"),
    "derived/s02_constrained_space_newformat.scene": (3, 0, 0, 0, "box 3"),
    "derived/s03_table_with_objects_minus_mesh.scene": (8, 0, 0, 0, "box 6, cylinder 2"),
    "scene_text/sr_benchmarking/empty.scene": (0, 0, 1, 0, ""),  # "." alone
    "scene_text/sr_benchmarking/scene_ground.scene": (1, 0, 0, 0, "box 1"),
    "scene_text/sr_benchmarking/scene_ground_with_boxes.scene": (5, 0, 0, 0, "box 5"),
    "scene_text/sr_benchmarking/scene_table.scene": (5, 0, 0, 0, "box 4, convex 1"),
    "scene_text/sr_benchmarking/scene_table_with_objects.scene": (
        9,
        0,
        0,
        0,
        "box 6, convex 1, cylinder 2",
    ),
    "scene_text/sr_benchmarking/scene_table_with_tote.scene": (6, 0, 0, 0, "box 4, convex 2"),
    "scene_text/sr_benchmarking/scene_table_with_two_totes.scene": (7, 0, 0, 0, "box 4, convex 3"),
    "scene_text/sr_benchmarking/test_scene_to_import.scene": (5, 0, 0, 0, "box 5"),
    "scene_text/sr_interface_left/constrained_space.scene": (3, 0, 0, 0, "box 3"),
    "scene_text/sr_interface_left/obstacle_example.scene": (1, 0, 1, 0, "box 1"),  # no "."
    "scene_text/sr_interface_right/constrained_space.scene": (3, 0, 0, 0, "box 3"),
    "scene_text/sr_interface_right/obstacle_example.scene": (1, 0, 1, 0, "box 1"),  # no "."
    # Fetch's (MBM's templates, robowflex): every object in base_link, a link of Fetch.
    "yaml/motion_bench_maker/scene_box.yaml": (0, 0, 7, 7, ""),
    "yaml/motion_bench_maker/scene_cage.yaml": (0, 0, 8, 8, ""),
    "yaml/motion_bench_maker/scene_small.yaml": (0, 0, 7, 7, ""),
    "yaml/motion_bench_maker/scene_table.yaml": (0, 0, 12, 12, ""),
    "yaml/motion_bench_maker/scene_tall.yaml": (0, 0, 15, 15, ""),
    "yaml/motion_bench_maker/scene_thin.yaml": (0, 0, 21, 21, ""),
    "yaml/robowflex/fetch_scene.yml": (0, 0, 21, 21, ""),  # meshes of fetch_description
    "yaml/robowflex/scene0001.yaml": (0, 0, 9, 7, ""),  # + Fetch's joints, its allowed pairs
    "yaml/robowflex/scene_vicon0001.yaml": (0, 0, 10, 7, ""),  # + tracker frames
    "yaml/robowflex/table_scene.yaml": (0, 0, 8, 8, ""),
    "yaml/robowflex/test.yml": (1, 0, 3, 1, "box 1"),  # UR5's joints and pairs, a kinect mesh
}


def real_file(name: str) -> Path:
    path = ROOT / name
    if not path.is_file():
        pytest.skip(f"the real MoveIt scene files are not at {ROOT}")
    return path


def test_every_real_file_is_listed():
    if not ROOT.is_dir():
        pytest.skip(f"the real MoveIt scene files are not at {ROOT}")
    found = {
        str(p.relative_to(ROOT))
        for folder in ("scene_text", "yaml", "derived")
        for p in (ROOT / folder).rglob("*")
        if p.suffix in (".scene", ".yaml", ".yml")
    }
    assert found == set(EXPECTED)


@pytest.mark.parametrize("name", sorted(EXPECTED))
def test_real_files_load_with_a_warning_for_what_is_left_out(shared_scene, name):
    path = real_file(name)
    world, held, warnings, skipped, shapes = EXPECTED[name]
    loaded = mut.load_moveit_scene(shared_scene, path)
    assert (len(loaded.world), len(loaded.attached)) == (world, held)
    assert (len(loaded.warnings), len(loaded.skipped)) == (warnings, skipped)
    assert all(str(path) in w for w in loaded.warnings)
    assert describe(loaded.world) == shapes
    assert sorted(shared_scene.world_objects) == sorted(o.name for o in loaded.world)
    if warnings:
        with pytest.raises(PlanningError) as info:
            mut.load_moveit_scene(shared_scene, path, strict=True)
        assert info.value.code == ErrorCode.INVALID_SCENE and "strict" in info.value.message


def describe(objects) -> str:
    counts = collections.Counter(o.shape for o in objects)
    return ", ".join(f"{shape} {n}" for shape, n in sorted(counts.items()))


def test_meshes_are_hulls_in_the_scene(shared_scene):
    """scene_table_with_tote.scene: a table and a tote given as triangles, as hulls."""
    mut.load_moveit_scene(shared_scene, real_file(EXPECTED_TOTE))
    table = shared_scene.world_objects["shadow_table_2017_full_simplified__link"]
    assert table.shape == "convex" and len(table.vertices) == 8  # a 1.5 x 1.5 x 0.012 slab
    q = shared_scene.model.named_configurations["ready"]
    assert "shadow_table_2017_full_simplified__link" in shared_scene.describe_collisions(q)


EXPECTED_TOTE = "scene_text/sr_benchmarking/scene_table_with_tote.scene"


def test_fetch_meshes_load_through_a_package_map(shared_scene):
    """robowflex's Fetch, drawn as collision objects from fetch_description's meshes (DAE and
    STL), found in VAMP's copy of Fetch's meshes."""
    path = real_file("yaml/robowflex/fetch_scene.yml")
    fetch = USER_CACHE / "packages" / "vamp_resources" / "fetch"
    if not (fetch / "meshes" / "base_link.dae").is_file():
        from tests.planning.model.real_files import vamp_robot_dir

        fetch = vamp_robot_dir("fetch")  # skips when there is no copy
    packages = {"fetch_description": str(fetch)}
    loaded = mut.load_moveit_scene(shared_scene, path, package_paths=packages)
    assert loaded.warnings == [] and len(loaded.world) == 21
    assert {o.shape for o in loaded.world} == {"convex"}


@pytest.mark.parametrize("robot", ["ur5", "fetch", "baxter"])
def test_motionbenchmaker_sets_of_other_robots_load(shared_scene, robot):
    folders = [cached_folder(robot), USER_CACHE / "mbm" / robot]
    scenes = [sorted(f.glob("*/scene0001.yaml")) for f in folders if f.is_dir()]
    scenes = next((found for found in scenes if found), [])
    if not scenes:
        pytest.skip(f"no MotionBenchMaker set of {robot} in {' or '.join(map(str, folders))}")
    for path in scenes:
        loaded = mut.load_moveit_scene(shared_scene, path)
        # Fetch's objects sit in base_link, a link of Fetch: left out on the Panda, one warning
        # each; the UR5's and Baxter's are in the world. Each warns once of the robot's joints
        # and once of its allowed pairs.
        if robot == "fetch":
            assert loaded.world == [] and loaded.skipped, path
        else:
            assert loaded.world and loaded.skipped == [], path
        assert len(loaded.warnings) == 2 + len(loaded.skipped), path
        assert "joints that panda does not have" in loaded.warnings[0]
