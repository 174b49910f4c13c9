"""drake_sim.base.presets, and load_typed / apply_overrides meeting a preset's name or path where
a dataclass with ``PRESETS`` is expected."""

import dataclasses as dc
from typing import ClassVar

import pytest

import drake_sim.base.presets as mut
from drake_sim.base.config import apply_overrides, load_typed
from drake_sim.base.errors import ConfigError


@dc.dataclass
class Sensor:
    PRESETS: ClassVar[str] = "sensors"

    rate: float = 5.0  # Hz
    beams: int = 360
    offset: float | None = None


@dc.dataclass
class Robot:
    name: str = "r"
    sensor: Sensor = dc.field(default_factory=Sensor)
    spares: list[Sensor] = dc.field(default_factory=list)
    maybe: Sensor | None = None


@pytest.fixture
def config(tmp_path, monkeypatch):
    """A config/ folder with two sensor presets."""
    folder = tmp_path / "config" / "sensors"
    folder.mkdir(parents=True)
    (folder / "fast.yaml").write_text("rate: 20.0  # Hz\nbeams: 720\noffset: -90.0\n")
    (folder / "slow.yaml").write_text("rate: 1.0\n")
    monkeypatch.setattr(mut, "config_dir", lambda: tmp_path / "config")
    return tmp_path / "config"


def test_names_and_files(config):
    assert mut.preset_names(Sensor) == ["fast", "slow"]
    assert mut.preset_file(Sensor, "fast") == config / "sensors" / "fast.yaml"


def test_a_name_loads_the_preset(config):
    robot = load_typed(Robot, data="name: x\nsensor: fast  # a comment\n")
    assert robot == Robot(name="x", sensor=Sensor(rate=20.0, beams=720, offset=-90.0))
    quoted = load_typed(Robot, data='{sensor: "slow", name: y}')
    assert quoted == Robot(name="y", sensor=Sensor(rate=1.0))


def test_a_preset_replaces_the_whole_section(config):
    """Keys the preset leaves out get the dataclass's defaults, not the values before it."""
    before = Robot(sensor=Sensor(rate=3.0, beams=10, offset=1.0))
    assert load_typed(Robot, data="sensor: slow", defaults=before).sensor == Sensor(rate=1.0)


def test_presets_in_lists_and_optional_sections(config):
    robot = load_typed(Robot, data="spares: [slow, {rate: 2.0}, fast]\nmaybe: slow\n")
    assert robot.spares == [Sensor(rate=1.0), Sensor(rate=2.0), Sensor(20.0, 720, -90.0)]
    assert robot.maybe == Sensor(rate=1.0)
    assert load_typed(Robot, data="maybe: null").maybe is None


def test_a_path_loads_the_file(config, tmp_path, monkeypatch):
    own = tmp_path / "mine.yaml"
    own.write_text("beams: 7\n")
    assert load_typed(Robot, data=f"sensor: {own}").sensor == Sensor(beams=7)
    monkeypatch.chdir(tmp_path)  # relative: from the working directory ...
    assert load_typed(Robot, data="sensor: mine.yaml").sensor == Sensor(beams=7)
    assert load_typed(Robot, data="sensor: config/sensors/slow.yaml").sensor.rate == 1.0
    monkeypatch.chdir(config / "sensors")  # ... else from config/
    assert load_typed(Robot, data="sensor: sensors/fast.yaml").sensor.beams == 720


def test_unknown_name_names_file_key_name_and_the_known_ones(config):
    with pytest.raises(ConfigError) as info:
        load_typed(Robot, data="sensor: medium\n", where="robot.yaml")
    message = str(info.value)
    assert message.startswith("robot.yaml: 'sensor': unknown sensors preset 'medium'")
    assert "known: fast, slow" in message and "\n" not in message
    with pytest.raises(ConfigError, match=r"'spares\[1\]': unknown sensors preset 'x'"):
        load_typed(Robot, data="spares: [fast, x]")
    with pytest.raises(ConfigError, match="'sensor': no such sensors file 'no/such.yaml'"):
        load_typed(Robot, data="sensor: no/such.yaml")


def test_a_bad_preset_file_is_named(config):
    (config / "sensors" / "broken.yaml").write_text("beams: many\n")
    with pytest.raises(ConfigError, match=r"broken.yaml: 'beams' must be a number"):
        load_typed(Robot, data="sensor: broken")


def test_other_strings_are_not_presets(config):
    """Only a dataclass with PRESETS takes a name; a string field stays a string."""
    assert load_typed(Robot, data="name: fast").name == "fast"
    with pytest.raises(ConfigError, match="'sensor' must be a mapping"):
        load_typed(Robot, data="sensor: 3")


def test_overrides_name_a_preset_and_set_keys_on_top(config):
    robot = apply_overrides(Robot, Robot(), ["sensor=fast", "sensor.rate=2.5"])
    assert robot.sensor == Sensor(rate=2.5, beams=720, offset=-90.0)
    robot = apply_overrides(Robot, robot, ["sensor=slow"])
    assert robot.sensor == Sensor(rate=1.0)
    robot = apply_overrides(Robot, Robot(spares=[Sensor(), Sensor()]), ["spares[1]=fast"])
    assert robot.spares == [Sensor(), Sensor(20.0, 720, -90.0)]
    with pytest.raises(ConfigError) as info:
        apply_overrides(Robot, Robot(), ["sensor=medium"])
    assert str(info.value).startswith("--set 'sensor=medium': 'sensor': unknown sensors preset")
