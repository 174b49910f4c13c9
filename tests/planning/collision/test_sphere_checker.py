"""The sphere-first collision adapter (planning.collision.sphere_checker): sphere_model keeps one
model per scene and slack; SphereCheckerAdapter answers configurations, edges and free prefixes
exactly as Drake's checker does at the same samples, counts what the spheres and Drake decided,
leaves uncertain configurations to Drake only after ``fallback_after`` sphere verdicts, and
remembers edges proven free at its resolution."""

import numpy as np
import pytest
from pydrake.math import RigidTransform

import planning.collision.sphere_checker as mut
from drake_sim.base.resources import config_dir
from planning import PlanningScene
from planning.collision.checker import CheckerAdapter
from planning.collision.spheres import FREE, UNKNOWN

E = np.eye(7)


@pytest.fixture(scope="module")
def scene():
    return PlanningScene()


@pytest.fixture
def wall(scene):
    """A wall in front of the robot, for one test."""
    scene.add_box("wall", [0.05, 0.8, 0.8], RigidTransform([0.45, 0.0, 0.4]))
    yield scene
    scene.remove_object("wall")


def random_q(scene, n, seed=0):
    adapter = CheckerAdapter(scene)
    return np.random.default_rng(seed).uniform(adapter.lower, adapter.upper, (n, 7))


def drake_free(scene, qs):
    return np.array([scene.is_collision_free(q) for q in qs])


def test_one_model_per_scene_and_slack(scene, monkeypatch):
    model = mut.sphere_model(scene)
    assert mut.sphere_model(scene) is model
    assert mut.sphere_model(scene, 0.015) is model  # the default slack
    assert mut.SphereCheckerAdapter(scene).model is model
    # Another slack or another scene: another model (stand-ins here, covers take seconds).
    monkeypatch.setattr(mut, "SphereCollisionModel", lambda scene, slack: (scene, slack))
    looser = mut.sphere_model(scene, 0.03)
    assert looser == (scene, 0.03) and mut.sphere_model(scene, 0.03) is looser
    other = PlanningScene()
    assert mut.sphere_model(other) == (other, 0.015)
    assert mut.sphere_model(scene) is model


def test_configurations_agree_with_drake_and_are_counted(wall):
    scene = wall
    qs = random_q(scene, 200, seed=1)
    dut = mut.SphereCheckerAdapter(scene, hulls=False)  # the spheres, then Drake
    free = dut.configs_free(qs)
    assert free.dtype == bool
    np.testing.assert_array_equal(free, drake_free(scene, qs))
    assert free.any() and not free.all()
    assert dut.counts["spheres"] + dut.counts["drake"] == len(qs)
    unknown = int(np.sum(dut.model.classify(qs) == UNKNOWN))
    assert dut.counts["drake"] == unknown and dut.counts["spheres"] > 0.8 * len(qs)
    for q, f in zip(qs[:10], free[:10], strict=True):
        assert dut.config_free(q) == f


def test_a_tighter_cover_decides_part_of_what_the_first_cannot(wall):
    """With ``refine_slack`` the configurations the first cover leaves UNKNOWN go to a tighter
    one, and only those it cannot decide to Drake: the same answers, fewer Drake calls."""
    scene = wall
    qs = random_q(scene, 400, seed=2)
    first = mut.SphereCheckerAdapter(scene).model
    unknown = qs[first.classify(qs) == UNKNOWN]
    assert len(unknown) >= 5
    dut = mut.SphereCheckerAdapter(scene, refine_slack=0.005, hulls=False)
    free = dut.configs_free(unknown)
    np.testing.assert_array_equal(free, drake_free(scene, unknown))
    tighter = mut.sphere_model(scene, 0.005).classify(unknown)
    assert dut.counts["drake"] == np.sum(tighter == UNKNOWN) < len(unknown)
    assert dut.counts["spheres"] + dut.counts["drake"] == len(unknown)
    # Edges and prefixes decide their uncertain samples the same way.
    plain = mut.SphereCheckerAdapter(scene, resolution=0.05, hulls=False)
    refined = mut.SphereCheckerAdapter(scene, resolution=0.05, refine_slack=0.005, hulls=False)
    for q_a, q_b in zip(unknown[:-1], unknown[1:], strict=True):
        assert refined.edge_free(q_a, q_b) == plain.edge_free(q_a, q_b)
        assert refined.free_prefix(q_a, q_b) == plain.free_prefix(q_a, q_b)
    assert refined.counts["drake"] < plain.counts["drake"]


def test_the_exact_shapes_decide_most_of_what_the_first_cover_cannot(wall):
    """By default the configurations the first cover leaves UNKNOWN go to the robot's exact
    shapes (``SphereCollisionModel.prove_free``) and only those they cannot prove free to
    Drake: the same answers, fewer Drake calls; edges too."""
    scene = wall
    qs = random_q(scene, 400, seed=2)
    unknown = qs[mut.SphereCheckerAdapter(scene).model.classify(qs) == UNKNOWN]
    dut = mut.SphereCheckerAdapter(scene)
    free = dut.configs_free(unknown)
    np.testing.assert_array_equal(free, drake_free(scene, unknown))
    proven = dut.model.prove_free(unknown)
    assert not np.any(proven & ~free)
    assert dut.counts["drake"] == np.sum(~proven) < len(unknown) / 2
    assert dut.counts["spheres"] + dut.counts["drake"] == len(unknown)
    plain = mut.SphereCheckerAdapter(scene, resolution=0.05, hulls=False)
    exact = mut.SphereCheckerAdapter(scene, resolution=0.05)
    for q_a, q_b in zip(unknown[:-1], unknown[1:], strict=True):
        assert exact.edge_free(q_a, q_b) == plain.edge_free(q_a, q_b)
        assert exact.free_prefix(q_a, q_b) == plain.free_prefix(q_a, q_b)
    assert exact.counts["drake"] < plain.counts["drake"]


def test_edges_and_prefixes_match_drake_samples(wall):
    scene = wall
    adapter = mut.SphereCheckerAdapter(scene, 0.05)
    drake = CheckerAdapter(scene, 0.05)
    qs = random_q(scene, 40, seed=5)
    qa, qb = qs[:20], qs[20:]
    free_a = drake_free(scene, qa)
    qa, qb = qa[free_a], qb[free_a]
    prefixes = adapter.free_prefixes(qa, qb)
    np.testing.assert_allclose(prefixes, drake.free_prefixes(qa, qb))
    assert np.any(prefixes == 1.0) and np.any(prefixes < 1.0)
    for a, b, t in zip(qa, qb, prefixes, strict=True):
        assert adapter.edge_free(a, b) == drake.edge_free(a, b) == (t == 1.0)
        assert adapter.free_prefix(a, b) == t


def test_edge_free_checks_its_start_too(wall):
    scene = wall
    dut = mut.SphereCheckerAdapter(scene, 0.05)
    ready = scene.model.named_configurations["ready"]
    colliding = np.array([0.0, 1.7, 0.0, -0.5, 0.0, 0.5, 0.0])  # through the table
    assert not dut.config_free(colliding)
    assert not dut.edge_free(colliding, ready)
    assert dut.free_prefix(ready, colliding) < 1.0


def test_edges_proven_free_at_the_resolution_are_remembered(scene):
    ready = scene.model.named_configurations["ready"]
    away = ready + 0.5 * E[0]
    dut = mut.SphereCheckerAdapter(scene, 0.05)
    assert dut.edge_free(ready, away) and dut.is_proven(ready, away)
    before = dict(dut.counts)
    assert dut.edge_free(ready, away)
    assert dut.counts == before  # answered from the memo: nothing classified
    default = mut.SphereCheckerAdapter(scene)
    assert default.edge_free(ready, away) and not default.is_proven(ready, away)


def test_drake_decides_uncertain_configurations_after_the_fallback_count():
    """Before ``fallback_after`` sphere classifications an UNKNOWN configuration counts as
    colliding and Drake is not asked; from then on Drake decides it."""
    scene = PlanningScene()
    scene.load_yaml(config_dir() / "pickplace.yaml")
    qs = random_q(scene, 400, seed=7)
    state = mut.sphere_model(scene).classify(qs)
    unknown = qs[state == UNKNOWN]
    assert len(unknown) > 0
    free = drake_free(scene, unknown)
    assert free.any()  # some are free for Drake: the spheres were only unsure
    late = mut.SphereCheckerAdapter(scene, fallback_after=10**9)
    assert not late.configs_free(unknown).any() and late.counts["drake"] == 0
    early = mut.SphereCheckerAdapter(scene, fallback_after=0, hulls=False)
    np.testing.assert_array_equal(early.configs_free(unknown), free)
    assert early.counts["drake"] == len(unknown)
    # The switch happens when the count of configurations the spheres decided is reached.
    switch = mut.SphereCheckerAdapter(
        scene, fallback_after=int((state != UNKNOWN).sum()), hulls=False
    )
    assert not switch.configs_free(unknown).any()
    switch.configs_free(qs)  # the spheres decide that many here
    np.testing.assert_array_equal(switch.configs_free(unknown), free)
    # Segments too: before the fallback an uncertain sample blocks, after it Drake decides.
    starts = np.tile(qs[state == FREE][0], (len(unknown), 1))
    waiting = mut.SphereCheckerAdapter(scene, fallback_after=10**9)
    deciding = mut.SphereCheckerAdapter(scene, fallback_after=0, hulls=False)
    before, after = (a.free_prefixes(starts, unknown) for a in (waiting, deciding))
    assert np.all(before <= after) and np.any(before < after)
    assert waiting.counts["drake"] == 0 and deciding.counts["drake"] > 0
