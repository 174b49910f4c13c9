"""Sphere models of the Panda (planning.collision.spheres and friends): batched kinematics equal
Drake's, the spheres cover every collision mesh, their verdicts agree with Drake's checker in MBM
and pick-and-place scenes, and scene changes made at run time are seen."""

import numpy as np
import pytest
from pydrake.math import RigidTransform
from pydrake.multibody.tree import BodyIndex

import planning.collision.spheres as mut
from drake_sim.base.resources import config_dir
from planning import PlanningScene
from planning.collision.checker import CheckerAdapter
from planning.collision.sphere_checker import SphereCheckerAdapter, sphere_model
from planning.collision.sphere_cover import box_polytope, cover_polytope, cylinder_polytope
from planning.collision.sphere_robot import shape_polytope
from planning.io.mbm import default_dataset

DATASET = default_dataset()  # the repository's copy: benchmarks/data/mbm_panda


@pytest.fixture(scope="module")
def scene():
    return PlanningScene()


@pytest.fixture
def dut(scene):
    model = sphere_model(scene)
    yield model
    for name in list(scene.attached_objects):
        scene.remove_object(name)
    for name in set(scene.world_objects) - {"table"}:
        scene.remove_object(name)


def random_q(scene, n, seed=0):
    adapter = CheckerAdapter(scene)
    return np.random.default_rng(seed).uniform(adapter.lower, adapter.upper, (n, 7))


def drake_free(scene, qs):
    full = np.tile(scene.full_q(np.zeros(7)), (len(qs), 1))
    full[:, scene.model.arm_indices] = qs
    return np.asarray(scene.checker.CheckConfigsCollisionFree(list(full)), dtype=bool)


def test_batched_kinematics_equal_drake(scene, dut):
    qs = random_q(scene, 20)
    scene.finger_positions = [0.01, 0.03]
    try:
        dut.sync()
        T = dut._transforms(qs)
        for n, q in enumerate(qs):
            context = scene.plant_context(q)
            for k, body in enumerate(dut._bodies):
                X_WB = scene.plant.EvalBodyPoseInWorld(
                    context, scene.plant.get_body(BodyIndex(body))
                )
                np.testing.assert_allclose(T[k, n], X_WB.GetAsMatrix4(), atol=1e-9)
    finally:
        scene.finger_positions = scene.config.model.finger_position


def test_spheres_cover_every_collision_mesh_vertex(scene, dut):
    """Every hull vertex of every collision geometry (and points on the finger boxes' faces)
    lies in one of its body's outer spheres, in random configurations."""
    plant = scene.plant
    inspector = scene.checker.MakeStandaloneModelContext().GetQueryObject().inspector()
    qs = random_q(scene, 5, seed=1)
    centres, radii = dut.sphere_centres(qs)
    owner = np.array(dut._bodies)[dut._slot]
    for n, q in enumerate(qs):
        context = scene.plant_context(q)
        for body in set(owner):
            X_WB = plant.EvalBodyPoseInWorld(context, plant.get_body(BodyIndex(int(body))))
            mine = owner == body
            for g in plant.GetCollisionGeometriesForBody(plant.get_body(BodyIndex(int(body)))):
                v, polygons, _, _ = shape_polytope(inspector.GetShape(g))
                points = [v] + [v[f].mean(axis=0, keepdims=True) for f in polygons]
                p_W = (X_WB @ inspector.GetPoseInFrame(g)).multiply(np.vstack(points).T).T
                d = np.linalg.norm(p_W[:, None, :] - centres[n, mine][None], axis=2)
                assert (d <= radii[mine][None, :] + 1e-9).any(axis=1).all()


def test_cover_of_a_box_is_conservative_and_inner_balls_inside():
    v, faces = box_polytope([0.1, 0.04, 0.2])
    cover = cover_polytope(v, faces, slack=0.01, spacing=0.01, dense_spacing=0.002)
    rng = np.random.default_rng(0)
    # Random points on the faces and inside.
    points = rng.uniform(-1, 1, (4000, 3)) * [0.05, 0.02, 0.1]
    face = rng.integers(0, 3, 4000)
    points[np.arange(4000), face] = np.sign(points[np.arange(4000), face]) * [0.05, 0.02, 0.1][0]
    points[face == 1, 1] = np.sign(points[face == 1, 1]) * 0.02
    points[face == 2, 2] = np.sign(points[face == 2, 2]) * 0.1
    points = np.vstack([points, v])
    d = np.linalg.norm(points[:, None] - cover.p_BS[None], axis=2)
    assert (d <= cover.radius).any(axis=1).all()
    # Inner balls lie inside the box.
    reach = np.abs(cover.p_BS) + cover.inner[:, None]
    assert np.all(reach <= [0.05 + 1e-9, 0.02 + 1e-9, 0.1 + 1e-9])
    assert len(cover.radius) < 100


def test_cylinder_prism_contains_the_cylinder():
    v, _ = cylinder_polytope(0.05, 0.2, sides=16)
    apothem = np.linalg.norm(v[:2, :2].mean(axis=0))
    assert apothem == pytest.approx(0.05)


def check_agreement(scene, qs):
    """Sphere verdicts never contradict Drake's; the adapter's answers equal Drake's."""
    model = sphere_model(scene)
    state = model.classify(qs)
    free = drake_free(scene, qs)
    assert not np.any((state == mut.FREE) & ~free)
    assert not np.any((state == mut.COLLIDING) & free)
    assert np.mean(state != mut.UNKNOWN) > 0.8  # the spheres decide most configurations
    np.testing.assert_array_equal(SphereCheckerAdapter(scene).configs_free(qs), free)


def test_agrees_with_drake_in_mbm_scenes(scene, dut):
    from planning.benchmark import problems_folder
    from planning.io import mbm

    folder = problems_folder(DATASET)
    for family in ("cage_panda", "bookshelf_thin_panda"):
        problem = next(mbm.iter_problems(folder, [family], 1))
        scene.load_moveit(problem.scene_file)
        check_agreement(scene, random_q(scene, 1000, seed=2))
    scene.clear()
    scene.add_box("table", scene.config.table.size, RigidTransform(scene.config.table.position))


def test_agrees_with_drake_in_the_pick_and_place_scene(scene, dut):
    scene.load_yaml(config_dir() / "pickplace.yaml")
    qs = random_q(scene, 1000, seed=3)
    check_agreement(scene, qs)
    # Holding the object: attached at a configuration where the hand is around it.
    scene.attach_new(
        type(scene.world_objects["object"])(
            "held", "box", (0.045, 0.045, 0.08), RigidTransform([0.0, 0.0, 0.1034])
        )
    )
    check_agreement(scene, qs)


def test_objects_added_removed_and_attached_at_run_time_are_seen(scene, dut):
    q = scene.model.named_configurations["ready"]
    assert dut.classify(q[None])[0] == mut.FREE
    p_WH = scene.attachment_pose(q).translation()
    scene.add_sphere("ball", 0.05, RigidTransform(p_WH))
    assert dut.classify(q[None])[0] != mut.FREE
    assert not SphereCheckerAdapter(scene).config_free(q)
    scene.move_object("ball", RigidTransform(p_WH + [0.0, 0.0, 0.5]))
    assert dut.classify(q[None])[0] == mut.FREE
    scene.remove_object("ball")
    # A held rod reaching down through the table.
    scene.attach_new(
        type(scene.world_objects["table"])(
            "rod", "cylinder", (0.02, 2.0), RigidTransform([0.0, 0.0, 0.1])
        )
    )
    assert dut.classify(q[None])[0] != mut.FREE
    assert not SphereCheckerAdapter(scene).config_free(q)
    scene.remove_object("rod")
    assert dut.classify(q[None])[0] == mut.FREE
    # The fingers move with the scene's finger positions.
    before = dut.sphere_centres(q[None])[0]
    scene.finger_positions = 0.0
    try:
        assert not np.allclose(dut.sphere_centres(q[None])[0], before)
    finally:
        scene.finger_positions = scene.config.model.finger_position


def test_unsupported_geometry_falls_back_to_drake(scene, dut, monkeypatch):
    monkeypatch.setattr(dut, "supported", False)
    qs = random_q(scene, 50, seed=4)
    assert np.all(dut.classify(qs) == mut.UNKNOWN)
    np.testing.assert_array_equal(
        SphereCheckerAdapter(scene).configs_free(qs), drake_free(scene, qs)
    )
    # Segments too: everything goes to Drake (from free starts), or blocks before the fallback.
    qa, qb = qs[:25][drake_free(scene, qs[:25])], qs[25:][drake_free(scene, qs[:25])]
    expected = CheckerAdapter(scene, 0.05).free_prefixes(qa, qb)
    np.testing.assert_allclose(SphereCheckerAdapter(scene, 0.05).free_prefixes(qa, qb), expected)
    waiting = SphereCheckerAdapter(scene, 0.05, fallback_after=10**9)
    assert not waiting.free_prefixes(qa, qb).any()


def test_edges_and_prefixes_match_drake_samples(scene, dut):
    scene.add_box("wall", [0.05, 0.8, 0.8], RigidTransform([0.45, 0.0, 0.4]))
    adapter = SphereCheckerAdapter(scene, 0.05)
    drake = CheckerAdapter(scene, 0.05)
    qs = random_q(scene, 40, seed=5)
    qa, qb = qs[:20], qs[20:]
    free_a = drake_free(scene, qa)
    qa, qb = qa[free_a], qb[free_a]
    np.testing.assert_allclose(adapter.free_prefixes(qa, qb), drake.free_prefixes(qa, qb))
    for a, b in zip(qa, qb, strict=True):
        assert adapter.edge_free(a, b) == drake.edge_free(a, b)


def test_prefixes_stop_at_the_first_blocking_sample(scene, dut):
    """The compiled scan of segments agrees with classifying every sample: it stops at the
    first COLLIDING sample (or the first uncertain one with stop_at_unknown) and lists the
    UNKNOWN samples before it."""
    scene.add_box("wall", [0.05, 0.8, 0.8], RigidTransform([0.45, 0.0, 0.4]))
    qs = random_q(scene, 60, seed=6)
    q_a, q_b, step = qs[:30], qs[30:], 0.1
    for stop_at_unknown in (False, True):
        first, n, edge, local = dut.prefixes(q_a, q_b, step, stop_at_unknown)
        for k in range(len(q_a)):
            t = np.arange(1, n[k] + 1) / n[k]
            state = dut.classify(q_a[k] + t[:, None] * (q_b[k] - q_a[k]))
            blocking = (state != mut.FREE) if stop_at_unknown else (state == mut.COLLIDING)
            expected = int(np.argmax(blocking)) if blocking.any() else n[k]
            assert first[k] == expected
            unknown = np.flatnonzero(state[:expected] == mut.UNKNOWN)
            np.testing.assert_array_equal(local[edge == k], unknown)
    assert len(n) == 30 and np.all(n == np.ceil(np.linalg.norm(q_b - q_a, axis=1) / step))


def test_drake_decides_uncertain_configurations_after_the_fallback_count(scene, dut):
    """Before ``fallback_after`` sphere classifications an UNKNOWN configuration counts as
    colliding and Drake is not asked; from then on Drake decides it."""
    scene.load_yaml(config_dir() / "pickplace.yaml")
    qs = random_q(scene, 400, seed=7)
    state = dut.classify(qs)
    unknown = qs[state == mut.UNKNOWN]
    assert len(unknown) > 0
    free = drake_free(scene, unknown)
    assert free.any()  # some are free for Drake: the spheres were only unsure
    late = SphereCheckerAdapter(scene, fallback_after=10**9)
    assert not late.configs_free(unknown).any() and late.counts["drake"] == 0
    early = SphereCheckerAdapter(scene, fallback_after=0)
    np.testing.assert_array_equal(early.configs_free(unknown), free)
    assert early.counts["drake"] == len(unknown)
    # The switch happens when the count of configurations the spheres decided is reached.
    switch = SphereCheckerAdapter(scene, fallback_after=int((state != mut.UNKNOWN).sum()))
    assert not switch.configs_free(unknown).any()
    switch.configs_free(qs)  # the spheres decide that many here
    np.testing.assert_array_equal(switch.configs_free(unknown), free)


def test_non_finite_configurations_are_never_proven_free(scene, dut):
    q = scene.model.named_configurations["ready"].copy()
    q[2] = np.nan
    assert dut.classify(q[None])[0] == mut.UNKNOWN
    qs = np.vstack([scene.model.named_configurations["ready"], q])
    first, n, edge, local = dut.prefixes(qs[:1], qs[1:], 0.1, stop_at_unknown=True)
    assert first[0] < n[0]  # the NaN end blocks the segment
