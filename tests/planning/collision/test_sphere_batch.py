"""``sphere_batch.classify_batch`` gives every lane the verdict the scalar kernel gives its
configuration, in scenes with every object kind and a held object, for any number of lanes in
use, with non-finite joints, and in its early-stopping mode."""

import numpy as np
import pytest
from numba import njit
from pydrake.math import RigidTransform

from planning import PlanningScene
from planning.collision import sphere_batch as mut
from planning.collision.checker import CheckerAdapter
from planning.collision.sphere_checker import sphere_model
from planning.collision.sphere_kernel import COLLIDING, FREE, UNKNOWN
from tests.planning.collision.test_sphere_kernel import classify_each


@njit
def _batched(qs, d, count, mode, excused):
    """classify_batch over the rows, ``count`` at a time: (verdicts, blocked per batch)."""
    work = mut.batch_work(d, count)
    verdict = np.empty(count, dtype=np.int64)
    out = np.empty(len(qs), dtype=np.int64)
    blocked = np.zeros((len(qs) + count - 1) // count, dtype=np.bool_)
    for b, start in enumerate(range(0, len(qs), count)):
        n = min(count, len(qs) - start)
        blocked[b] = mut.classify_batch(qs[start:], n, d, work, mode, excused, verdict, np.zeros(0))
        out[start : start + n] = verdict[:n]
    return out, blocked


def _scenes():
    """A wall, a cylinder and a ball around the arm's workspace, and one with a held box."""
    scene = PlanningScene()
    scene.add_box("wall", [0.05, 0.8, 0.8], RigidTransform([0.45, 0.0, 0.4]))
    scene.add_cylinder("post", 0.05, 0.9, RigidTransform([0.0, 0.45, 0.45]))
    scene.add_sphere("ball", 0.12, RigidTransform([0.3, -0.35, 0.6]))
    yield "objects", scene
    ready = scene.model.named_configurations["ready"]
    scene.add_box("held", [0.04, 0.04, 0.12], scene.attachment_pose(ready))
    scene.attach("held", ready)
    yield "held", scene


def _samples(scene, seed):
    """Random configurations, and samples along random edges (neighbours, as a batch has)."""
    adapter = CheckerAdapter(scene)
    rng = np.random.default_rng(seed)
    qs = rng.uniform(adapter.lower, adapter.upper, (400, 7))
    ends = rng.uniform(adapter.lower, adapter.upper, (40, 2, 7))
    t = np.linspace(0.0, 1.0, 24)[:, None]
    edges = np.concatenate([a + t * (b - a) for a, b in ends])
    return np.ascontiguousarray(np.concatenate([qs, edges]))


@pytest.mark.parametrize("count", [1, 3, 8, mut.LANES])
def test_every_lane_gets_the_scalar_verdict(count):
    kinds = set()
    for _, scene in _scenes():
        d = sphere_model(scene).kernel_data()
        qs = _samples(scene, seed=count)
        expected = classify_each(qs, d)
        got, _ = _batched(qs, d, count, mut.FULL, np.zeros(count, dtype=np.bool_))
        np.testing.assert_array_equal(got, expected)
        kinds |= set(expected.tolist())
    assert kinds == {FREE, COLLIDING, UNKNOWN}


@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_a_non_finite_lane_is_unknown_and_blocks(bad):
    _, scene = next(_scenes())
    d = sphere_model(scene).kernel_data()
    ready = scene.model.named_configurations["ready"]
    qs = np.tile(ready, (8, 1))
    qs[3, 2] = bad
    got, _ = _batched(qs, d, 8, mut.FULL, np.zeros(8, dtype=np.bool_))
    assert got[3] == UNKNOWN and got[0] == FREE
    excused = np.ones(8, dtype=np.bool_)
    excused[3] = False
    _, blocked = _batched(qs, d, 8, mut.FIRST_BLOCK, excused)
    assert blocked[0]


def test_first_block_stops_exactly_when_a_lane_blocks():
    """FIRST_BLOCK says a batch blocks when one of its lanes is COLLIDING, or UNKNOWN without
    being excused; excused UNKNOWN lanes do not block it."""
    seen = set()
    for _, scene in _scenes():
        d = sphere_model(scene).kernel_data()
        qs = _samples(scene, seed=11)
        verdicts = classify_each(qs, d)
        for excuse in (False, True):
            excused = np.full(8, excuse)
            _, blocked = _batched(qs, d, 8, mut.FIRST_BLOCK, excused)
            for b in range(len(blocked)):
                v = verdicts[b * 8 : (b + 1) * 8]
                expect = bool(np.any(v == COLLIDING) or (not excuse and np.any(v == UNKNOWN)))
                assert blocked[b] == expect
                seen.add(expect)
    assert seen == {True, False}


@pytest.mark.parametrize("count", [0, 1, 31, 33, 200])
def test_classify_many_gives_each_configuration_the_scalar_verdict(count):
    for _, scene in _scenes():
        model = sphere_model(scene)
        d = model.kernel_data()
        qs = _samples(scene, seed=count)[:count].copy()
        if count > 1:
            qs[count // 2, 3] = np.nan  # a non-finite row among the others
        got = mut.classify_many(qs, d, np.zeros((0, 7)))
        assert got.dtype == np.int8 and got.shape == (count,)
        if count:
            np.testing.assert_array_equal(got, classify_each(qs, d))
            np.testing.assert_array_equal(model.classify(qs), got)  # what the model answers
        if count > 1:
            assert got[count // 2] == UNKNOWN
