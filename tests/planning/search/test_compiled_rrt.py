"""The compiled search (planning.search.compiled_rrt): the straight line when free, RRT-Connect
and shortcutting around an obstacle with every segment free for Drake's checker at 0.01 rad, one
seed one path, a check budget that ends the search, the fine check's verdicts, and the
generator's numbers."""

import numpy as np
import pytest
from numba import njit

import planning.search.compiled_rrt as mut
from planning.collision.checker import CheckerAdapter, first_invalid_segment
from planning.collision.sphere_checker import sphere_model
from planning.collision.sphere_kernel import COLLIDING, UNKNOWN
from planning.paths import path_length
from tests.planning.collision.test_sphere_kernel import classify_each, classify_stopping

E = np.eye(7)
FINE = 0.01  # rad


@pytest.fixture(scope="module")
def data(scene):
    return sphere_model(scene).kernel_data()


@pytest.fixture(scope="module")
def limits(scene):
    adapter = CheckerAdapter(scene)
    return adapter.lower, adapter.upper


def search(
    data,
    limits,
    q_a,
    q_b,
    seed=0,
    max_checks=50_000,
    iterations=20,
    anchor_radius=0.0,
    balance=True,
    domain=np.inf,
    domain_min=1.0,
):
    settings = (0.1, 1.0, 0.05, max_checks, iterations, mut.seed_state(seed), anchor_radius)
    settings = (*settings, balance, domain, domain_min, True)
    return mut.plan(q_a, q_b, *limits, data, settings, *mut.NO_HULLS)


def test_a_free_straight_line_is_the_path(data, limits, ends):
    q_a = ends[0]
    status, path, how, checks = search(data, limits, q_a, q_a - 0.2 * E[0])
    assert status == mut.FOUND and how == 0 and checks >= 1
    np.testing.assert_array_equal(path, [q_a, q_a - 0.2 * E[0]])


@pytest.mark.parametrize(
    "balance, domain",
    [(True, np.inf), (False, np.inf), (True, 1.0)],
    ids=["balanced", "in-turn", "dynamic-domain"],
)
def test_around_an_obstacle_every_segment_is_free_for_drake(
    scene, data, limits, ends, balance, domain
):
    q_a, q_b = ends
    assert not CheckerAdapter(scene).edge_free(q_a, q_b)  # the box is in the way
    status, path, how, _ = search(data, limits, q_a, q_b, balance=balance, domain=domain)
    assert status == mut.FOUND and how == 1
    np.testing.assert_array_equal(path[0], q_a)
    np.testing.assert_array_equal(path[-1], q_b)
    bad, unknown, _, checks = mut.fine_check(path, FINE, data, *mut.NO_HULLS, False)
    assert bad == -1 and checks > 0
    assert all(scene.is_collision_free(q) for q in unknown)
    assert first_invalid_segment(CheckerAdapter(scene), path, FINE) is None
    # Shortcutting left no waypoint it could skip: the path is far shorter than a tree walk.
    assert path_length(path) < 3.0 * np.linalg.norm(q_b - q_a)


def test_one_seed_gives_one_path(data, limits, ends):
    first = search(data, limits, *ends, seed=3)[1]
    np.testing.assert_array_equal(search(data, limits, *ends, seed=3)[1], first)
    assert not np.array_equal(search(data, limits, *ends, seed=4)[1], first)


def test_balancing_changes_the_search(data, limits, ends):
    balanced = search(data, limits, *ends, seed=3)
    in_turn = search(data, limits, *ends, seed=3, balance=False)
    assert balanced[0] == in_turn[0] == mut.FOUND
    assert balanced[3] != in_turn[3] or not np.array_equal(balanced[1], in_turn[1])


def test_the_check_budget_ends_the_search(data, limits, ends):
    status, path, _, checks = search(data, limits, *ends, max_checks=5)
    assert status == mut.GAVE_UP and len(path) == 0
    assert 5 <= checks < 100  # the round that crossed the budget finishes


def test_rejected_targets_count_against_the_budget(data, limits, ends):
    # A domain of 1 mrad rejects almost every target once an extension has failed: the search
    # still ends, by the budget, having classified fewer configurations than it allows.
    status, path, _, checks = search(
        data, limits, *ends, max_checks=300, domain=1e-3, domain_min=1e-3
    )
    assert status == mut.GAVE_UP and len(path) == 0
    assert checks < 300


def test_the_fine_check_names_the_colliding_segment(scene, data, ends):
    q_a, q_b = ends
    ready = scene.model.named_configurations["ready"]
    path = np.array([q_a, q_a + 0.1 * E[1], q_b])  # the second segment crosses the box
    assert not scene.is_collision_free(ready)
    bad, _, _, _ = mut.fine_check(path, FINE, data, *mut.NO_HULLS, False)
    assert bad == 1


def test_the_fine_check_agrees_with_classifying_every_sample(scene, data, ends):
    """The batched fine check finds what the scalar kernel finds sample by sample: the first
    segment with a COLLIDING sample, and the UNKNOWN samples before it, in order."""
    q_a, q_b = ends
    rng = np.random.default_rng(3)
    collided = clear = undecided_met = False
    for _ in range(20):
        path = np.vstack([q_a, q_a + rng.normal(0.0, 0.4, (3, 7)), q_b])
        samples, owners = [], []
        for s, (a, b) in enumerate(zip(path[:-1], path[1:], strict=True)):
            n = max(1, int(np.ceil(np.linalg.norm(b - a) / FINE)))
            samples += [a + (i / n) * (b - a) for i in range(1, n + 1)]
            owners += [s] * n
        state = classify_each(np.array(samples), data)
        colliding = np.flatnonzero(state == COLLIDING)
        stop = colliding[0] if len(colliding) else len(samples)
        expected_bad = owners[stop] if len(colliding) else -1
        undecided = [k for k in range(stop) if state[k] == UNKNOWN]
        bad, unknown, segment, checks = mut.fine_check(path, FINE, data, *mut.NO_HULLS, False)
        assert bad == expected_bad
        np.testing.assert_array_equal(unknown, np.array(samples)[undecided].reshape(-1, 7))
        np.testing.assert_array_equal(segment, np.array(owners, dtype=int)[undecided])
        assert checks >= stop
        collided |= bad >= 0
        clear |= bad < 0
        undecided_met |= len(undecided) > 0
    assert collided and clear and undecided_met  # every outcome was met


def test_the_generator_is_the_same_everywhere():
    state = mut.seed_state(0)
    assert state.dtype == np.uint64 and state[0] != 0
    draws = [mut._uniform(state) for _ in range(1000)]
    assert all(0.0 <= x < 1.0 for x in draws)
    assert abs(np.mean(draws) - 0.5) < 0.05
    # Fixed numbers: xorshift64* seeded by SplitMix64 is plain integer arithmetic.
    again = mut.seed_state(0)
    assert [mut._uniform(again) for _ in range(3)] == draws[:3]
    assert mut.seed_state(1)[0] != mut.seed_state(0)[0]


@njit
def _edge_free(q_a, q_b, step, d, anchors, anchor_radius):
    """``_free`` with fresh scratch arrays (they do not box back into Python from the cache),
    the spheres alone deciding."""
    scratch = mut.make_scratch(d, len(q_a), anchors, anchor_radius, mut._no_hulls(), False)
    return mut._free(q_a, q_b, step, d, scratch)


@njit
def _first_blocking(q_a, q_b, step, d):
    """``_edge_prefix`` of one segment, no anchors, the spheres alone: (first, n,
    configurations classified)."""
    scratch = mut.make_scratch(d, len(q_a), np.empty((0, len(q_a))), 0.0, mut._no_hulls(), False)
    first, n = mut._edge_prefix(q_a, q_b, step, d, scratch)
    return first, n, scratch[3][0]


def test_edge_prefix_agrees_with_sampling_every_step(data, limits):
    """The certified march finds the same first blocking sample as checking all of them."""
    rng = np.random.default_rng(2)
    fewer = 0
    for _ in range(60):
        q_a, q_b = rng.uniform(*limits, (2, 7))
        q_b = q_a + 0.5 * (q_b - q_a)
        first, n, checks = _first_blocking(q_a, q_b, 0.01, data)
        every, n_every, _, _ = mut.sphere_kernel.prefixes(q_a[None], q_b[None], 0.01, True, data)
        assert (first, n) == (every[0], n_every[0])
        fewer += checks < min(first + 1, n)
    assert fewer > 10


@njit
def _edge_proven_free(q_a, q_b, step, d, hull_floats, hull_ints):
    """``_free`` with the exact shapes proving what the spheres cannot decide, no anchors, and
    the count of configurations it charged."""
    h = mut.unpack_hulls(hull_floats, hull_ints)
    scratch = mut.make_scratch(d, len(q_a), np.empty((0, len(q_a))), 0.0, h, True)
    return mut._free(q_a, q_b, step, d, scratch), scratch[3][0]


def test_undecided_samples_pass_only_near_the_anchors(scene, data, limits):
    """A configuration the spheres cannot decide blocks an edge ending there, unless it is an
    anchor itself (the search's start or goal, which Drake has checked)."""
    from planning.collision.spheres import UNKNOWN

    model = sphere_model(scene)
    rng = np.random.default_rng(5)
    qs = rng.uniform(*limits, (4000, 7))
    undecided = qs[model.classify(qs) == UNKNOWN][0]
    free = next(q for q in qs if model.classify(q)[0] == 0 and np.linalg.norm(q - undecided) > 0.5)
    none = np.empty((0, 7))
    assert not _edge_free(free, undecided, 0.1, data, none, 0.0)
    assert not _edge_free(undecided, undecided, 0.1, data, none, 0.0)
    assert _edge_free(undecided, undecided, 0.1, data, undecided[None, :], 0.05)
    # Near an anchor is not enough for the end, which may become a waypoint.
    assert not _edge_free(free, undecided, 0.1, data, (undecided + 0.01)[None, :], 0.05)


def _own_pairs_alone(q, d):
    """True when the spheres leave q UNKNOWN for a pair of the robot's own links alone."""
    state, radius = classify_stopping(q, d)
    return state == mut.UNKNOWN and radius == mut.SELF_UNKNOWN


def test_undecided_own_pairs_the_exact_shapes_prove_free_pass(scene, data, limits):
    """With the search's hull proofs, a sample the spheres leave UNKNOWN for the robot's own
    links alone passes when its exact shapes prove it free, anywhere (no anchor needed); one
    UNKNOWN against an object, or not proven, still blocks. What passes is free for Drake."""
    model = sphere_model(scene)
    hulls = model.packed_hulls()
    rng = np.random.default_rng(5)
    qs = rng.uniform(*limits, (4000, 7))
    undecided = qs[model.classify(qs) == UNKNOWN]
    proven = mut.hull_kernel.prove_free(undecided, data, model.hull_data(), np.zeros((0, 7)))
    own = np.array([_own_pairs_alone(q, data) for q in undecided])
    assert (proven & own).any() and (proven & ~own).any() and (~proven & own).any()
    for q, ok, asked in zip(undecided[:80], proven[:80] & own[:80], own[:80], strict=True):
        # A proof costs HULL_CHECKS configurations of the search's budget.
        assert _edge_proven_free(q, q, 0.1, data, *hulls) == (ok, 1 + asked * mut.HULL_CHECKS)
        assert not _edge_free(q, q, 0.1, data, np.empty((0, 7)), 0.0)
        if ok:
            assert scene.is_collision_free(q)


def test_an_edge_with_a_non_finite_end_is_never_free(data, ends):
    q_a = ends[0]
    bad = q_a.copy()
    bad[2] = np.nan
    none = np.empty((0, 7))
    assert _edge_free(q_a, q_a - 0.3 * np.eye(7)[0], 0.1, data, none, 0.0)  # (a free one is)
    assert not _edge_free(q_a, bad, 0.1, data, none, 0.0)
    assert not _edge_free(bad, q_a, 0.1, data, none, 0.0)


def test_solve_is_the_ends_check_the_search_and_the_fine_check_in_one_call(
    scene, data, limits, ends
):
    args = (*limits, *mut.pack(data), *mut.NO_HULLS)

    def settings():  # a fresh generator each time, seeded with 3
        return (0.1, 1.0, 0.05, 50_000, 20, mut.seed_state(3), 0.0, True, np.inf, 1.0, True)

    status, path, how, checks, unproven, bad, unknown, segment = mut.solve(
        *ends, *args, settings(), True, FINE, False
    )
    alone = search(data, limits, *ends, seed=3)
    assert status == alone[0] == mut.FOUND and how == alone[2] and unproven == 0
    np.testing.assert_array_equal(path, alone[1])
    fine = mut.fine_check(path, FINE, data, *mut.NO_HULLS, False)
    assert bad == fine[0] == -1
    np.testing.assert_array_equal(unknown, fine[1])
    np.testing.assert_array_equal(segment, fine[2])
    assert checks == alone[3] + fine[3] + 2  # and the two ends
    # An end the spheres cannot prove free stops it before any search: bit 1 the goal.
    ready = scene.model.named_configurations["ready"]  # inside the box
    result = mut.solve(ends[0], ready, *args, settings(), True, FINE, False)
    assert result[0] == mut.ENDS_UNPROVEN and result[4] == 2 and len(result[1]) == 0
    nan = np.full(7, np.nan)
    assert mut.solve(nan, ends[1], *args, settings(), True, FINE, False)[4] == 1
    # Without the ends' check it searches; with fine_step 0 it does not fine-check.
    result = mut.solve(*ends, *args, settings(), False, 0.0, False)
    assert result[0] == mut.FOUND and result[3] == alone[3] and result[5] == -1
    np.testing.assert_array_equal(result[1], alone[1])


def test_solve_asks_the_exact_shapes_about_what_the_spheres_cannot_decide(scene, data, limits):
    """With the packed ``HullData``, an end the spheres leave UNKNOWN but the exact shapes prove
    free does not stop the call (ENDS_UNPROVEN), and the fine check returns only the UNKNOWN
    samples those cannot prove free."""
    model = sphere_model(scene)
    hulls = model.packed_hulls()
    # Configurations by the wall that the spheres cannot decide and the hulls prove free.
    rng = np.random.default_rng(11)
    ready = scene.model.named_configurations["ready"]
    qs = np.clip(ready + rng.normal(0.0, 0.3, (3000, 7)), *limits)
    unknown = qs[model.classify(qs) == UNKNOWN]
    proven = unknown[mut.hull_kernel.prove_free(unknown, data, model.hull_data(), np.zeros((0, 7)))]
    assert len(proven) >= 2
    start, goal = proven[0], proven[1]

    def solve(hull_buffers, check_ends):
        args = (*limits, *mut.pack(data), *hull_buffers)
        # The search on the spheres alone (its own proofs off): the fine check is compared.
        settings = (0.1, 1.0, 0.05, 50_000, 20, mut.seed_state(3), 0.0, True, np.inf, 1.0, False)
        return mut.solve(start, goal, *args, settings, check_ends, FINE, False)

    without = solve(mut.NO_HULLS, True)
    assert without[0] == mut.ENDS_UNPROVEN and without[4] == 3  # neither end proven
    status, path, _, _, unproven, bad, unknown_left, segment = solve(hulls, True)
    assert status == mut.FOUND and unproven == 0
    # The same search either way; the fine check's UNKNOWN samples are the spheres' less those
    # the hulls prove (fine samples by the wall, between the search's).
    alone = solve(mut.NO_HULLS, False)
    np.testing.assert_array_equal(path, alone[1])
    assert bad == alone[5]
    left = {tuple(q) for q in unknown_left}
    assert left <= {tuple(q) for q in alone[6]}
    expected = ~mut.hull_kernel.prove_free(alone[6], data, model.hull_data(), np.zeros((0, 7)))
    assert len(left) == int(expected.sum()) < len(alone[6])
    assert len(segment) == len(unknown_left)


@njit
def _free_after(q_a, q_b, d, blocked):
    """``_free(q_a, q_b)`` (end known) after the edges ``blocked`` (K, 2, 7) were checked with
    the same scratch arrays, and the configurations it classified."""
    scratch = mut.make_scratch(d, len(q_a), np.empty((0, len(q_a))), 0.0, mut._no_hulls(), False)
    for k in range(len(blocked)):
        mut._free(blocked[k, 0], blocked[k, 1], 0.1, d, scratch)
    before = scratch[3][0]
    free = mut._free(q_a, q_b, 0.1, d, scratch, True)
    return free, scratch[3][0] - before


def test_an_edge_passing_a_sample_that_blocked_another_is_checked_there_first(data, ends):
    """``_free`` checks first the sample nearest to a remembered blocking one: an edge running
    past the wall where the edge before was blocked costs one check. The order never changes
    the answer: random edges get the same one with and without other edges checked before."""
    start, goal = ends
    wall = (start + goal) / 2.0  # "ready", in the wall
    none = np.empty((0, 2, 7))
    first = np.array([[start, wall]])  # blocked at its end, remembered
    # A longer edge through the wall's side (it spans joint 1 from about -0.7 to 0.5 rad about
    # "ready"), its midpoint past the wall: the bisection meets the wall at the second check.
    q_a, q_b = wall - 0.8 * E[0] + 0.02 * E[1], wall + 2.4 * E[0] + 0.02 * E[1]
    fresh = _free_after(q_a, q_b, data, none)
    remembered = _free_after(q_a, q_b, data, first)
    assert not fresh[0] and not remembered[0]
    assert remembered[1] == 1 < fresh[1]
    rng = np.random.default_rng(3)
    for _ in range(60):
        before = np.array([[start, wall], [goal, wall + rng.normal(0.0, 0.1, 7)]])
        q_a = rng.choice([start, goal]) + rng.normal(0.0, 0.3, 7)
        q_b = wall + rng.normal(0.0, 0.6, 7)
        assert _free_after(q_a, q_b, data, none)[0] == _free_after(q_a, q_b, data, before)[0]
