"""The Panda planning model: converted assets, SRDF filters, named configurations, config."""

import numpy as np
import pytest

from drake_sim.base.errors import ConfigError
from drake_sim.base.resources import cache_dir
from planning import config as config_mod
from planning.model import assets as panda_assets
from planning.model import panda as mut
from planning.model.panda_config import PandaModelConfig


@pytest.fixture(scope="module")
def model():
    return mut.build_panda_model(config_mod.PandaPlanningConfig().model)


def test_urdf_is_cached_with_relative_converted_meshes():
    for geometry in panda_assets.COLLISION_GEOMETRIES:
        urdf = panda_assets.panda_urdf(geometry)
        assert cache_dir() in urdf.parents
        text = urdf.read_text()
        assert "package://" not in text and str(cache_dir()) not in text
        assert ".dae" not in text and ".stl" not in text
        assert "../meshes/visual/link1.gltf" in text
        assert (urdf.parent / "../meshes/visual/hand.gltf").resolve().is_file()
        assert panda_assets.panda_urdf(geometry) == urdf  # the second call reuses the cache
    assert "declare_convex" in panda_assets.panda_urdf("convex_mesh").read_text()
    with pytest.raises(ValueError, match="collision_geometry"):
        panda_assets.panda_urdf("voxels")


def test_srdf_is_read():
    info = panda_assets.read_srdf()
    assert ("panda_hand", "panda_leftfinger") in info.disabled_collisions
    assert len(info.disabled_collisions) == 35
    assert info.group_states["default"]["panda_joint4"] == pytest.approx(-2.35619)


def test_model_has_arm_fingers_and_attachment(model):
    plant = model.plant
    assert plant.num_positions() == 9
    assert list(model.arm_indices) == list(range(7))
    assert list(model.finger_indices) == [7, 8]
    for name in ("panda_link0", "panda_hand", "panda_leftfinger", mut.ATTACHMENT_BODY):
        assert plant.HasBodyNamed(name, model.instance)
    assert plant.HasFrameNamed("panda_hand_tcp", model.instance)


def test_srdf_pairs_are_scene_graph_filters(model):
    """Filters live in the SceneGraph model, so IK distance constraints see them too."""
    plant, inspector = model.plant, model.scene_graph.model_inspector()

    def filtered(a, b):
        ids_a = plant.GetCollisionGeometriesForBody(plant.GetBodyByName(a))
        ids_b = plant.GetCollisionGeometriesForBody(plant.GetBodyByName(b))
        return all(inspector.CollisionFiltered(i, j) for i in ids_a for j in ids_b)

    assert filtered("panda_hand", "panda_link5")  # "Default" in the SRDF: not adjacent
    assert filtered("panda_link3", "panda_rightfinger")
    assert not filtered("panda_link1", "panda_link7")
    assert not filtered("panda_link2", "panda_hand")


def test_named_configurations(model):
    named = model.named_configurations
    assert {"ready", "extended", "transport", "default"} <= set(named)
    np.testing.assert_allclose(named["default"], named["ready"], atol=1e-3)
    lower = model.plant.GetPositionLowerLimits()[:7]
    upper = model.plant.GetPositionUpperLimits()[:7]
    for name, q in named.items():
        assert q.shape == (7,), name
        assert np.all(q >= lower) and np.all(q <= upper), name


def test_default_config_has_a_table_with_top_at_zero():
    table = config_mod.PandaPlanningConfig().table
    assert table.position[2] + table.size[2] / 2 == pytest.approx(0.0)


@pytest.mark.parametrize(
    "text, match",
    [
        ("model: {colour: red}", "unknown"),
        ("model: {named_configurations: {bad: [0, 1]}}", "7"),
        ("model: {finger_position: 0.5}", "finger_position"),
        ("table: {size: [1, 1], position: [0, 0, 0]}", "table"),
        ("ik: {time_budget: 0}", "time_budget"),
        ("model: [", "malformed YAML at line 2"),
    ],
)
def test_bad_config_is_a_config_error(text, match):
    with pytest.raises(ConfigError, match=match):
        config_mod.load_panda_config(data=text)


def test_missing_config_file(tmp_path):
    with pytest.raises(ConfigError, match="no such file"):
        config_mod.load_panda_config(tmp_path / "nope.yaml")


def test_bad_disabled_pair_names_the_body(model):
    from pydrake.planning import RobotDiagramBuilder

    builder = RobotDiagramBuilder(time_step=0.0)
    instance = mut.add_panda(builder.plant(), PandaModelConfig())
    builder.plant().Finalize()
    with pytest.raises(ConfigError, match="panda_link9"):
        mut.apply_disabled_collisions(
            builder.plant(), builder.scene_graph(), instance, [("panda_link9", "panda_hand")]
        )


def test_plant_distance_constraints_honour_the_srdf_filters():
    """An IK/trajectory-optimisation distance constraint on the plant agrees with the checker."""
    from pydrake.multibody.inverse_kinematics import MinimumDistanceLowerBoundConstraint
    from pydrake.planning import RobotDiagramBuilder

    from planning import PlanningScene

    config = config_mod.PandaPlanningConfig()
    config.table = None
    scene = PlanningScene(config)
    rng = np.random.default_rng(0)
    lower, upper = scene.plant.GetPositionLowerLimits(), scene.plant.GetPositionUpperLimits()
    qs = [np.concatenate([rng.uniform(lower[:7], upper[:7]), [0.04, 0.04]]) for _ in range(200)]
    violations = {}
    for apply in (False, True):
        builder = RobotDiagramBuilder(time_step=0.0)
        instance = mut.add_panda(builder.plant(), config.model)
        builder.plant().Finalize()
        if apply:
            pairs = mut.disabled_collision_pairs(config.model)
            mut.apply_disabled_collisions(builder.plant(), builder.scene_graph(), instance, pairs)
        diagram = builder.Build()
        context = diagram.CreateDefaultContext()
        plant_context = diagram.plant().GetMyMutableContextFromRoot(context)
        constraint = MinimumDistanceLowerBoundConstraint(diagram.plant(), 0.0, plant_context)
        violations[apply] = [not constraint.CheckSatisfied(q) for q in qs]
    assert sum(violations[True]) < sum(violations[False])
    disagree = sum(
        v == scene.is_collision_free(q) for v, q in zip(violations[True], qs, strict=True)
    )
    assert disagree <= 2


def test_add_table_has_its_top_at_zero():
    from pydrake.geometry import Role
    from pydrake.multibody.plant import AddMultibodyPlantSceneGraph
    from pydrake.systems.framework import DiagramBuilder

    from planning.config import PandaPlanningConfig
    from planning.model.panda import add_table

    table = PandaPlanningConfig().table
    builder = DiagramBuilder()
    plant, scene_graph = AddMultibodyPlantSceneGraph(builder, 0.0)
    add_table(plant, table)
    plant.Finalize()
    inspector = scene_graph.model_inspector()
    frame = plant.GetBodyFrameIdOrThrow(plant.world_body().index())
    for role in (Role.kProximity, Role.kIllustration):
        (geometry,) = inspector.GetGeometries(frame, role)
        z_top = inspector.GetPoseInFrame(geometry).translation()[2] + table.size[2] / 2
        assert abs(z_top) < 1e-12
