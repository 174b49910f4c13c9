"""diagrams.world_scenario: ``load_scenario`` reads a typed scenario (unknown keys are errors,
missing keys keep defaults) and ``check_world_scenario`` rejects a bad world file, non-finite
poses, a continuous plant, bad friction and a negative triad length, naming the key."""

import dataclasses as dc
import math

import pytest
from pydrake.multibody.plant import MultibodyPlantConfig

import diagrams.world_scenario as mut
from diagrams.flip_scenario import FlipScenario
from drake_sim.base.errors import ConfigError
from drake_sim.base.resources import config_dir, models_dir


def write(tmp_path, text: str):
    path = tmp_path / "world.yaml"
    path.write_text(text)
    return path


def check(**changes):
    mut.check_world_scenario(dc.replace(mut.WorldScenario(), **changes), "w.yaml")


def test_defaults_are_valid():
    dut = mut.WorldScenario()
    assert dut.world == "package://drake_sim_models/worlds/ddrive.world.sdf"
    assert dut.ground.mu_dynamic <= dut.ground.mu_static
    assert dut.robot_pose == mut.PlanarPose(0.0, 0.0, 0.0, upside_down=False)
    assert dut.plant.time_step > 0
    mut.check_world_scenario(dut)


def test_load_scenario_reads_values_and_keeps_defaults(tmp_path):
    path = write(
        tmp_path,
        "world: ''\nrobot_pose: {x: 1.5, yaw: 0.3, upside_down: true}\n"
        "ground: {mu_static: 0.6, mu_dynamic: 0.5}\nplant: {time_step: 0.004}\n",
    )
    dut = mut.load_scenario(path)
    assert dut.world == ""
    assert dut.robot_pose == mut.PlanarPose(x=1.5, y=0.0, yaw=0.3, upside_down=True)
    assert dut.ground == mut.GroundConfig(mu_static=0.6, mu_dynamic=0.5)
    assert dut.plant.time_step == 0.004
    assert dut.plant.contact_model == "point"  # the schema's default, kept
    assert dut.frame_triad_length == 0.15 and dut.random_seed == 0


def test_load_scenario_defaults_and_schema(tmp_path):
    base = mut.WorldScenario(world="", random_seed=7)
    dut = mut.load_scenario(write(tmp_path, "frame_triad_length: 0.0\n"), defaults=base)
    assert (dut.world, dut.random_seed, dut.frame_triad_length) == ("", 7, 0.0)
    view = mut.load_scenario(config_dir() / "view.yaml", FlipScenario, check=False)
    assert isinstance(view, FlipScenario) and view.scene.frame_triad_length == 0.15


@pytest.mark.parametrize(
    "text, match",
    [
        ("wrld: ''", "unknown key 'wrld'"),
        ("ground: {mu: 1}", "unknown key 'ground.mu'"),
        ("robot_pose: {x: .nan}", "'robot_pose.x' must be finite"),
        ("world: package://drake_sim_models/worlds/none.sdf", "'world' file not found"),
        ("world: package://elsewhere/a.sdf", "'world': unknown package"),
        ("ground: {mu_static: 0.5, mu_dynamic: 0.7}", "'ground.mu_dynamic' must not exceed"),
        ("plant: {time_step: 0}", "'plant.time_step' must be > 0"),
        ("frame_triad_length: -0.1", "'frame_triad_length' must be finite and >= 0"),
        ("robot_pose: [", "malformed YAML"),
    ],
)
def test_load_scenario_rejects_bad_files(tmp_path, text, match):
    path = write(tmp_path, text)
    with pytest.raises(ConfigError, match=match) as info:
        mut.load_scenario(path)
    assert str(info.value).startswith(str(path))


def test_missing_file_and_unchecked_load(tmp_path):
    with pytest.raises(ConfigError, match="no such scenario file"):
        mut.load_scenario(tmp_path / "missing.yaml")
    dut = mut.load_scenario(write(tmp_path, "world: gone.sdf\n"), check=False)
    assert dut.world == "gone.sdf"


def test_world_may_be_a_plain_path_or_empty(tmp_path):
    check(world=str(models_dir() / "worlds" / "ddrive.world.sdf"))
    check(world="")
    with pytest.raises(ConfigError, match="^w.yaml: 'world' file not found"):
        check(world=str(tmp_path))  # a folder is not a world file


@pytest.mark.parametrize("key", ["x", "y", "yaw"])
@pytest.mark.parametrize("value", [math.nan, math.inf, -math.inf])
def test_non_finite_pose(key, value):
    with pytest.raises(ConfigError, match=f"^w.yaml: 'robot_pose.{key}' must be finite"):
        check(robot_pose=dc.replace(mut.PlanarPose(), **{key: value}))


@pytest.mark.parametrize(
    "ground",
    [
        mut.GroundConfig(mu_static=math.nan, mu_dynamic=0.5),
        mut.GroundConfig(mu_static=math.inf, mu_dynamic=0.5),
        mut.GroundConfig(mu_static=0.9, mu_dynamic=-0.1),
    ],
)
def test_bad_friction(ground):
    with pytest.raises(ConfigError, match="'ground' friction must be finite and >= 0"):
        check(ground=ground)


def test_dynamic_friction_may_equal_but_not_exceed_static():
    check(ground=mut.GroundConfig(mu_static=0.7, mu_dynamic=0.7))
    check(ground=mut.GroundConfig(mu_static=0.0, mu_dynamic=0.0))
    with pytest.raises(ConfigError, match="'ground.mu_dynamic' must not exceed 'ground.mu_stat"):
        check(ground=mut.GroundConfig(mu_static=0.7, mu_dynamic=0.71))


def test_continuous_plant_and_bad_triads():
    with pytest.raises(ConfigError, match="'plant.time_step' must be > 0"):
        check(plant=MultibodyPlantConfig(time_step=0.0))
    for length in (math.nan, -1.0):
        with pytest.raises(ConfigError, match="'frame_triad_length'"):
            check(frame_triad_length=length)
    check(frame_triad_length=0.0)
