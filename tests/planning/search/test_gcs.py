"""GCS paths (planning.search.gcs) through IRIS regions on the pick-and-place scene, every path
re-checked independently at 0.01 rad; the regions CLI and the planner's use of GCS. The regions
themselves are tested in test_iris_regions."""

import os
import subprocess
import sys

import numpy as np
import pytest
from pydrake.geometry.optimization import HPolyhedron
from pydrake.math import RigidTransform, RotationMatrix

import planning.search.gcs as mut
import planning.search.iris_regions as regions_mut
from planning import PlanningScene, RobotState
from planning.io.scene_files import load_scene_yaml
from tests.cli_helpers import assert_bad_input

R_DOWN = RotationMatrix.MakeXRotation(np.pi)  # hand z axis pointing down
# Coarser than the defaults (about 2 s instead of 6 s for this scene); the paths are checked.
CHEAP = regions_mut.RegionOptions(epsilon=0.05, num_particles=200)


@pytest.fixture(scope="module")
def scene():
    scene = PlanningScene()
    load_scene_yaml(scene, "config/pickplace.yaml")
    return scene


@pytest.fixture(scope="module")
def seeds(scene):
    """ready, pre-grasp above the object, pre-place above the place target."""
    state = RobotState(scene)
    ready = state.named("ready")
    p_object = scene.object_pose("object").translation()
    out = [ready]
    for p in (p_object, scene.place_position):
        out.append(state.ik(RigidTransform(R_DOWN, p + [0, 0, 0.12]), q_seed=ready).q)
    return np.array(out)


@pytest.fixture(scope="module")
def cache(tmp_path_factory):
    return tmp_path_factory.mktemp("regions")


@pytest.fixture(scope="module")
def regions(scene, seeds, cache):
    return regions_mut.load_or_build_regions(scene, seeds, CHEAP, folder=cache)


def assert_fine_collision_free(scene, path, resolution=0.01):
    """Checks the straight-line interpolation with the scene's own single-config query."""
    for a, b in zip(path[:-1], path[1:], strict=True):
        n = max(1, int(np.ceil(np.linalg.norm(b - a) / resolution)))
        for s in np.linspace(0.0, 1.0, n + 1):
            assert scene.is_collision_free(a + s * (b - a)), f"collision at {a + s * (b - a)}"


def test_gcs_over_the_obstacle_is_collision_free(scene, seeds, regions):
    pre_grasp, pre_place = seeds[1], seeds[2]
    assert not scene.is_edge_collision_free(pre_grasp, pre_place)
    result = mut.GcsPlanner(scene, regions).plan(pre_grasp, pre_place)
    assert result.success, result.message
    np.testing.assert_array_equal(result.path[0], pre_grasp)
    np.testing.assert_array_equal(result.path[-1], pre_place)
    assert_fine_collision_free(scene, result.path)
    # Shorter than going back up through "ready".
    via_ready = np.linalg.norm(seeds[0] - pre_grasp) + np.linalg.norm(pre_place - seeds[0])
    assert result.length < via_ready


def test_gcs_from_ready_to_a_pose_over_the_obstacle(scene, seeds, regions):
    state = RobotState(scene)
    top = scene.world_objects["obstacle"].X_PO.translation() + [0, 0, 0.25]
    q_over = state.ik(RigidTransform(R_DOWN, top), q_seed=seeds[0]).q
    result = mut.GcsPlanner(scene, regions).plan(seeds[0], q_over)
    assert result.success, result.message
    np.testing.assert_array_equal(result.path[-1], q_over)
    assert_fine_collision_free(scene, result.path)


def test_start_outside_the_regions_is_joined_by_a_checked_edge(scene, seeds):
    ready = seeds[0]
    box = HPolyhedron.MakeBox(ready - 0.05, ready + 0.05)
    dut = mut.GcsPlanner(scene, [box])
    start, goal = ready + [0.3, 0, 0, 0, 0, 0, 0], ready + [0, 0, 0, 0, 0, 0, 0.02]
    result = dut.plan(start, goal)
    assert result.success, result.message
    np.testing.assert_array_equal(result.path[0], start)
    assert box.PointInSet(result.path[1], 1e-6)
    assert_fine_collision_free(scene, result.path)


def test_a_region_through_the_obstacle_is_repaired_or_reported(scene, seeds):
    """A region that holds the colliding straight line between pre-grasp and pre-place (as a
    too-coarse IRIS region may): the result is never an unchecked path."""
    pre_grasp, pre_place = seeds[1], seeds[2]
    box = HPolyhedron.MakeBox(np.minimum(pre_grasp, pre_place), np.maximum(pre_grasp, pre_place))
    dut = mut.GcsPlanner(scene, [box], mut.GcsOptions(max_repairs=2))
    result = dut.plan(pre_grasp, pre_place)
    if result.success:
        assert_fine_collision_free(scene, result.path)
    else:
        assert result.path is None and result.repairs >= 1
        assert "collides" in result.message or "no path" in result.message
    assert dut.regions[0].A().shape[0] > box.A().shape[0]  # cut


def test_unreachable_goal_is_reported(scene, seeds, regions):
    colliding = np.array([0, 1.7, 0, -0.5, 0, 0.5, 0])
    result = mut.GcsPlanner(scene, regions).plan(seeds[0], colliding)
    assert not result.success and result.path is None
    assert "goal collides" in result.message


def test_regions_cli_rejects_bad_input(tmp_path):
    def cli(*args):
        return subprocess.run(
            [sys.executable, "-m", "drake_sim.tools.regions", *args], capture_output=True, text=True
        )

    assert_bad_input(cli("--scene", str(tmp_path / "none.yaml")), "none.yaml")
    assert_bad_input(cli("--scene", "config/pickplace.yaml", "--set", "epsilon=x"), "epsilon")
    assert_bad_input(cli("--scene", "config/pickplace.yaml", "--set", "bogus=1"), "bogus")


def test_regions_cli_builds_then_loads(tmp_path):
    env = {**os.environ, "DRAKE_SIM_CACHE": str(tmp_path)}
    command = [sys.executable, "-m", "drake_sim.tools.regions", "--scene", "config/pickplace.yaml"]
    command += ["--set", "num_particles=200", "--set", "epsilon=0.05"]
    first = subprocess.run(command, capture_output=True, text=True, env=env)
    assert first.returncode == 0, first.stderr
    assert "built and saved" in first.stdout and "region 1:" in first.stderr
    second = subprocess.run(command, capture_output=True, text=True, env=env)
    assert second.returncode == 0 and "loaded from" in second.stdout
    assert len(list((tmp_path / "iris_regions").glob("*.npz"))) == 1


def test_motion_planner_uses_gcs_while_the_scene_is_unchanged(scene, seeds, regions):
    from planning import MotionPlanner

    dut = MotionPlanner(scene)
    dut.use_gcs(regions, CHEAP)
    result = dut.plan_to_joints(seeds[2], q_start=seeds[1])  # over the obstacle
    assert result.success and result.trajectory.info["planner"].startswith("gcs")
    assert_fine_collision_free(scene, result.trajectory.waypoints)
    scene.add_box("late_box", [0.05, 0.05, 0.05], RigidTransform([0.3, 0.5, 0.5]))
    try:  # the regions no longer describe the scene: RRT-Connect
        again = dut.plan_to_joints(seeds[2], q_start=seeds[1])
        assert again.trajectory.info["planner"].startswith("rrt_connect")
    finally:
        scene.remove_object("late_box")
