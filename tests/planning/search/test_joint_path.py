"""The planner's joint path pipeline (planning.search.joint_path): the straight line when free,
RRT-Connect around an obstacle, every returned path valid at the fine resolution, a colliding
segment repaired, the adapters the options ask for, and a timeout reported as TIMED_OUT."""

import time

import numpy as np
import pytest
from pydrake.math import RigidTransform

import planning.search.joint_path as mut
from planning import ErrorCode, MotionPlannerOptions, PlanningError, PlanningScene
from planning.collision.checker import CheckerAdapter, first_invalid_segment
from planning.collision.sphere_checker import SphereCheckerAdapter

E = np.eye(7)
FINE = 0.01  # rad


@pytest.fixture(scope="module")
def dut(scene):
    return mut.JointPathSearch(scene, MotionPlannerOptions())


def deadline(seconds=30.0):
    return time.perf_counter() + seconds


def test_a_free_straight_line_is_the_path(scene, dut, ends):
    start = ends[0]
    goal = start - 0.2 * E[0]
    path, how = dut.find(start, goal, deadline())
    assert how == "straight"
    np.testing.assert_array_equal(path, [start, goal])


def test_around_the_wall_the_path_is_valid_at_the_fine_resolution(scene, dut, ends):
    assert not scene.is_edge_collision_free(*ends)
    path, how = dut.find(*ends, deadline())
    assert how.startswith("rrt_connect")
    np.testing.assert_array_equal(path[[0, -1]], ends)
    assert first_invalid_segment(CheckerAdapter(scene), path, FINE) is None


def test_a_colliding_segment_is_repaired(scene, dut, ends):
    straight = np.vstack(ends)  # through the wall
    rng = np.random.default_rng(0)
    path, how = dut._validated(dut.adapter(FINE), straight, "test", deadline(), rng)
    assert "+repaired" in how or "+replanned" in how
    assert first_invalid_segment(CheckerAdapter(scene), path, FINE) is None


def test_adapters_follow_the_options(scene):
    options = MotionPlannerOptions()
    search = mut.JointPathSearch(scene, options).adapter(search=True)
    assert isinstance(search, SphereCheckerAdapter)
    assert search.resolution == options.spheres.search_resolution
    options.spheres.enabled = False
    plain = mut.JointPathSearch(scene, options).adapter(FINE)
    assert type(plain) is CheckerAdapter and plain.resolution == FINE


def test_no_time_left_is_timed_out(dut, ends):
    with pytest.raises(PlanningError) as info:
        dut.find(*ends, time.perf_counter() - 1.0)
    assert info.value.code is ErrorCode.TIMED_OUT


# ---------------------------------------------------------------------------------------------
# The compiled search runs first with sphere models; the Python pipeline takes over when it
# gives up, and a compiled path that fails the fine check is repaired.
# ---------------------------------------------------------------------------------------------


def test_the_compiled_search_runs_first_and_one_seed_gives_one_path(scene, dut, ends, monkeypatch):
    calls = []
    monkeypatch.setattr(mut, "rrt_connect", lambda *a, **k: calls.append(1))
    first, how = dut.find(*ends, deadline())
    again, _ = dut.find(*ends, deadline())
    assert how == "rrt_connect" and not calls  # the Python RRT-Connect never ran
    np.testing.assert_array_equal(first, again)
    assert first_invalid_segment(CheckerAdapter(scene), first, FINE) is None


def test_when_the_compiled_search_gives_up_the_python_pipeline_asks_drake(scene, ends):
    options = MotionPlannerOptions()
    options.spheres.drake_fallback_after = 3  # the compiled search gives up at once
    dut = mut.JointPathSearch(scene, options)
    path, how = dut.find(*ends, deadline())
    assert how.startswith("rrt_connect")
    assert first_invalid_segment(CheckerAdapter(scene), path, FINE) is None


def test_a_compiled_path_failing_the_fine_check_is_repaired_in_compiled_code(
    scene, dut, ends, monkeypatch
):
    """The search's path is replaced by the straight line through the box: the fine check
    (made in the same compiled call) finds the collision and a compiled re-plan of that segment
    mends it."""
    solve = mut.compiled_rrt.solve

    def through_the_box(q_a, q_b, *args):
        result = solve(q_a, q_b, *args)
        straight = np.vstack([q_a, q_b])
        data = mut.compiled_rrt.unpack(args[2], args[3])  # packed: floats, ints, then the hulls'
        checked = mut.compiled_rrt.fine_check(straight, args[-2], data, args[4], args[5], args[-1])[
            :3
        ]
        return (mut.compiled_rrt.FOUND, straight, 1, *result[3:5], *checked)

    plan, edge_steps, budgets = mut.compiled_rrt.plan, [], []

    def recorded(q_a, q_b, lower, upper, data, settings, *hulls):
        edge_steps.append(settings[0])  # edge_step
        budgets.append(settings[3])  # max_checks
        return plan(q_a, q_b, lower, upper, data, settings, *hulls)

    monkeypatch.setattr(mut.compiled_rrt, "solve", through_the_box)
    monkeypatch.setattr(mut.compiled_rrt, "plan", recorded)
    monkeypatch.setattr(mut, "rrt_connect", lambda *a, **k: pytest.fail("Python RRT ran"))
    path, how = dut.find(*ends, deadline())
    assert how == "rrt_connect+repaired" and len(path) > 2
    # The repair searched on edges at repair_resolution; the fine check had the last word.
    assert edge_steps and set(edge_steps) == {MotionPlannerOptions().validation.repair_resolution}
    assert max(budgets) <= mut._REPAIR_CHECKS < MotionPlannerOptions().spheres.drake_fallback_after
    assert first_invalid_segment(CheckerAdapter(scene), path, FINE) is None


def test_after_a_repair_only_the_new_piece_and_what_follows_are_checked_again(
    scene, ends, monkeypatch
):
    """The segments before a repaired one passed the fine check, Drake deciding what the
    spheres could not: the next round checks from the repaired segment's start on, so those
    samples are not sent to Drake twice."""
    dut = mut.JointPathSearch(scene, MotionPlannerOptions())
    start, goal = ends
    middle = [start + 0.1 * E[1], start + 0.2 * E[1]]
    searched = np.vstack([start, *middle, goal])
    piece = np.vstack([middle[0], middle[0] + 0.05 * E[2], middle[1]])
    seen = []

    def failing(path, resolution, data, hulls, checked=None):
        seen.append(path.copy())
        return 1 if len(seen) == 1 else -1  # the segment middle[0] -> middle[1], once

    def found(q_a, q_b, *args):  # the solve's 8 outputs, its fine check left to ``failing``
        return (mut.compiled_rrt.FOUND, searched, 1, 0, 0, -1, np.empty((0, 7)), np.empty(0))

    monkeypatch.setattr(mut.compiled_rrt, "solve", found)
    monkeypatch.setattr(mut.compiled_rrt, "plan", lambda *a: (mut.compiled_rrt.FOUND, piece, 1, 0))
    monkeypatch.setattr(dut, "_first_failing_segment", failing)
    path, how = dut.find(start, goal, deadline())
    assert how == "rrt_connect+repaired"
    np.testing.assert_array_equal(path, np.vstack([start, piece, goal]))
    np.testing.assert_array_equal(seen[0], searched)
    np.testing.assert_array_equal(seen[1], np.vstack([piece, goal]))  # from the repair on


@pytest.mark.parametrize("fused", [True, False], ids=["one-call", "separate-calls"])
def test_the_ends_are_checked_in_the_search_and_drake_decides_the_unproven(
    scene, ends, fused, monkeypatch
):
    """With ``check_ends``, the ends the spheres prove free are not asked about again; one
    they cannot prove free (here: "ready", inside the box) goes to ``check_ends``, which
    raises for a collision before any search."""
    monkeypatch.setattr(mut.JointPathSearch, "fused", fused)
    dut = mut.JointPathSearch(scene, MotionPlannerOptions())
    asked = []
    path, _ = dut.find(*ends, deadline(), lambda *flags: asked.append(flags))
    assert (
        asked in ([], [(False, False)])
        and first_invalid_segment(CheckerAdapter(scene), path, FINE) is None
    )
    ready = scene.model.named_configurations["ready"]  # inside the box

    def collides(start, goal):
        asked.append((start, goal))
        raise PlanningError(ErrorCode.GOAL_IN_COLLISION, "the goal collides")

    with pytest.raises(PlanningError, match="goal collides"):
        dut.find(ends[0], ready, deadline(), collides)
    assert asked[-1] == (False, True)


def test_one_call_and_separate_calls_give_the_same_path(scene, ends, monkeypatch):
    one, how = mut.JointPathSearch(scene, MotionPlannerOptions()).find(*ends, deadline())
    monkeypatch.setattr(mut.JointPathSearch, "fused", False)
    separate, again = mut.JointPathSearch(scene, MotionPlannerOptions()).find(*ends, deadline())
    np.testing.assert_array_equal(one, separate)
    assert how == again


def test_the_spheres_prove_free_what_drake_finds_free(scene, dut, ends):
    ready = scene.model.named_configurations["ready"]
    assert dut.proves_free(ends[0]) and scene.is_collision_free(ends[0])
    assert not dut.proves_free(ready)  # inside the box
    options = MotionPlannerOptions()
    options.spheres.enabled = False
    assert not mut.JointPathSearch(scene, options).proves_free(ends[0])  # no model: no proof


def test_a_short_timeout_bounds_the_compiled_search(scene, ends, monkeypatch):
    """The compiled search cannot read the clock: the time left becomes its check budget (at
    2 us a check), so a request with 5 ms left may check about 2 500 configurations, not the
    1 000 000 of drake_fallback_after; with the default timeout that bound is the one that binds."""
    budgets = []
    real = mut.compiled_rrt.solve

    def recorded(*args):
        budgets.append(args[8][3])  # the settings' max_checks (after the packed arrays)
        return real(*args)

    monkeypatch.setattr(mut.compiled_rrt, "solve", recorded)
    dut = mut.JointPathSearch(scene, MotionPlannerOptions())
    try:
        dut.find(*ends, time.perf_counter() + 0.005)
    except PlanningError as e:
        assert e.code is ErrorCode.TIMED_OUT
    assert 0 < budgets[0] <= 2_500
    dut.find(*ends, deadline())
    assert budgets[-1] == MotionPlannerOptions().spheres.drake_fallback_after


def test_the_tighter_cover_is_remade_in_prepare_not_in_a_request():
    """After a held object changes, requests leave the tighter cover out (Drake decides what
    the first cannot) rather than spend ~45 ms remaking it; ``prepare`` remakes it."""
    scene = PlanningScene()
    dut = mut.JointPathSearch(scene, MotionPlannerOptions())
    assert dut._refine_model() is not None
    assert dut.adapter(FINE)._refine is not None
    table = scene.world_objects["table"]
    scene.attach_new(type(table)("cup", "box", (0.04, 0.04, 0.08), RigidTransform([0, 0, 0.1])))
    assert dut._refine_model() is None and dut.adapter(FINE)._refine is None
    dut.prepare()
    assert dut._refine_model() is not None and dut.adapter(FINE)._refine is not None


def test_warm_up_readies_every_compiled_call_a_request_may_make(scene, monkeypatch):
    """``warm_up`` (made once, by ``MotionPlanner``) compiles or loads the search's calls and
    the Python side's exact proofs, so that a request's first use of them costs no load (~18
    ms for the proofs); without ``spheres.hull_proofs`` it leaves those out."""
    from planning.collision.spheres import SphereCollisionModel

    calls = {"warm_up": 0, "prove_free": 0}
    monkeypatch.setattr(
        mut.compiled_rrt, "warm_up", lambda *a: calls.__setitem__("warm_up", calls["warm_up"] + 1)
    )
    real = SphereCollisionModel.prove_free

    def recorded(self, qs):
        calls["prove_free"] += 1
        return real(self, qs)

    monkeypatch.setattr(SphereCollisionModel, "prove_free", recorded)
    mut.JointPathSearch(scene, MotionPlannerOptions()).warm_up()
    assert calls == {"warm_up": 1, "prove_free": 1}
    options = MotionPlannerOptions()
    options.spheres.hull_proofs = False
    mut.JointPathSearch(scene, options).warm_up()
    assert calls == {"warm_up": 2, "prove_free": 1}


def test_a_path_touching_between_its_samples_is_not_returned():
    """The straight line passes every sample, cell centres included, but touches a blade
    between them (``tests/graze_helpers.py``): with ``validation.swept`` (the default) the
    planner goes around it and the independent audit finds nothing on its path; without, it
    returns the straight line, which the audit finds touching. A planner whose cells lost their
    margins would return that line too, and fail here."""
    from drake_sim.tools.path_audit import audit_path
    from tests.graze_helpers import JOINT_NAMES, grazing_segment

    scene = PlanningScene()
    q_a, q_b, target = grazing_segment(scene)
    options = MotionPlannerOptions()
    path, how = mut.JointPathSearch(scene, options).find(q_a, q_b, deadline())
    assert how != "straight"
    np.testing.assert_array_equal(path[[0, -1]], [q_a, q_b])
    assert audit_path(target, path, JOINT_NAMES, offsets=8)[0] == np.inf
    options.validation.swept = False
    path, how = mut.JointPathSearch(scene, options).find(q_a, q_b, deadline())
    assert how == "straight"
    assert audit_path(target, path, JOINT_NAMES, offsets=8)[0] < 0.0


def test_a_path_that_cannot_be_repaired_makes_way_for_a_search_with_the_next_seed(
    scene, ends, monkeypatch
):
    """When the compiled search's path fails the fine check and the repairs fail too with time
    left, a fresh compiled search with the next seed runs rather than the request failing; the
    seeds are consecutive, so the answer is still the same on any machine."""
    dut = mut.JointPathSearch(scene, MotionPlannerOptions())
    start, goal = ends
    grazing = np.vstack([start, (start + goal) / 2 + 0.3, goal])
    good = np.vstack([start, goal])
    attempts = []

    def compiled(model, q_start, q_goal, deadline, check_ends=None, attempt=0):
        attempts.append(attempt)
        return (None, "rrt_connect", grazing) if attempt < 2 else (good, "rrt_connect", None)

    def validated(fine, path, how, deadline, rng):
        raise PlanningError(ErrorCode.PLANNING_FAILED, "no path passed the fine collision check")

    monkeypatch.setattr(dut, "_compiled", compiled)
    monkeypatch.setattr(dut, "_validated", validated)
    path, how = dut.find(start, goal, deadline())
    assert attempts == [0, 1, 2] and how == "rrt_connect+seed2"
    np.testing.assert_array_equal(path, good)
    # With no time left after the repairs, the failure stands: no other search.
    attempts.clear()
    real, late = time.perf_counter, []

    def out_of_time(fine, path, how, deadline, rng):
        late.append(True)
        raise PlanningError(ErrorCode.PLANNING_FAILED, "no path passed the fine collision check")

    monkeypatch.setattr(dut, "_validated", out_of_time)
    monkeypatch.setattr(mut.time, "perf_counter", lambda: real() + (1e6 if late else 0.0))
    with pytest.raises(PlanningError) as info:
        dut.find(start, goal, deadline())
    assert attempts == [0] and info.value.code is ErrorCode.PLANNING_FAILED
