import math

import pytest

import diagrams.mapping_scenario as mut
from drake_sim.base.config import load_checked
from drake_sim.base.errors import ConfigError


def test_the_shipped_scenario_loads_and_names_files_that_exist():
    scenario = load(mut.MappingScenario, mut.check_mapping_scenario, mut.default_scenario_file())
    assert mut.config_path(scenario.arena).is_file()
    assert scenario.lidar.samples == 360 and scenario.lidar.rate == 5.0
    assert scenario.plant.time_step > 0


def test_defaults_are_valid_and_paths_resolve(tmp_path):
    assert mut.check_mapping_scenario(mut.MappingScenario())
    assert mut.config_path(str(tmp_path)) == tmp_path
    assert mut.config_path("arenas/room.yaml").parent.name == "arenas"


@pytest.mark.parametrize(
    "text, needle",
    [
        ("colour: red\n", "colour"),
        ("lidar: {samples: 0}\n", "samples"),
        ("lidar: {range_min: 5.0}\n", "range"),
        ("odometry: {rate: -1}\n", "odometry.rate"),
        ("route_follower: {speed: .nan}\n", "speed"),
        ("plant: {time_step: 0.0}\n", "time_step"),
        ("log_period: 0\n", "log_period"),
        ("drive_rate: .inf\n", "drive_rate"),
        ("random_seed: -3\n", "random_seed"),
        ("slam: {resolution: -0.05}\n", "resolution"),
        ("[1, 2\n", "scenario"),
    ],
)
def test_bad_values_name_the_file_and_key(tmp_path, text, needle):
    path = tmp_path / "scenario.yaml"
    path.write_text(text)
    with pytest.raises(ConfigError, match=needle) as raised:
        load(mut.MappingScenario, mut.check_mapping_scenario, path)
    assert "scenario.yaml" in str(raised.value)
    assert "\n" not in str(raised.value).strip()


def test_duration_keys_must_be_positive():
    scenario = mut.MappingScenario(duration_factor=math.nan)
    with pytest.raises(ConfigError, match="duration_factor"):
        mut.check_mapping_scenario(scenario)


def load(schema, check, filename):
    """The scenario file, as the app's recipe loads it (``load_checked``)."""
    return load_checked(schema, filename, check, what="scenario file")
