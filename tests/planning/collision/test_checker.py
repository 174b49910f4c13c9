"""Collision queries on Drake's checker (planning.collision.checker): CheckerAdapter's
configuration, batch, edge and free-prefix queries agree with the scene's own checks on a scene
with a wall in front of the hand; edges proven free at the adapter's resolution are remembered
under their edge_key; first_invalid_segment finds the first colliding segment of a path (None
for a free one) and skips segments already proven free."""

import numpy as np
import pytest
from pydrake.math import RigidTransform

import planning.collision.checker as mut
from planning.paths import densify

E = np.eye(7)


@pytest.fixture(scope="module")
def scene(wall_scene):
    """The wall scene (``tests/planning/conftest.py``)."""
    return wall_scene


@pytest.fixture(scope="module")
def ends(scene):
    """(left, middle, right): left and right are free, the middle collides with the wall."""
    ready = scene.model.named_configurations["ready"]
    return ready - 0.8 * E[0], ready, ready + 0.8 * E[0]


@pytest.fixture
def dut(scene):
    return mut.CheckerAdapter(scene)


def random_free(scene, n, seed):
    adapter = mut.CheckerAdapter(scene)
    qs = np.random.default_rng(seed).uniform(adapter.lower, adapter.upper, (4 * n, 7))
    return qs[adapter.configs_free(qs)][:n]


def nearby(scene, q_a, size, seed):
    """A configuration about ``size`` rad from each row of q_a, within the joint limits."""
    adapter = mut.CheckerAdapter(scene)
    step = np.random.default_rng(seed).normal(0.0, size / np.sqrt(7), q_a.shape)
    return np.clip(q_a + step, adapter.lower, adapter.upper)


def samples_free(scene, q_a, q_b, resolution):
    """Every sample of the segment at ``resolution``, each checked by the scene on its own."""
    return all(scene.is_collision_free(q) for q in densify(np.vstack([q_a, q_b]), resolution)[0])


def test_limits_and_full_configurations(scene, dut):
    arm = scene.model.arm_indices
    np.testing.assert_array_equal(dut.lower, scene.plant.GetPositionLowerLimits()[arm])
    np.testing.assert_array_equal(dut.upper, scene.plant.GetPositionUpperLimits()[arm])
    q = np.linspace(-1.0, 1.0, 7)
    np.testing.assert_array_equal(dut.full(q), scene.full_q(q))
    assert dut.resolution is None and mut.CheckerAdapter(scene, 0.02).resolution == 0.02


def test_configurations_agree_with_the_scene(scene, dut, ends):
    left, middle, right = ends
    assert dut.config_free(left) and dut.config_free(right)
    assert not dut.config_free(middle)
    qs = np.vstack([np.random.default_rng(0).uniform(dut.lower, dut.upper, (30, 7)), ends])
    free = dut.configs_free(qs)
    assert free.dtype == bool and free.shape == (len(qs),)
    np.testing.assert_array_equal(free, [scene.is_collision_free(q) for q in qs])
    assert free.any() and not free.all()


def test_edges_through_the_wall_collide_and_free_edges_do_not(scene, ends):
    left, middle, right = ends
    for resolution in (None, 0.05, 0.01):
        dut = mut.CheckerAdapter(scene, resolution)
        assert not dut.edge_free(left, right), resolution
        assert not dut.edge_free(right, left), resolution
        assert dut.edge_free(left, left - 0.3 * E[0]), resolution
        short = left + 0.02 * E[1]  # a single step
        assert dut.edge_free(left, short) == scene.is_collision_free(short)


def test_edges_agree_with_the_scene_and_with_every_sample(scene):
    q_a = random_free(scene, 12, seed=2)
    q_b = nearby(scene, q_a, 2.0, seed=2)
    default, sampled = mut.CheckerAdapter(scene), mut.CheckerAdapter(scene, 0.05)
    verdicts = []
    for a, b in zip(q_a, q_b, strict=True):
        verdicts.append(default.edge_free(a, b))
        assert verdicts[-1] == scene.is_edge_collision_free(a, b)
        assert sampled.edge_free(a, b) == samples_free(scene, a, b, 0.05)
    assert any(verdicts) and not all(verdicts)  # both kinds were tested


def test_free_prefix_stops_before_the_first_colliding_sample(scene, ends):
    left, middle, right = ends
    resolution = 0.02
    dut = mut.CheckerAdapter(scene, resolution)
    t = dut.free_prefix(left, right)
    assert 0.0 < t < 1.0
    n = int(np.ceil(np.linalg.norm(right - left) / resolution))
    k = round(t * n)
    assert t == pytest.approx(k / n)
    ts = np.arange(1, k + 1) / n
    assert all(scene.is_collision_free(left + s * (right - left)) for s in ts)
    assert not scene.is_collision_free(left + (k + 1) / n * (right - left))
    # A free segment is free all the way; one whose first sample collides not at all.
    assert dut.free_prefix(left, left - 0.3 * E[0]) == 1.0
    towards = left + (k + 1) / n * (right - left)  # the first colliding sample
    assert dut.free_prefix(left, towards) == pytest.approx(k / (k + 1))
    coarse = mut.CheckerAdapter(scene, 10.0)  # one sample per segment: its end
    assert coarse.free_prefix(left, middle) == 0.0
    assert coarse.free_prefix(left, right) == 1.0


def test_free_prefixes_are_the_free_prefix_of_each_row(scene, ends):
    left, _, right = ends
    dut = mut.CheckerAdapter(scene, 0.05)
    qs = random_free(scene, 10, seed=2)
    q_a = np.vstack([qs, left, left])
    q_b = np.vstack([nearby(scene, qs, 1.0, seed=2), right, left - 0.3 * E[0]])
    out = dut.free_prefixes(q_a, q_b)
    assert out.shape == (12,)
    np.testing.assert_array_equal(
        out, [dut.free_prefix(a, b) for a, b in zip(q_a, q_b, strict=True)]
    )
    assert out[-1] == 1.0 and out[-2] < 1.0
    assert np.all((out >= 0.0) & (out <= 1.0))


def test_edges_proven_free_at_the_resolution_are_remembered(scene, ends):
    left = ends[0]
    away = left - 0.3 * E[0]
    dut = mut.CheckerAdapter(scene, 0.05)
    assert not dut.is_proven(left, away)
    assert dut.edge_free(left, away)
    assert dut.is_proven(left, away)
    assert not dut.is_proven(away, left)  # an edge and its reverse have different keys
    # The memo answers: an obstacle added since is not seen by this adapter, but by a new one.
    X = RigidTransform(scene.attachment_pose(0.5 * (left + away)).translation())
    scene.add_box("late", [0.1, 0.1, 0.1], X)
    try:
        assert dut.edge_free(left, away)
        assert not mut.CheckerAdapter(scene, 0.05).edge_free(left, away)
    finally:
        scene.remove_object("late")
    # Without a resolution nothing is remembered.
    default = mut.CheckerAdapter(scene)
    assert default.edge_free(left, away) and not default.is_proven(left, away)
    default.mark_proven(ends[0], ends[2])
    assert default.is_proven(ends[0], ends[2])


def test_edge_key():
    a, b = np.arange(7.0), np.arange(7.0) + 1
    assert isinstance(mut.edge_key(a, b), bytes)
    assert mut.edge_key(a, b) == mut.edge_key(a.copy(), b.copy())
    assert mut.edge_key(a, b) != mut.edge_key(b, a)
    assert mut.edge_key(a, b) != mut.edge_key(a, b + 1e-12)


def test_first_invalid_segment_finds_the_first_colliding_segment(scene, ends):
    left, _, right = ends
    away = left - 0.3 * E[0]
    dut = mut.CheckerAdapter(scene, 0.01)
    free_path = np.vstack([away, left, left + 0.2 * E[1]])
    assert mut.first_invalid_segment(dut, free_path, 0.01) is None
    # The free segments are remembered; checking again finds nothing new.
    assert dut.is_proven(away, left) and dut.is_proven(left, left + 0.2 * E[1])
    assert mut.first_invalid_segment(dut, free_path, 0.01) is None
    path = np.vstack([away, left, right, right + 0.2 * E[0], left])  # segments 1 and 3 collide
    assert mut.first_invalid_segment(dut, path, 0.01) == 1
    assert not dut.is_proven(left, right) and dut.is_proven(right, right + 0.2 * E[0])
    assert mut.first_invalid_segment(dut, path[2:], 0.01) == 1
    assert mut.first_invalid_segment(dut, path[:2], 0.01) is None
    assert mut.first_invalid_segment(dut, path[:1], 0.01) is None  # no segment at all


def test_first_invalid_segment_reuses_proofs_at_the_same_resolution_only(scene, ends):
    left, _, right = ends
    path = np.vstack([left, right])
    dut = mut.CheckerAdapter(scene, 0.01)
    dut.mark_proven(left, right)  # a false proof, to see whether it is used
    assert mut.first_invalid_segment(dut, path, 0.01) is None
    assert mut.first_invalid_segment(dut, path, 0.02) == 0
    assert mut.first_invalid_segment(mut.CheckerAdapter(scene), path, 0.01) == 0
