"""Checks that hold between samples (``validation.swept``): a configuration proven free with the
margins of a motion (``sphere_kernel.motion_margins``) has every configuration within that
motion free too, by the spheres (``sphere_batch.classify_many``), by the exact shapes
(``hull_kernel.prove_free``) and by Drake's distances (``checker.drake_clear``), in scenes with
every object kind and a held object; the speed bounds behind those margins hold
(``checker.geometry_speed``, ``HullData.speed``); and cells cover a segment, a cell whose
centre fails only by its margin being cut into smaller ones (``checker.swept_free``)."""

import numpy as np
import pytest
from pydrake.math import RigidTransform
from pydrake.multibody.tree import BodyIndex

from planning import PlanningScene
from planning.collision import checker as mut
from planning.collision.sphere_batch import classify_many
from planning.collision.sphere_checker import SphereCheckerAdapter, sphere_model
from planning.collision.sphere_kernel import COLLIDING, FREE, motion_margins
from planning.collision.sphere_robot import robot_hulls

MOTION = 0.01  # rad per joint: a cell's half at 0.01 rad is at most 0.005 in any joint


@pytest.fixture(scope="module", params=["objects", "held"])
def scene(request):
    """A wall, a cylinder and a ball around the arm; and the same with a held box."""
    scene = PlanningScene()
    scene.add_box("wall", [0.05, 0.8, 0.8], RigidTransform([0.45, 0.0, 0.4]))
    scene.add_cylinder("post", 0.05, 0.9, RigidTransform([0.0, 0.45, 0.45]))
    scene.add_sphere("ball", 0.12, RigidTransform([0.3, -0.35, 0.6]))
    if request.param == "held":
        ready = scene.model.named_configurations["ready"]
        X = scene.attachment_pose(ready).multiply(RigidTransform([0.0, 0.0, 0.06]))
        scene.add_box("held", [0.03, 0.03, 0.06], X)  # between the fingers, clear of link 6
        scene.attach("held", ready)
    return scene


def _samples(scene, count, seed=0):
    """Random configurations within 0.8 rad of "ready", where most are free."""
    adapter = mut.CheckerAdapter(scene)
    rng = np.random.default_rng(seed)
    ready = scene.model.named_configurations["ready"]
    qs = np.clip(ready + rng.uniform(-0.8, 0.8, (count, 7)), adapter.lower, adapter.upper)
    return adapter, rng, qs


def _within(rng, q, motion, count=6):
    """Configurations within ``motion`` (per joint) of q: corners and random points."""
    corners = q + motion * rng.choice([-1.0, 1.0], (count, len(q)))
    inside = q + motion * rng.uniform(-1.0, 1.0, (count, len(q)))
    return np.vstack([corners, inside])


def test_margins_grow_with_the_motion_and_skip_joints_turning_both_bodies(scene):
    d = sphere_model(scene).kernel_data()
    out = np.empty(len(d.body_step) + len(d.body_pair))
    motion_margins(np.zeros(7), d.speed, d.body_pair, out)
    assert not out.any()
    motion_margins(np.full(7, MOTION), d.speed, d.body_pair, out)
    bodies = len(d.body_step)
    np.testing.assert_allclose(out[:bodies], d.speed.sum(axis=1) * MOTION)
    for p, (a, b) in enumerate(d.body_pair):
        moving = (d.speed[a] > 0) & (d.speed[b] > 0)
        expected = ((d.speed[a] + d.speed[b]) * ~moving).sum() * MOTION
        assert out[bodies + p] == pytest.approx(expected)


def test_free_with_margins_means_free_within_the_motion_spheres(scene):
    d = sphere_model(scene).kernel_data()
    _, rng, qs = _samples(scene, 600)
    motion = np.full(qs.shape, MOTION)
    plain = classify_many(qs, d, np.zeros((0, 7)))
    widened = classify_many(qs, d, motion)
    assert np.all((widened == COLLIDING) == (plain == COLLIDING))  # collisions stay proofs
    assert np.all(plain[widened == FREE] == FREE)
    assert 0 < (widened == FREE).sum() < (plain == FREE).sum()  # some lose FREE, not all
    for q in qs[widened == FREE][:60]:
        near = np.ascontiguousarray(_within(rng, q, MOTION))
        assert np.all(classify_many(near, d, np.zeros((0, 7))) == FREE)


def test_free_with_margins_means_free_within_the_motion_shapes_and_drake(scene):
    model = sphere_model(scene)
    adapter, rng, qs = _samples(scene, 400, seed=1)
    motion = np.full(qs.shape, MOTION)
    proven = model.prove_free(qs, motion)
    assert np.all(model.prove_free(qs)[proven])
    speed = mut.geometry_speed(scene)
    clear = np.array(
        [mut.drake_clear(scene.checker, adapter.full(q), motion[0], speed) for q in qs]
    )
    assert proven.sum() > 20 and clear.sum() > 20
    assert not np.any(proven & ~clear)  # the shapes prove nothing Drake's distances reject
    for q in qs[clear][:40]:
        assert adapter.configs_free(_within(rng, q, MOTION)).all()


@pytest.mark.parametrize("source", ["drake", "hulls"])
def test_the_speed_bounds_hold(scene, source):
    """Every vertex of the robot's shapes moves no farther than the bound says, for small
    random motions from random configurations."""
    plant = scene.plant
    inspector = scene.checker.MakeStandaloneModelContext().GetQueryObject().inspector()
    bodies = list(mut.geometry_speed(scene).rows)
    shapes = robot_hulls(plant, inspector, [b for b in bodies if b in robot_hulls_bodies(scene)])
    if source == "drake":
        speed = mut.geometry_speed(scene)
        rows, table = speed.rows, speed.speed
    else:
        model = sphere_model(scene)
        present, table = model.geometry_speed()
        rows = {b: k for k, b in enumerate(present)}
    _, rng, qs = _samples(scene, 40, seed=2)
    for q in qs:
        dq = rng.uniform(-1.0, 1.0, 7) * 1e-3
        before, after = scene.plant_context(q), None
        poses = {b: plant.EvalBodyPoseInWorld(before, plant.get_body(BodyIndex(b))) for b in shapes}
        after = scene.plant_context(q + dq)
        for b, hulls in shapes.items():
            X_b = plant.EvalBodyPoseInWorld(after, plant.get_body(BodyIndex(b)))
            bound = table[rows[b]] @ np.abs(dq)
            for v, _ in hulls:
                moved = np.linalg.norm(X_b.multiply(v.T) - poses[b].multiply(v.T), axis=0)
                assert moved.max() <= bound * (1 + 1e-6) + 1e-12


def robot_hulls_bodies(scene):
    plant = scene.plant
    return {
        int(b)
        for b in plant.GetBodyIndices(scene.model.instance)
        if plant.GetCollisionGeometriesForBody(plant.get_body(b))
    }


def test_cells_cover_a_segment():
    q_a, q_b = np.zeros(7), np.r_[0.025, np.zeros(6)]
    centres, halves = mut.cells(q_a, q_b, 0.01)
    assert len(centres) == 3
    np.testing.assert_allclose(centres[:, 0], [0.025 / 6, 0.0125, 0.025 * 5 / 6])
    np.testing.assert_allclose(centres - halves, np.vstack([q_a, centres[:-1] + halves[:-1]]))
    np.testing.assert_allclose(centres[-1] + halves[-1], q_b)


def test_a_cell_failing_by_its_margin_alone_is_cut(scene, monkeypatch):
    """A centre free, but by less than the margins (ratio below 1), is cut into as many smaller
    cells as its ratio says (at least two), whose margins are smaller, until they pass; a centre
    that collides (ratio 0) settles its cell at once."""
    adapter = SphereCheckerAdapter(scene, 0.01)
    q = scene.model.named_configurations["ready"]
    calls = []

    def by_size(centres, motion):  # ratio 0.5 until the motion is below 1 mrad, then 2
        calls.append(len(centres))
        return np.where(np.abs(motion).max(axis=1) < 1e-3, 2.0, 0.5)

    monkeypatch.setattr(adapter, "cell_ratios", by_size)
    half = np.full((1, 7), 0.005)
    assert mut.swept_free(adapter, q[None], half).all()
    assert calls == [1, 3, 3, 3, 3]  # the cell; 3 (ceil(1.5 / 0.5)) of 1.7 mrad; 3 in each
    calls.clear()  # cells in order, up to the first that fails
    ratios = iter([[0.0, 2.0, 0.0]])
    monkeypatch.setattr(adapter, "cell_ratios", lambda c, motion: np.array(next(ratios)))
    assert list(mut.swept_free(adapter, np.vstack([q, q, q]), np.vstack([half] * 3))) == [
        False,
        False,
        False,
    ]
    monkeypatch.setattr(adapter, "cell_ratios", lambda c, motion: np.zeros(len(c)))
    assert not mut.swept_free(adapter, q[None], half).any()


def test_the_cell_ratio_is_drakes_distance_over_the_margin(scene):
    adapter = mut.CheckerAdapter(scene)
    ready = scene.model.named_configurations["ready"]
    speed = mut.geometry_speed(scene)
    motion = np.full(7, 1e-3)
    ratio = adapter.cell_ratios(ready, motion)[0]
    assert 0.0 < ratio <= 2.0
    assert mut.drake_clear(scene.checker, adapter.full(ready), motion, speed) == (ratio > 1.0)
    assert adapter.configs_free(ready, motion)[0] == (ratio > 1.0)
    if ratio < 2.0:  # twice the motion, half the ratio
        assert adapter.cell_ratios(ready, 2.0 * motion)[0] == pytest.approx(ratio / 2.0)
    spheres = SphereCheckerAdapter(scene, 0.01)
    both = spheres.cell_ratios(np.vstack([ready, ready]), np.vstack([motion, motion]))
    assert np.all((both > 1.0) == (ratio > 1.0))
