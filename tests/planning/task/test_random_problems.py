"""random_problems: deterministic per seed (problem k the same whatever the count), starts and
goals collision-free, in limits, apart and not joined by a free straight line, obstacles within
reach and clear of the base, and a problem that cannot be made named instead of a hang."""

import dataclasses as dc

import numpy as np
import pytest

import planning.task.random_problems as mut
from planning import PlanningScene


@pytest.fixture(scope="module")
def scene():
    return PlanningScene()


@pytest.fixture(scope="module")
def problems(scene):
    return list(mut.random_problems(scene, 8, seed=3))


def same(a: mut.RandomProblem, b: mut.RandomProblem) -> bool:
    return (
        a.number == b.number
        and a.joint_names == b.joint_names
        and np.array_equal(a.q_start, b.q_start)
        and np.array_equal(a.q_goal, b.q_goal)
        and [(o.name, o.shape, o.size) for o in a.objects]
        == [(o.name, o.shape, o.size) for o in b.objects]
        and all(o.X_PO.IsExactlyEqualTo(p.X_PO) for o, p in zip(a.objects, b.objects, strict=True))
    )


def test_deterministic_per_seed(scene, problems):
    again = list(mut.random_problems(scene, 8, seed=3))
    assert all(same(a, b) for a, b in zip(problems, again, strict=True))
    # The first problems of a seed do not depend on how many are asked for.
    first_two = list(mut.random_problems(scene, 2, 3))
    assert all(same(a, b) for a, b in zip(problems[:2], first_two, strict=True))
    other = next(mut.random_problems(scene, 1, seed=4))
    assert not np.array_equal(other.q_start, problems[0].q_start)


def test_starts_and_goals_are_valid_and_differ(scene, problems):
    assert [p.number for p in problems] == list(range(1, 9))
    options = mut.RandomProblemOptions()
    for problem in problems:
        assert isinstance(problem, mut.RandomProblem), problem
        assert problem.joint_names == tuple(f"panda_joint{i}" for i in range(1, 8))
        assert set(problem.other_joints) == {"panda_finger_joint1", "panda_finger_joint2"}
        scene.replace(world=problem.objects)
        for q in (problem.q_start, problem.q_goal):
            assert scene.in_joint_limits(q) and scene.is_collision_free(q)
        assert np.linalg.norm(problem.q_goal - problem.q_start) >= options.min_separation
        assert not scene.is_edge_collision_free(problem.q_start, problem.q_goal)


def test_obstacles_within_reach_and_clear_of_the_base(problems):
    ws = mut.PANDA_WORKSPACE
    shapes = set()
    for problem in problems:
        assert 3 <= len(problem.objects) <= 8
        for obj in problem.objects:
            shapes.add(obj.shape)
            p = obj.X_PO.translation()
            assert np.linalg.norm(p - np.asarray(ws.shoulder)) <= ws.reach
            assert np.hypot(p[0], p[1]) - mut.bounding_radius(obj.shape, obj.size) >= (
                ws.base_radius
            )
            assert p[2] >= ws.floor
    assert shapes == {"box", "cylinder"}


def test_bounding_radius_holds_the_shape():
    assert mut.bounding_radius("box", (2.0, 2.0, 1.0)) == pytest.approx(1.5)
    assert mut.bounding_radius("cylinder", (0.3, 0.8)) == pytest.approx(0.5)
    assert mut.bounding_radius("sphere", (0.2,)) == pytest.approx(0.2)


def test_a_problem_that_cannot_be_made_is_named(scene):
    # Goals 100 rad from any start cannot be had within the Panda's limits.
    options = dc.replace(
        mut.RandomProblemOptions(), min_separation=100.0, configuration_draws=3, scene_draws=2
    )
    result = list(mut.random_problems(scene, 2, 0, options=options))
    assert all(isinstance(r, mut.ProblemGenerationError) for r in result)
    assert [r.number for r in result] == [1, 2]
    assert "random problem 2" in str(result[1]) and "2 scenes of 3 draws" in str(result[1])


def test_count_must_be_positive(scene):
    with pytest.raises(ValueError, match=">= 1"):
        list(mut.random_problems(scene, 0, 0))
