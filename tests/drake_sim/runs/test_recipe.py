"""An app described once (drake_sim.runs.recipe): the one loader (files, ``robot.`` and
scenario overrides, the seed at the recipe's one seed key, the checks), flags as overrides, and
``start`` (load and make the run in one call). A toy app with two small schemas stands in for
the real ones, whose recipes are tested beside their runs."""

import argparse
import dataclasses as dc
from pathlib import Path

import pytest

import drake_sim.runs.recipe as mut
from drake_sim.base.errors import ConfigError


@dc.dataclass
class Robot:
    mass: float = 1.0  # kg
    wheels: int = 2


@dc.dataclass
class Noise:
    sigma: float = 0.1
    random_seed: int = 0


@dc.dataclass
class Scenario:
    speed: float = 0.5  # m/s
    noise: Noise = dc.field(default_factory=Noise)


def check_robot(robot: Robot, where: str) -> Robot:
    if robot.mass <= 0:
        raise ConfigError(f"{where}: 'mass' must be > 0, got {robot.mass}")
    return robot


def check_scenario(scenario: Scenario, where: str) -> Scenario:
    if scenario.speed < 0:
        raise ConfigError(f"{where}: 'speed' must be >= 0, got {scenario.speed}")
    return scenario


@pytest.fixture
def app(tmp_path):
    """The toy app, its default files in ``tmp_path`` and a ``make_run`` that keeps its
    arguments."""
    robot_file, scenario_file = tmp_path / "robot.yaml", tmp_path / "scenario.yaml"
    robot_file.write_text("mass: 2.0\n")
    scenario_file.write_text("speed: 0.8\nnoise: {random_seed: 7}\n")

    def make_run(inputs, options, *, meshcat=None, realtime=False):
        return {"inputs": inputs, "options": options, "meshcat": meshcat, "realtime": realtime}

    return mut.AppRecipe(
        name="toy",
        robot=mut.InputFile(Robot, lambda: robot_file, check_robot, what="robot file"),
        scenario=mut.InputFile(Scenario, lambda: scenario_file, check_scenario),
        seed_key="noise.random_seed",
        make_run=make_run,
    )


def test_the_default_files_and_the_scenario_s_own_seed(app):
    inputs = mut.load_inputs(app)
    assert inputs.robot == Robot(mass=2.0)
    assert inputs.scenario == Scenario(speed=0.8, noise=Noise(random_seed=7))
    assert inputs.seed == 7
    assert app.load() == inputs


def test_files_given_replace_the_defaults(app, tmp_path):
    other = tmp_path / "other.yaml"
    other.write_text("speed: 0.1\n")
    inputs = app.load(scenario=other, robot=str(tmp_path / "robot.yaml"))
    assert inputs.scenario.speed == 0.1 and inputs.seed == 0  # the schema's own seed


def test_robot_overrides_go_to_the_robot_file(app):
    inputs = app.load(overrides=["robot.mass=3.5", "speed=0.2", "noise.sigma=0.3"])
    assert inputs.robot == Robot(mass=3.5)
    assert inputs.scenario.speed == 0.2 and inputs.scenario.noise.sigma == 0.3


def test_without_a_robot_file_every_override_is_the_scenario_s(app):
    bare = dc.replace(app, robot=None)
    inputs = bare.load(overrides=["speed=0.3"])
    assert inputs.robot is None and inputs.scenario.speed == 0.3
    with pytest.raises(ConfigError, match="unknown key 'robot'"):  # not a scenario key
        bare.load(overrides=["robot.mass=3.5"])


def test_the_seed_lands_at_the_seed_key_and_in_the_inputs(app):
    inputs = app.load(seed=12, overrides=["noise.random_seed=3"])
    assert inputs.seed == 12 and inputs.scenario.noise.random_seed == 12  # --seed wins
    assert app.load(overrides=["noise.random_seed=3"]).seed == 3


@pytest.mark.parametrize(
    "overrides, match",
    [
        (["speed=-1"], "--set: 'speed' must be >= 0"),
        (["robot.mass=0"], r"--set \(robot file\): 'mass' must be > 0"),
        (["sped=1"], "unknown key 'sped'"),
        (["robot.legs=4"], "unknown key 'legs'"),
        (["noise.sigma=fast"], "'noise.sigma' must be a number"),
        (["speed"], "'speed': expected KEY=VALUE"),
    ],
)
def test_a_bad_override_is_a_config_error_naming_the_key(app, overrides, match):
    with pytest.raises(ConfigError, match=match):
        app.load(overrides=overrides)


def test_a_bad_file_is_a_config_error_naming_it(app, tmp_path):
    bad = tmp_path / "bad.yaml"
    bad.write_text("speed: -2\n")
    with pytest.raises(ConfigError, match=f"{bad}: 'speed' must be >= 0"):
        app.load(scenario=bad)


def test_split_overrides():
    robot, scenario = mut.split_overrides(["robot.a=1", "b=2", "robotic=3", "robot.c.d=4"])
    assert robot == ["a=1", "c.d=4"] and scenario == ["b=2", "robotic=3"]


def test_a_loader_of_its_own_gets_the_overrides_and_the_loader_keywords(app, tmp_path):
    calls = []

    def load_overridden(path, overrides, **loader):
        calls.append((path, overrides, loader))
        return Scenario(noise=Noise(random_seed=int(overrides[-1].split("=")[1])))

    recipe = dc.replace(
        app, robot=None, scenario=dc.replace(app.scenario, load_overridden=load_overridden)
    )
    inputs = recipe.load(overrides=["speed=1"], seed=4, scene=tmp_path / "scene.yaml")
    assert inputs.seed == 4
    ((path, overrides, loader),) = calls
    assert path == tmp_path / "scenario.yaml"
    assert overrides == ["speed=1", "noise.random_seed=4"]
    assert loader == {"scene": tmp_path / "scene.yaml"}


def test_flag_override_and_dest():
    flag = mut.Flag("--route-file", "route")
    assert flag.dest == "route_file"
    assert mut.Flag("--mode", "mode").override("both") == ("--mode both", 'mode="both"')
    assert mut.Flag("--n", "n").override(3) == ("--n 3", "n=3")
    label, relative = flag.override(Path("routes/room.yaml"))
    assert label == "--route-file routes/room.yaml"
    assert relative == f'route="{Path("routes/room.yaml").absolute()}"'
    assert Path(relative.split("=", 1)[1].strip('"')).is_absolute()


def test_option_reads_a_namespace_or_a_dict():
    assert mut.option({"teleop": True}, "teleop") is True
    assert mut.option(argparse.Namespace(teleop=True), "teleop") is True
    assert mut.option({}, "out", "maps") == "maps"
    assert mut.option(argparse.Namespace(), "out") is None


def test_start_loads_and_makes_the_run_in_one_call(app):
    run = app.start(seed=5, overrides=["speed=0.4"], meshcat="page", realtime=True, teleop=True)
    assert run["inputs"] == app.load(seed=5, overrides=["speed=0.4"])
    assert run["options"] == {"teleop": True}
    assert run["meshcat"] == "page" and run["realtime"] is True
