"""The robot's own pairs proven apart at every configuration (``self_pairs``) are left out of
the checks, and only those: a pair that can touch stays, a proof that runs out of cells keeps
the pair, and the joints' box is each joint's poses, once."""

import numpy as np
import pytest

from planning.collision import self_pairs
from planning.collision.spheres import FREE, SphereCollisionModel
from tests.robot_helpers import elbow_scene


@pytest.fixture(scope="module")
def low_arm(tmp_path_factory):
    return elbow_scene(tmp_path_factory.mktemp("elbow_low"), 0.3)


def _plate_and_arm(scene):
    plant = scene.plant
    return frozenset(int(plant.GetBodyByName(n).index()) for n in ("base", "arm"))


def test_a_pair_that_never_comes_close_is_left_out(low_arm):
    model = SphereCollisionModel(low_arm)
    assert model._never == {_plate_and_arm(low_arm)}
    assert len(model.kernel_data().body_pair) == 0  # nothing left to check
    rng = np.random.default_rng(0)
    qs = np.column_stack([rng.uniform(-4, 4, 300), rng.uniform(-1.5, 0.3, 300)])
    assert np.all(model.classify(qs) == FREE)
    assert all(low_arm.is_collision_free(q) for q in qs)  # Drake agrees


def test_a_pair_that_can_touch_stays(tmp_path):
    scene = elbow_scene(tmp_path, 1.5)
    model = SphereCollisionModel(scene)
    assert model._never == set()
    assert len(model.kernel_data().body_pair) == 1


def test_a_proof_out_of_cells_keeps_the_pair(tmp_path, monkeypatch):
    monkeypatch.setattr(self_pairs, "BUDGET", 10)  # fewer than the first grid's 64 cells
    monkeypatch.setenv("DRAKE_SIM_CACHE", str(tmp_path / "cache"))  # no proof read back
    scene = elbow_scene(tmp_path / "robot", 0.3)
    assert SphereCollisionModel(scene)._never == set()


def test_the_box_is_one_turn_of_a_revolute_joint():
    low, high, wrap = self_pairs.domain(
        [-2 * np.pi, -np.inf, -1.0, -0.5], [2 * np.pi, np.inf, 1.0, 0.5], [True, True, True, False]
    )
    np.testing.assert_allclose(low, [-2 * np.pi, -np.pi, -1.0, -0.5])
    np.testing.assert_allclose(high, [0.0, np.pi, 1.0, 0.5])
    assert wrap.tolist() == [True, True, False, False]
