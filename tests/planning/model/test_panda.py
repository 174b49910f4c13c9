"""The Panda: converted assets, SRDF filters, the planning configuration's checks."""

import numpy as np
import pytest

from drake_sim.base.errors import ConfigError
from drake_sim.base.resources import cache_dir
from planning import config as config_mod
from planning.model import assets as panda_assets
from planning.model.model_config import RobotModelConfig
from planning.model.planning_model import apply_disabled_collisions, robot_model


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


def test_default_config_has_a_table_with_top_at_zero():
    table = config_mod.PlanningConfig().table
    assert table.position[2] + table.size[2] / 2 == pytest.approx(0.0)


@pytest.mark.parametrize(
    "text, match",
    [
        ("model: {colour: red}", "unknown"),
        ("model: {named_configurations: {bad: [0, 1]}}", "has 2 values, group 'arm' has 7"),
        ("model: {finger_position: 0.5}", "finger_position"),
        ("table: {size: [1, 1], position: [0, 0, 0]}", "table"),
        ("ik: {time_budget: 0}", "time_budget"),
        ("model: [", "malformed YAML at line 2"),
    ],
)
def test_bad_config_is_a_config_error(text, match):
    with pytest.raises(ConfigError, match=match):
        config_mod.load_planning_config(data=text)


def test_missing_config_file(tmp_path):
    with pytest.raises(ConfigError, match="no such file"):
        config_mod.load_planning_config(tmp_path / "nope.yaml")


def test_bad_disabled_pair_names_the_body():
    from pydrake.planning import RobotDiagramBuilder

    builder = RobotDiagramBuilder(time_step=0.0)
    instance = robot_model(RobotModelConfig()).add_to(builder.plant())
    builder.plant().Finalize()
    with pytest.raises(ConfigError, match="panda_link9"):
        apply_disabled_collisions(
            builder.plant(), builder.scene_graph(), instance, [("panda_link9", "panda_hand")]
        )


def test_plant_distance_constraints_honour_the_srdf_filters():
    """An IK/trajectory-optimisation distance constraint on the plant agrees with the checker."""
    from pydrake.multibody.inverse_kinematics import MinimumDistanceLowerBoundConstraint
    from pydrake.planning import RobotDiagramBuilder

    from planning import PlanningScene

    config = config_mod.PlanningConfig()
    config.table = None
    scene = PlanningScene(config)
    rng = np.random.default_rng(0)
    lower, upper = scene.plant.GetPositionLowerLimits(), scene.plant.GetPositionUpperLimits()
    qs = [np.concatenate([rng.uniform(lower[:7], upper[:7]), [0.04, 0.04]]) for _ in range(200)]
    violations = {}
    for apply in (False, True):
        builder = RobotDiagramBuilder(time_step=0.0)
        robot = robot_model(config.model)
        instance = robot.add_to(builder.plant())
        builder.plant().Finalize()
        if apply:
            pairs = robot.disabled_pairs
            apply_disabled_collisions(builder.plant(), builder.scene_graph(), instance, pairs)
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
