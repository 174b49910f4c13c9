"""BatchedCollisionChecker: shapes wait in a queue until the checker is next used, then land in
every context with the collision filters Drake's own ``AddCollisionShapeToBody`` gives them."""

import numpy as np
import pytest
from pydrake.geometry import Box, Sphere
from pydrake.math import RigidTransform
from pydrake.planning import SceneGraphCollisionChecker

from planning import PlanningScene
from planning.collision.batched_checker import BatchedCollisionChecker


@pytest.fixture(scope="module")
def scene():
    return PlanningScene()


def geometry_count(context) -> int:
    return context.GetQueryObject().inspector().num_geometries()


def geometry_ids(context) -> set:
    return set(context.GetQueryObject().inspector().GetAllGeometryIds())


def partners(checker, context, geometry_id, exclude) -> set[tuple[str, str]]:
    """The (body, geometry) pairs SceneGraph would test ``geometry_id`` against; added
    geometries are named "added" (their names differ between the two ways of adding)."""
    inspector = context.GetQueryObject().inspector()
    plant = checker.plant()
    found = set()
    for a, b in inspector.GetCollisionCandidates():
        if geometry_id not in (a, b):
            continue
        other = b if a == geometry_id else a
        if other in exclude:
            continue
        body = plant.GetBodyFromFrameId(inspector.GetFrameId(other)).name()
        name = inspector.GetName(other)
        found.add((body, "added" if "(" in name else name))
    return found


def test_the_scene_uses_the_batched_checker(scene):
    assert isinstance(scene.checker, BatchedCollisionChecker)
    assert isinstance(scene.checker, SceneGraphCollisionChecker)


def test_queued_shapes_reach_every_context_at_the_next_use(scene):
    checker = scene.checker
    checker.flush()
    early = checker.MakeStandaloneModelContext()
    count = geometry_count(early)
    world = scene.plant.world_body().index()
    first = checker.queue_shape(world, Box(0.1, 0.1, 0.1), RigidTransform([2, 0, 0]), "a")
    second = checker.queue_shape(world, Sphere(0.1), RigidTransform([2, 1, 0]), "b")
    assert checker.pending == 2
    assert geometry_count(early) == count  # nothing registered yet
    checker.queue_removal(second)  # still queued: simply dropped
    assert checker.pending == 1
    checker.CheckConfigCollisionFree(scene.full_q(np.zeros(7)))  # any use flushes
    assert checker.pending == 0
    assert geometry_count(early) == count + 1
    late = checker.MakeStandaloneModelContext()  # cloned from the prototype: has it too
    assert geometry_count(late) == count + 1
    inspector = late.GetQueryObject().inspector()
    assert inspector.GetName(first).startswith("a (")
    checker.queue_removal(first)
    assert checker.pending == 1 and geometry_count(early) == count + 1
    checker.flush()
    assert geometry_count(early) == count and geometry_count(late) == count


def test_filters_match_drakes_own_add(scene):
    """For a world shape and a held shape, and again after a filter change, a queued shape is
    tested against exactly the geometries a shape added by Drake's AddCollisionShapeToBody is."""
    checker = scene.checker
    checker.flush()
    context = checker.MakeStandaloneModelContext()
    plant = scene.plant
    world = plant.world_body()
    hand = plant.GetBodyByName("panda_attachment")
    link5 = plant.GetBodyByName("panda_link5")
    X = RigidTransform([0.0, 0.0, 0.1])
    try:
        for round_ in range(2):
            for body in (world, hand):
                group = f"reference {round_} {body.name()}"
                before = geometry_ids(context)
                assert SceneGraphCollisionChecker.AddCollisionShapeToBody(
                    checker, group, body, Box(0.02, 0.02, 0.02), X
                )
                (reference,) = geometry_ids(context) - before
                ours = checker.queue_shape(body.index(), Box(0.02, 0.02, 0.02), X, "ours")
                checker.flush()
                pair = {reference, ours}
                expected = partners(checker, context, reference, pair)
                assert expected, body.name()
                assert partners(checker, context, ours, pair) == expected, body.name()
                if body == hand:  # held shapes never meet each other; link 5 after round 0
                    inspector = context.GetQueryObject().inspector()
                    assert inspector.CollisionFiltered(reference, ours)
                    assert any(b == "panda_link5" for b, _ in expected) == (round_ == 0)
                    assert ("panda_hand", "added") not in expected
                    assert any(b == "panda_link1" for b, _ in expected)
                else:
                    assert not any(b == "panda_link0" for b, _ in expected)  # welded base
                    assert ("world", "added") not in expected  # anchored pairs: never
                checker.queue_removal(ours)
            # A filter change (the held shapes may now touch link 5) for the next round.
            checker.SetCollisionFilteredBetween(hand.index(), link5.index(), True)
    finally:
        checker.SetCollisionFilteredBetween(hand.index(), link5.index(), False)
        for shapes in list(checker.GetAllAddedCollisionShapes()):
            checker.RemoveAllAddedCollisionShapes(shapes)
        checker.flush()


def test_own_names_do_not_flush(scene):
    checker = scene.checker
    geometry_id = checker.queue_shape(
        scene.plant.world_body().index(), Sphere(0.01), RigidTransform([3, 0, 0]), "quiet"
    )
    assert checker.pending == 1  # reading ``pending`` did not flush
    checker.queue_removal(geometry_id)
    assert checker.pending == 0
