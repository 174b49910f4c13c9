"""Clearance tables of the robot's own pairs (``pair_tables``): on a two-joint arm whose arm
link can swing into its base plate, every value the table gives is a clearance Drake's exact
distance keeps (across the continuous joint's wrap too), the table decides most configurations,
and the sphere model with the table never calls a colliding configuration free."""

import numpy as np
import pytest

from planning.collision import pair_tables, self_pairs
from planning.collision.sphere_kernel import COLLIDING, FREE, table_clearance
from planning.collision.spheres import SphereCollisionModel
from tests.robot_helpers import elbow_scene


@pytest.fixture(scope="module")
def elbow(tmp_path_factory):
    return elbow_scene(tmp_path_factory.mktemp("elbow"), 1.5)


def _pair_distance(scene, q) -> float:
    """Drake's signed distance between the plate's and the arm's collision shapes at q."""
    plant, graph = scene.plant, scene.model.scene_graph
    context = scene.model.diagram.CreateDefaultContext()
    plant.SetPositions(plant.GetMyContextFromRoot(context), scene.full_q(q))
    query = graph.get_query_output_port().Eval(graph.GetMyContextFromRoot(context))
    (a,) = plant.GetCollisionGeometriesForBody(plant.GetBodyByName("base"))
    (b,) = plant.GetCollisionGeometriesForBody(plant.GetBodyByName("arm"))
    return query.ComputeSignedDistancePairClosestPoints(a, b).distance


def _configurations(n, lift_upper, seed=0):
    rng = np.random.default_rng(seed)  # the pan joint beyond one turn: the cells wrap
    return np.column_stack([rng.uniform(-5.0, 5.0, n), rng.uniform(-1.5, lift_upper, n)])


def test_every_table_value_is_a_clearance_drake_keeps(elbow):
    model = SphereCollisionModel(elbow)
    d = model.kernel_data()
    assert len(d.body_pair) == 1 and d.table_start[0] == 0  # plate and arm, tabulated
    assert d.table_wrap[0].tolist() == [1, 0]  # the continuous pan wraps, the lift does not
    assert d.table_n[0, 0] * d.table_n[0, 1] == len(d.table)
    qs = _configurations(1500, 1.5)
    values = np.array([table_clearance(d, 0, q) for q in qs])
    distances = np.array([_pair_distance(elbow, q) for q in qs])
    assert np.all(distances[values > 0.0] >= values[values > 0.0])
    assert np.any(distances < 0.0)  # the arm does reach the plate
    assert np.mean(values > 0.0) > 0.5  # most configurations need no sphere test of the pair
    # Undecided only near contact: a cell loses at most LOSS to the motion within it.
    assert np.all(values[distances > 2 * pair_tables.LOSS] > 0.0)
    # Outside the lift's limits, no cell: the spheres decide.
    assert table_clearance(d, 0, np.array([0.0, 1.6])) == 0.0
    assert table_clearance(d, 0, np.array([np.nan, 0.0])) == 0.0


def test_the_model_with_its_table_agrees_with_drake(elbow):
    model = SphereCollisionModel(elbow)
    qs = _configurations(1500, 1.5, seed=1)
    verdicts = model.classify(qs)
    colliding = np.array([not elbow.is_collision_free(q) for q in qs])
    assert not np.any(colliding & (verdicts == FREE))
    assert not np.any(~colliding & (verdicts == COLLIDING))
    assert np.mean(verdicts[~colliding] == FREE) > 0.8


def test_kernel_fields_lay_the_tables_end_to_end():
    one = [np.array([v]) for v in (1, 3, False, -1.0, 0.5)]
    table = pair_tables.PairTable(*one, np.array([0.1, 0.0, 0.2]))
    fields = pair_tables.kernel_fields([None, table, table])
    assert fields["table_start"].tolist() == [-1, 0, 3]
    assert fields["table_joint"].tolist() == [[-1, -1], [1, -1], [1, -1]]
    assert fields["table_n"].tolist() == [[1, 1], [3, 1], [3, 1]]
    assert fields["table"].tolist() == [0.1, 0.0, 0.2, 0.1, 0.0, 0.2]
    empty = pair_tables.kernel_fields([])
    assert empty["table"].shape == (0,) and empty["table_joint"].shape == (0, 2)


def test_a_table_is_made_once_then_read_from_the_cache(elbow, monkeypatch):
    model = SphereCollisionModel(elbow)
    before = model.kernel_data().table.copy()

    def refuse(*args):
        raise AssertionError("tabulated again")

    monkeypatch.setattr(pair_tables, "clearance_grid", refuse)
    again = SphereCollisionModel(elbow).kernel_data().table
    np.testing.assert_array_equal(again, before)
    # A cover with another slack has other sphere speeds, so other table values, from the
    # same grid: the cells' clearances (the costly part) are computed once per robot.
    other = SphereCollisionModel(elbow, slack=0.005).kernel_data()
    assert len(other.table) == len(before)
    scale = before[before > 0.0] / other.table[before > 0.0]
    assert np.allclose(scale, scale[0])


def test_a_joint_outside_the_group_changes_only_the_keys_of_pairs_it_moves(tmp_path):
    """A table is kept for the positions of the joints outside the group on its pair's way (a
    finger): moving the finger makes a new key for the plate and the finger, not for the plate
    and the arm."""
    scene = elbow_scene(tmp_path, 1.5, finger=True)
    model = SphereCollisionModel(scene)
    plant = scene.plant
    names = {int(i): plant.get_body(i).name() for i in plant.GetBodyIndices(scene.model.instance)}

    def keys():
        d, h, present = model.kernel_data(), model.hull_data(), model._present
        low, high, wrap = self_pairs.domain(model._own.lower, model._own.upper,
                                            model._own.revolute)  # fmt: skip
        out = {}
        for a, b in d.body_pair:
            rows = [r for r, (g, e) in enumerate(h.pair)
                    if {int(h.geom_body[g]), int(h.geom_body[e])} == {int(a), int(b)}]  # fmt: skip
            pair = frozenset((names[present[a]], names[present[b]]))
            out[pair] = pair_tables.table_key(d, h, rows, a, b, low, high, wrap, d.speed)
        return out

    before = keys()
    scene.set_positions({"slide": 0.04})
    after = keys()
    plate_arm, plate_finger = frozenset(("base", "arm")), frozenset(("base", "finger"))
    assert before[plate_arm] is not None and before[plate_arm] == after[plate_arm]
    assert before[plate_finger] is not None and before[plate_finger] != after[plate_finger]
