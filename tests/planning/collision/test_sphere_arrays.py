"""The sphere kernels' arrays (planning.collision.sphere_arrays): groups that hold their spheres,
thresholds with the margin on the safe side, the robot's arrays as the model reads them, exact
shapes folded with the kinematic tree, and the world's objects as kernel rows."""

import numpy as np
import pytest
from pydrake.math import RigidTransform

import planning.collision.sphere_arrays as mut
from planning import PlanningScene
from planning.collision import sphere_kernel
from planning.collision.sphere_checker import sphere_model
from planning.collision.sphere_cover import SphereSet


@pytest.fixture(scope="module")
def scene():
    scene = PlanningScene()
    scene.add_box("wall", [0.05, 0.8, 0.8], RigidTransform([0.45, 0.0, 0.4]))
    return scene


def _spheres(n, seed=0):
    rng = np.random.default_rng(seed)
    radius = rng.uniform(0.01, 0.05, n)
    return SphereSet(p_BS=rng.normal(0.0, 0.1, (n, 3)), radius=radius, inner=0.5 * radius)


def test_body_groups_hold_their_spheres():
    spheres = _spheres(11)
    groups, bounds, (centre, radius), norm = mut.body_groups(spheres)
    assert sorted(np.concatenate(groups)) == list(range(11))
    assert all(len(g) <= mut.GROUP for g in groups)
    for members, (c, r) in zip(groups, bounds, strict=True):
        reach = np.linalg.norm(spheres.p_BS[members] - c, axis=1) + spheres.radius[members]
        assert np.all(reach <= r + 1e-12)  # a group's sphere holds its spheres
        assert np.linalg.norm(c - centre) + r <= radius + 1e-12  # the body's holds the groups
    assert norm >= np.linalg.norm(spheres.p_BS, axis=1).max()


def test_the_models_robot_arrays_are_robot_arrays_of_its_spheres(scene):
    model = sphere_model(scene)
    data = model.kernel_data()
    # Outer thresholds exceed the spheres' own sums by the margin: never above a true distance.
    used = data.env_out >= 0
    assert np.all(np.sqrt(data.env_out[used]) >= model._radius[data.env_member[used]] + mut.MARGIN)
    assert len(data.sphere_step) == model.num_spheres
    assert np.all(np.diff(data.body_pair_start) >= 0)
    rows = mut.primitives(scene.world_objects.values())
    np.testing.assert_array_equal(data.objects, rows)


def test_hull_arrays_and_their_folding(scene):
    model = sphere_model(scene)
    raw = model._hull_raw
    assert raw["vert_start"][-1] == len(raw["vert"])
    assert np.all(raw["geom_bound"] > 0) and np.all(raw["pair_gap"] >= mut.HULL_MARGIN)
    hulls = model.hull_data()
    assert isinstance(hulls, mut.HullData)
    assert len(hulls.geom_step) == len(raw["geom_step"])
    assert np.all(hulls.geom_step < len(model.kernel_data().parent))  # the folded tree's steps


def test_filters_and_robot_arrays_thresholds_follow_the_paddings():
    spheres = {0: _spheres(6, 1), 1: _spheres(5, 2)}
    padding = np.full((3, 3), 0.02)
    filtered = np.zeros((3, 3), dtype=int)
    filters = mut.Filters(filtered, padding, world_body=2, checked={(0, 1)})
    step, slot = np.array([4, 7]), {0: 0, 1: 1}
    dut = mut.robot_arrays(spheres, lambda b, s: mut.body_groups(s), step, slot, filters)
    assert dut.sphere_slot.tolist() == [0] * 6 + [1] * 5
    assert dut.arrays["body_step"].tolist() == [4, 7]
    np.testing.assert_array_equal(dut.radius, np.concatenate([s.radius for s in spheres.values()]))
    assert len(dut.arrays["body_pair"]) == 1  # the one checked pair
    out = dut.arrays["env_out"]
    radius = dut.radius[dut.arrays["env_member"]]
    np.testing.assert_allclose(np.sqrt(out[out >= 0]), (radius + 0.02 + mut.MARGIN)[out >= 0])


def test_speed_table_bounds_a_revolute_joints_points():
    # One revolute joint about z at the origin: a point r from the axis moves r m/rad.
    terms = np.zeros((1, 3, 3, 4))
    terms[0, 0, 2, 2] = 1.0  # A: z stays
    terms[0, 1] = [[0, -1, 0, 0], [1, 0, 0, 0], [0, 0, 0, 0]]  # B: the sin q part
    terms[0, 2] = [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 0, 0]]  # C: the cos q part
    speed = mut.speed_table(
        np.array([-1]), np.array([1]), np.array([0]), terms, np.zeros(1), np.array([0]),
        np.array([0]), np.array([0.3]),
    )  # fmt: skip
    # A bound: B's and C's rotations stacked, sqrt(2) times the true 0.3 m/rad here.
    assert speed.shape == (1, 1) and 0.3 < speed[0, 0] == pytest.approx(0.3 * np.sqrt(2))


def test_primitives_are_kernel_rows():
    scene = PlanningScene()
    scene.add_sphere("ball", 0.1, RigidTransform([0.3, 0.0, 0.5]))
    (row,) = mut.primitives([scene.world_objects["ball"]])
    assert row[sphere_kernel.OBJ_KIND] == 2 and row[sphere_kernel.OBJ_SIZE] == 0.1
    lower = row[sphere_kernel.OBJ_LOWER : sphere_kernel.OBJ_LOWER + 3]
    np.testing.assert_allclose(lower, [0.2, -0.1, 0.4])
    assert sphere_kernel._distance2(0.3, 0.0, 0.5, row) == 0.0  # inside
