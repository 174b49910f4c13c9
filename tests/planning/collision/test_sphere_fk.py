"""Batched forward kinematics (planning.collision.sphere_fk): BatchedKinematics gives the same
body poses as Drake's plant for many configurations at once, revolute, prismatic and weld joints
alike (the Panda's arm, fingers and hand), refuses trees with other joint types, and folds the
steps that cannot move in a plan into those that can (fold_fixed_steps, fold_points)."""

import numpy as np
import pytest
from pydrake.multibody.plant import MultibodyPlant
from pydrake.multibody.tree import BallRpyJoint, PrismaticJoint, RevoluteJoint, SpatialInertia

import planning.collision.sphere_fk as mut
from planning import PlanningScene
from planning.collision.sphere_kernel import transforms


@pytest.fixture(scope="module")
def scene():
    return PlanningScene()


def panda_bodies(scene):
    plant = scene.plant
    return [plant.GetBodyByName(name, scene.model.instance).index() for name in BODIES]


BODIES = ["panda_link3", "panda_link7", "panda_hand", "panda_leftfinger", "panda_rightfinger"]


def random_full(scene, n, seed):
    plant, rng = scene.plant, np.random.default_rng(seed)
    lower, upper = plant.GetPositionLowerLimits(), plant.GetPositionUpperLimits()
    return rng.uniform(lower, upper, (n, plant.num_positions()))  # fingers too


def test_poses_equal_drakes(scene):
    plant = scene.plant
    bodies = panda_bodies(scene)
    dut = mut.BatchedKinematics(plant, bodies)
    assert dut.num_positions == plant.num_positions() == 9
    qs = random_full(scene, 20, seed=0)
    R, p = dut.poses(qs)
    T = dut.transforms(qs)
    assert R.shape == (len(bodies), 20, 3, 3) and p.shape == (len(bodies), 20, 3)
    assert T.shape == (len(bodies), 20, 4, 4)
    np.testing.assert_array_equal(T[:, :, 3], np.broadcast_to([0.0, 0.0, 0.0, 1.0], (5, 20, 4)))
    context = plant.CreateDefaultContext()
    for n, q in enumerate(qs):
        plant.SetPositions(context, q)
        for k, body in enumerate(bodies):
            X_WB = plant.EvalBodyPoseInWorld(context, plant.get_body(body))
            np.testing.assert_allclose(T[k, n], X_WB.GetAsMatrix4(), atol=1e-9)
            np.testing.assert_allclose(R[k, n], X_WB.rotation().matrix(), atol=1e-9)
            np.testing.assert_allclose(p[k, n], X_WB.translation(), atol=1e-9)


def test_the_fingers_move_along_their_prismatic_joints(scene):
    plant = scene.plant
    dut = mut.BatchedKinematics(plant, panda_bodies(scene))
    q = np.tile(scene.full_q(scene.model.named_configurations["ready"]), (2, 1))
    q[0, scene.model.finger_indices] = 0.0
    q[1, scene.model.finger_indices] = 0.04
    _, p = dut.poses(q)
    hand, left, right = p[2], p[3], p[4]
    # Closed: both fingers at the same place; open: 4 cm each way, the hand does not move.
    assert np.linalg.norm(left[0] - right[0]) < 1e-9
    assert np.linalg.norm(left[1] - right[1]) == pytest.approx(0.08)
    np.testing.assert_allclose(hand[0], hand[1])


def test_a_single_configuration_and_the_flat_tree(scene):
    plant = scene.plant
    bodies = panda_bodies(scene)
    dut = mut.BatchedKinematics(plant, bodies)
    q = random_full(scene, 3, seed=1)
    np.testing.assert_allclose(dut.transforms(q[1])[:, 0], dut.transforms(q)[:, 1])
    parent, kind, q_index, terms = dut.arrays()
    steps = len(parent)
    assert kind.shape == q_index.shape == (steps,) and terms.shape == (steps, 3, 3, 4)
    assert np.all(parent < np.arange(steps))  # parents come first (-1: the world)
    assert set(kind.tolist()) == {0, 1, 2}  # welds, revolute and prismatic joints
    assert len(dut.out) == len(bodies) and np.all(dut.out < steps)
    assert sorted(q_index[kind > 0].tolist()) == list(range(9))  # each joint once


def chain(joint_type):
    """A world-attached body on a joint of the given type, and a child on a revolute joint."""
    plant = MultibodyPlant(0.0)
    inertia = SpatialInertia.SolidSphereWithMass(1.0, 0.05)
    a = plant.AddRigidBody("a", inertia)
    b = plant.AddRigidBody("b", inertia)
    world = plant.world_body().body_frame()
    if joint_type is PrismaticJoint:
        plant.AddJoint(PrismaticJoint("ja", world, a.body_frame(), [1.0, 0.0, 0.0]))
    elif joint_type is BallRpyJoint:
        plant.AddJoint(BallRpyJoint("ja", world, a.body_frame()))
    plant.AddJoint(RevoluteJoint("jb", a.body_frame(), b.body_frame(), [0.0, 1.0, 0.0]))
    plant.Finalize()
    return plant, [a.index(), b.index()]


def test_a_small_prismatic_revolute_chain():
    plant, bodies = chain(PrismaticJoint)
    dut = mut.BatchedKinematics(plant, bodies[::-1])  # any order
    q = np.array([[0.3, 0.5], [-0.2, -1.0]])
    _, p = dut.poses(q)
    np.testing.assert_allclose(p[1], [[0.3, 0.0, 0.0], [-0.2, 0.0, 0.0]], atol=1e-12)
    context = plant.CreateDefaultContext()
    for n in range(2):
        plant.SetPositions(context, q[n])
        X = plant.EvalBodyPoseInWorld(context, plant.get_body(bodies[1]))
        np.testing.assert_allclose(dut.transforms(q)[0, n], X.GetAsMatrix4(), atol=1e-12)


@pytest.mark.parametrize("joint_type", [BallRpyJoint, None])
def test_other_joint_types_and_floating_bodies_are_refused(joint_type):
    plant, bodies = chain(joint_type)  # None: body "a" floats
    with pytest.raises(NotImplementedError):
        mut.BatchedKinematics(plant, bodies)


def test_folding_keeps_one_step_per_arm_joint_and_every_pose(scene):
    """The fixed steps (welds, and the fingers at the template's positions) fold into the arm
    joints' steps; every old step's pose is its new step's pose times its offset, and points
    moved with ``fold_points`` land where they were."""
    plant = scene.plant
    dut = mut.BatchedKinematics(plant, panda_bodies(scene))
    full = random_full(scene, 8, seed=2)
    template = full[0].copy()
    arm = np.asarray(scene.model.arm_indices, dtype=np.int64)
    tree, offsets = mut.fold_fixed_steps(*dut.arrays(), template, arm)
    parent, kind, q_index, _ = tree
    moving = kind > 0
    assert sorted(q_index[moving].tolist()) == sorted(arm.tolist())  # each arm joint once
    assert np.all(parent[~moving] == -1)  # what stays fixed hangs from the world, constant
    assert len(parent) < len(dut.arrays()[0]) and np.all(parent < np.arange(len(parent)))
    fulls = np.tile(template, (len(full), 1))
    fulls[:, arm] = full[:, arm]  # the arm moves, the fingers stay at the template
    old = transforms(fulls, *dut.arrays())
    new = transforms(fulls, *tree)
    rng = np.random.default_rng(3)
    points = rng.normal(size=(len(offsets), 3))
    steps, moved = mut.fold_points(offsets, np.arange(len(offsets)), points)
    for s, (step, X) in enumerate(offsets):
        assert steps[s] == step
        for n in range(len(full)):
            X_old = np.vstack([old[n, s], [0, 0, 0, 1]])
            X_new = np.vstack([new[n, step], [0, 0, 0, 1]])
            np.testing.assert_allclose(X_new @ X, X_old, atol=1e-12)
            np.testing.assert_allclose(
                new[n, step, :, :3] @ moved[s] + new[n, step, :, 3],
                old[n, s, :, :3] @ points[s] + old[n, s, :, 3],
                atol=1e-12,
            )


def test_folding_a_tree_whose_joints_all_move_changes_nothing():
    plant, bodies = chain(PrismaticJoint)
    dut = mut.BatchedKinematics(plant, bodies)
    tree, offsets = mut.fold_fixed_steps(*dut.arrays(), np.zeros(2), np.array([0, 1]))
    for got, want in zip(tree, dut.arrays(), strict=True):
        np.testing.assert_array_equal(got, want)
    assert [step for step, _ in offsets] == [0, 1]
    assert all(np.array_equal(X, np.eye(4)) for _, X in offsets)
