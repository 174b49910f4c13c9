"""Robot models from files: the shipped descriptions (the Panda of example-robot-data; VAMP's
UR5, Fetch and Baxter) load with their group's joints, limits inside which their named states
lie, a plant that finalises and a finite tip pose; MoveIt's limit rules; the cache is hit the
second time; bad input is named."""

import logging
import math
import shutil

import numpy as np
import pytest
from pydrake.multibody.plant import AddMultibodyPlantSceneGraph
from pydrake.systems.framework import DiagramBuilder

import planning.model.robot_model as mut
from drake_sim.base.errors import ConfigError
from drake_sim.base.resources import config_dir
from drake_sim.robots.files import mesh_convert, robot_files
from planning.model.description import RobotDescription, load_robot_description
from tests.robot_helpers import MOVEIT_SRDF, make_toy_robot, vamp_robot

ROBOTS = {"panda": 7, "ur5": 6, "fetch": 8, "baxter": 14}
"""The shipped descriptions (config/robots/) and their group's joint count."""


@pytest.fixture
def toy_yaml(tmp_path):
    return make_toy_robot(tmp_path)


def robot_yaml(robot: str):
    """``config/robots/<robot>.yaml``, its VAMP files fetched first (or the test skipped)."""
    if robot != "panda":
        vamp_robot(robot)
    return config_dir() / "robots" / f"{robot}.yaml"


def plant_with(model):
    plant, _ = AddMultibodyPlantSceneGraph(DiagramBuilder(), 0.0)
    instance = model.add_to(plant)
    plant.Finalize()
    return plant, instance


def tip_position(plant, instance, model, q) -> np.ndarray:
    """The first tip's position in the world with the group at ``q``, the rest at zero."""
    context = plant.CreateDefaultContext()
    positions = plant.GetPositions(context)
    for name, value in zip(model.joint_names, q, strict=True):
        positions[plant.GetJointByName(name, instance).position_start()] = value
    plant.SetPositions(context, positions)
    tip = plant.GetBodyByName(model.tip_link, instance)
    return plant.EvalBodyPoseInWorld(context, tip).translation()


# ------------------------------------------------------------------ the shipped robots ----
@pytest.mark.parametrize("robot", ROBOTS)
def test_shipped_robot_loads(robot):
    model = mut.load_robot_model(robot_yaml(robot))
    assert model.num_joints == ROBOTS[robot] and len(set(model.joint_names)) == ROBOTS[robot]
    for array in (model.lower, model.upper, model.velocity, model.acceleration, model.jerk):
        assert array.shape == (ROBOTS[robot],)
    assert np.all(model.lower < model.upper) and np.all(model.velocity > 0)
    for name, q in model.named_states.items():
        assert np.all(model.lower <= q) and np.all(q <= model.upper), name
    assert all(link in model.tree.links for link in model.tip_links)


@pytest.mark.parametrize("robot", ROBOTS)
def test_shipped_robot_plant_and_tip(robot):
    model = mut.load_robot_model(robot_yaml(robot))
    plant, instance = plant_with(model)
    assert plant.num_positions() >= model.num_joints  # the base is welded: no free body
    assert not any(
        plant.get_body(b).is_floating_base_body() for b in plant.GetBodyIndices(instance)
    )
    states = dict(model.named_states) or {"middle": (model.lower + model.upper) / 2}
    for name, q in states.items():
        assert np.all(np.isfinite(tip_position(plant, instance, model, q))), name


def test_shipped_robot_details():
    panda = mut.load_robot_model(robot_yaml("panda"))
    assert panda.joint_names == [f"panda_joint{i}" for i in range(1, 8)]
    assert (
        panda.tip_link == "panda_hand_tcp"
        and ("panda_hand", "panda_leftfinger") in panda.disabled_pairs
    )
    baxter = mut.load_robot_model(robot_yaml("baxter"))
    assert baxter.tip_links == ["left_gripper", "right_gripper"]
    assert set(baxter.named_states) == {"both_ready", "both_neutral"}
    ur5 = mut.load_robot_model(robot_yaml("ur5"))
    assert ur5.tip_link == "ee_link" and set(ur5.named_states) == {"home"}
    fetch = mut.load_robot_model(robot_yaml("fetch"))
    assert fetch.joint_names[0] == "torso_lift_joint" and fetch.tip_link == "wrist_roll_link"


@pytest.mark.parametrize("robot", ["ur5", "panda"])
def test_a_second_load_hits_the_cache(robot, monkeypatch):
    first = mut.load_robot_model(robot_yaml(robot)).drake_urdf()
    stamp = first.stat().st_mtime_ns

    def no_conversion(*args, **kwargs):
        raise AssertionError("converted again")

    monkeypatch.setattr(mesh_convert, "convert_mesh", no_conversion)
    model = mut.load_robot_model(robot_yaml(robot))
    assert model.drake_urdf() == first and first.stat().st_mtime_ns == stamp
    plant_with(model)


def test_drake_noise_is_logged_at_debug_level(caplog):
    folder = vamp_robot("panda")  # inertias Drake finds unphysical, mimic on fixed joints
    description = RobotDescription(
        urdf="package://vamp_resources/panda/panda.urdf",
        srdf="package://vamp_resources/panda/panda.srdf",
        package_paths={"meshes": str(folder / "meshes")},
        group="panda_arm",
        source=str(folder / "vamp_panda.yaml"),
    )
    model = mut.load_robot_model(description)
    assert model.num_joints == 7 and set(model.named_states) == {"ready", "extended", "transport"}
    with caplog.at_level(logging.DEBUG):
        plant_with(model)
    assert not [r for r in caplog.records if r.name == "drake" and r.levelno >= logging.WARNING]
    assert any("inertia" in r.getMessage() for r in caplog.records if r.name == mut.__name__)


# ------------------------------------------------------------------ MoveIt's rules ----
def test_toy_limits_follow_moveit(toy_yaml, caplog):
    with caplog.at_level(logging.WARNING):
        model = mut.load_robot_model(toy_yaml)
    assert model.joint_names == ["j1", "j2", "j3"]
    np.testing.assert_allclose(model.lower, [-1.5, 0.05, -math.pi])  # soft limit, yaml, continuous
    np.testing.assert_allclose(model.upper, [1.8, 0.15, math.pi])
    np.testing.assert_array_equal(model.continuous, [False, False, True])
    np.testing.assert_allclose(model.velocity, [0.75, 0.5, 3.0])  # yaml, URDF, URDF
    np.testing.assert_allclose(model.acceleration, [2.0, np.inf, np.inf])
    np.testing.assert_allclose(model.jerk, [np.inf] * 3)
    assert list(model.named_states) == ["home"]
    np.testing.assert_allclose(model.named_states["home"], [0.5, 0.1, 3.0])
    assert model.tip_links == ["tool"] and model.disabled_pairs == [("base", "link1")]
    text = caplog.text
    assert "partial" in text and "ghost" in text  # a state without every joint; an unknown joint


def test_toy_plant(toy_yaml):
    model = mut.load_robot_model(toy_yaml)
    plant, instance = plant_with(model)
    assert plant.num_positions() == 3
    p = tip_position(plant, instance, model, [0.0, 0.1, 0.0])
    np.testing.assert_allclose(p, [0.1, 0.0, 0.55], atol=1e-12)  # 3 x 0.1 up, tool 0.25, j2 0.1


def test_group_given_replaces_the_files(toy_yaml):
    model = mut.load_robot_model(toy_yaml, group="first")
    assert model.group == "first" and model.joint_names == ["j1"] and model.tip_links == ["link1"]


@pytest.mark.skipif(not MOVEIT_SRDF.is_dir(), reason=f"no real MoveIt files at {MOVEIT_SRDF}")
def test_moveit_srdf_xacro_on_the_example_robot_data_panda(tmp_path, caplog):
    config = tmp_path / "moveit_resources_panda_moveit_config" / "config"
    config.mkdir(parents=True)
    for name in ("panda_arm_hand.srdf.xacro", "panda_arm.xacro", "hand.xacro"):
        shutil.copy(MOVEIT_SRDF / name, config / name)
    description = tmp_path / "panda.yaml"
    description.write_text(
        "urdf: package://example-robot-data/robots/panda_description/urdf/panda.urdf\n"
        "srdf: moveit_resources_panda_moveit_config/config/panda_arm_hand.srdf.xacro\n"
        "package_paths:\n"
        "  moveit_resources_panda_moveit_config: moveit_resources_panda_moveit_config\n"
        "group: panda_arm\n"
    )
    with caplog.at_level(logging.WARNING):
        model = mut.load_robot_model(description)
    assert model.num_joints == 7 and set(model.named_states) == {"ready", "extended", "transport"}
    assert model.tip_link == "panda_link8"
    for name in ("ready", "transport"):
        q = model.named_states[name]
        assert np.all(model.lower <= q) and np.all(q <= model.upper), name
    # MoveIt's "extended" stretches joint 4 to 0, past the Franka URDF's upper limit: kept, named.
    assert model.named_states["extended"][3] == 0.0 > model.upper[3]
    assert "extended (panda_joint4" in caplog.text


def test_a_moveit_config_folder(tmp_path):
    folder = tmp_path / "panda_moveit_config"
    (folder / "config").mkdir(parents=True)
    (folder / "package.xml").write_text("<package><name>panda_moveit_config</name></package>")
    (folder / ".setup_assistant").write_text(
        "moveit_setup_assistant_config:\n"
        "  URDF:\n"
        "    package: example-robot-data\n"
        "    relative_path: robots/panda_description/urdf/panda.urdf\n"
    )
    srdf = load_robot_description(config_dir() / "robots" / "panda.yaml").srdf
    shutil.copy(mut.robot_files.resolve_uri(srdf, tmp_path), folder / "config" / "panda.srdf")
    (folder / "config" / "joint_limits.yaml").write_text(
        "joint_limits:\n  panda_joint1: {has_velocity_limits: true, max_velocity: 1.0}\n"
    )
    model = mut.load_robot_model(folder, group="arm")
    assert model.num_joints == 7 and model.velocity[0] == 1.0


# ----------------------------------------------------------------------- bad input ----
def test_an_unknown_group_names_the_known_ones(toy_yaml):
    with pytest.raises(ConfigError, match="'nope'") as info:
        mut.load_robot_model(toy_yaml, group="nope")
    assert "arm" in str(info.value) and "first" in str(info.value)


def test_an_unknown_package_names_it_and_the_known_ones(toy_yaml):
    toy_yaml.write_text(
        toy_yaml.read_text().replace("urdf: toy_description/", "urdf: package://nowhere/")
    )
    with pytest.raises(ConfigError, match="'nowhere'") as info:
        mut.load_robot_model(toy_yaml)
    message = str(info.value)
    assert "toy_description" in message and "example-robot-data" in message


def test_a_missing_mesh_fails_at_load(toy_yaml):
    missing = toy_yaml.parent / "toy_description" / "meshes" / "link2.stl"
    missing.unlink()
    with pytest.raises(ConfigError, match="link2") as info:
        mut.load_robot_model(toy_yaml)
    assert str(missing) in str(info.value)


def test_a_group_with_no_active_joint_is_refused(toy_yaml):
    srdf = toy_yaml.parent / "toy_description" / "srdf" / "toy.srdf"
    srdf.write_text(
        srdf.read_text().replace(
            '<group name="first"><joint name="j1"/></group>',
            '<group name="first"><link name="base"/></group>',
        )
    )
    with pytest.raises(ConfigError, match="no active joints"):
        mut.load_robot_model(toy_yaml, group="first")


def test_a_description_without_a_group_plans_for_the_end_effectors_parent_group(tmp_path):
    """xArm7 from example-robot-data, named by its files only: the SRDF's default group."""
    robots = robot_files.resolve_package("example-robot-data") / "robots" / "xarm_description"
    urdf, srdf = (
        next((robots / "urdf").glob("*.urdf"), None),
        next((robots / "srdf").glob("*.srdf"), None),
    )
    if urdf is None or srdf is None:
        pytest.skip(f"example-robot-data has no xArm URDF and SRDF under {robots}")
    (tmp_path / "xarm.yaml").write_text(f"urdf: {urdf}\nsrdf: {srdf}\n")
    model = mut.load_robot_model(tmp_path / "xarm.yaml")
    assert model.group == "xarm7" and model.num_joints == 7
    assert all(np.all((q >= model.lower) & (q <= model.upper)) for q in model.named_states.values())
