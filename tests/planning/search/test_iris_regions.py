"""IRIS regions (planning.search.iris_regions) on the pick-and-place scene, with cheap options: the
regions cover the seeds, join consecutive seeds through overlapping regions, are mostly
collision-free inside, are cached on disk under a key that changes with the scene, the fingers,
the seeds and the options; bad seeds and options are rejected."""

from collections import deque

import numpy as np
import pytest
from pydrake.common import RandomGenerator
from pydrake.geometry.optimization import HPolyhedron
from pydrake.math import RigidTransform, RotationMatrix

import planning.search.iris_regions as mut
from planning import PlanningScene, RobotState
from planning.io.scene_files import load_scene_yaml

R_DOWN = RotationMatrix.MakeXRotation(np.pi)  # hand z axis pointing down
# Coarser than the defaults (about 1 s instead of 6 s for this scene).
CHEAP = mut.RegionOptions(epsilon=0.05, num_particles=200)


@pytest.fixture(scope="module")
def scene():
    scene = PlanningScene()
    load_scene_yaml(scene, "config/pickplace.yaml")
    return scene


@pytest.fixture(scope="module")
def seeds(scene):
    """ready, pre-grasp above the object, pre-place above the place target (the obstacle
    between the last two)."""
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
    return mut.load_or_build_regions(scene, seeds, CHEAP, folder=cache)


def test_regions_cover_the_seeds_and_are_cached(scene, seeds, regions, cache):
    assert not regions.loaded and regions.path.is_file() and regions.path.parent == cache
    assert regions.path.stem == regions.key == mut.region_key(scene, seeds, CHEAP)
    assert len(regions.regions) >= 2
    assert all(regions.containing(q) for q in seeds)
    np.testing.assert_array_equal(regions.seeds, seeds)
    again = mut.load_or_build_regions(scene, seeds, CHEAP, folder=cache)
    assert again.loaded and again.key == regions.key
    assert again.build_time == pytest.approx(regions.build_time)
    for a, b in zip(regions.regions, again.regions, strict=True):
        np.testing.assert_array_equal(a.A(), b.A())
        np.testing.assert_array_equal(a.b(), b.b())
    with np.load(regions.path) as data:  # the documented file layout
        n = len(regions.regions)
        assert {f"A_{i}" for i in range(n)} | {f"b_{i}" for i in range(n)} | {
            "seeds",
            "meta",
        } == set(data.files)
        np.testing.assert_array_equal(data["seeds"], seeds)


def test_consecutive_seeds_are_joined_through_overlapping_regions(seeds, regions):
    """With ``connect``, a chain of overlapping regions leads from each seed to the next."""
    sets = regions.regions
    assert all(r.ambient_dimension() == 7 for r in sets)
    neighbours = {
        i: [j for j in range(len(sets)) if j != i and sets[i].IntersectsWith(sets[j])]
        for i in range(len(sets))
    }
    for q_a, q_b in zip(seeds[:-1], seeds[1:], strict=True):
        reached, todo = set(regions.containing(q_a)), deque(regions.containing(q_a))
        while todo:
            for j in neighbours[todo.popleft()]:
                if j not in reached:
                    reached.add(j)
                    todo.append(j)
        assert reached & set(regions.containing(q_b))


def test_regions_are_mostly_collision_free_inside(scene, regions):
    generator = RandomGenerator(0)
    free = []
    for region in regions.regions:
        q = region.ChebyshevCenter()
        for _ in range(40):
            q = region.UniformSample(generator, q)
            free.append(scene.is_collision_free(q))
    assert np.mean(free) > 0.9  # at most epsilon = 5 % of each region collides, w.h.p.


def test_without_connect_one_region_per_seed_and_the_region_limit(scene, seeds):
    options = mut.RegionOptions(epsilon=0.05, num_particles=200, connect=False)
    dut = mut.build_regions(scene, seeds, options)
    assert len(dut) == len(seeds)
    for region, q in zip(dut, seeds, strict=True):
        assert region.PointInSet(q, 1e-9)
        # Within the box of max_half_width around its seed.
        w = options.max_half_width
        assert region.ContainedIn(HPolyhedron.MakeBox(q - w, q + w), 1e-6)
    with pytest.raises(RuntimeError, match="max_regions"):
        mut.build_regions(scene, seeds, mut.RegionOptions(connect=False, max_regions=2))


def test_the_key_changes_with_the_scene_fingers_seeds_and_options(scene, seeds):
    key = mut.region_key(scene, seeds, CHEAP)
    assert mut.region_key(scene, seeds, CHEAP) == key
    assert mut.region_key(scene, seeds + 1e-8, CHEAP) == key  # seeds are rounded to 1e-6 rad
    assert mut.region_key(scene, seeds[:2], CHEAP) != key
    assert mut.region_key(scene, seeds[::-1], CHEAP) != key  # the route's order matters
    assert mut.region_key(scene, seeds, mut.RegionOptions()) != key
    obstacle = scene.world_objects["obstacle"].X_PO
    scene.move_object("obstacle", RigidTransform(obstacle.translation() + [0, 0.01, 0]))
    try:
        assert mut.region_key(scene, seeds, CHEAP) != key
    finally:
        scene.move_object("obstacle", obstacle)
    fingers = scene.finger_positions
    scene.finger_positions = 0.0
    try:
        assert mut.region_key(scene, seeds, CHEAP) != key
    finally:
        scene.finger_positions = fingers
    assert mut.region_key(scene, seeds, CHEAP) == key


def test_bad_seeds_and_options_are_rejected(scene, seeds, cache):
    with pytest.raises(ValueError, match="collides"):
        mut.load_or_build_regions(scene, [[0, 1.7, 0, -0.5, 0, 0.5, 0]], folder=cache)
    with pytest.raises(ValueError, match="shape"):
        mut.load_or_build_regions(scene, np.zeros((2, 6)), folder=cache)
    with pytest.raises(ValueError, match="out of the joint limits"):
        mut.load_or_build_regions(scene, [seeds[0] + [5.0, 0, 0, 0, 0, 0, 0]], folder=cache)
    with pytest.raises(ValueError, match="RegionOptions"):
        mut.load_or_build_regions(scene, seeds, mut.RegionOptions(epsilon=0.0), folder=cache)


@pytest.mark.parametrize(
    "bad",
    [
        {"epsilon": 1.0},
        {"delta": 0.0},
        {"num_particles": 0},
        {"bisection_steps": 0},
        {"max_half_width": -0.1},
        {"max_regions": 0},
    ],
)
def test_check_region_options(bad):
    mut.check_region_options(CHEAP)
    with pytest.raises(ValueError, match="bad RegionOptions"):
        mut.check_region_options(mut.RegionOptions(**bad))
