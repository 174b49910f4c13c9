"""Wall-E's course scenario: loading and checking (diagrams.walle_scenario)."""

import pytest

import diagrams.walle_scenario as mut
from drake_sim.base.config import load_checked
from drake_sim.base.errors import ConfigError
from drake_sim.base.resources import config_dir


def test_shipped_file_loads_and_says_what_the_defaults_say():
    dut = load(mut.WalleScenario, mut.check_walle_scenario, mut.default_scenario_file())
    defaults = mut.WalleScenario()
    assert dut.mode == "both" and dut.controller == "lqr"
    assert dut.camera == defaults.camera
    assert dut.line_detector == defaults.line_detector
    assert dut.line_follower == defaults.line_follower
    assert dut.walle.imu == defaults.walle.imu
    assert dut.walle.pushes == []
    assert (dut.duration, dut.finish_margin) == (defaults.duration, defaults.finish_margin)
    assert mut.course_path(dut) == config_dir() / "courses" / "oval.yaml"
    assert mut.course_path(dut).is_file()


def test_nested_robot_scenario_and_absolute_course(tmp_path):
    path = tmp_path / "s.yaml"
    course = tmp_path / "c.yaml"
    path.write_text(
        f"mode: follow\ncourse: {course}\ncontroller: pid\n"
        "walle: {pushes: [{time: 1.0, force: [2.0, 0.0, 0.0]}], random_seed: 7}\n"
        "line_follower: {speed: 0.2}\n"
    )
    dut = load(mut.WalleScenario, mut.check_walle_scenario, path)
    assert dut.mode == "follow" and dut.controller == "pid"
    assert dut.walle.pushes[0].force == [2.0, 0.0, 0.0] and dut.walle.random_seed == 7
    assert dut.line_follower.speed == 0.2
    assert dut.line_follower.min_speed == mut.WalleScenario().line_follower.min_speed
    assert mut.course_path(dut) == course


@pytest.mark.parametrize(
    "text, message",
    [
        ("mode: fly\n", "'mode' must be one of"),
        ("controller: mpc\n", "'controller' must be one of"),
        ("duration: -1.0\n", "'duration' must be finite"),
        ("finish_margin: .nan\n", "'finish_margin' must be finite"),
        ("camera: {fov_y: 200.0}\n", "fov_y"),
        ("line_follower: {speed: 0.0}\n", "'speed' must be positive"),
        ("line_detector: {gate: .nan}\n", "'line_detector.gate' must be finite"),
        ("walle: {imu: {rate: -1.0}}\n", "'imu.rate'"),
        ("cam: {}\n", "unknown key 'cam'"),
    ],
)
def test_bad_values_name_the_key(tmp_path, text, message):
    path = tmp_path / "bad.yaml"
    path.write_text(text)
    with pytest.raises(ConfigError, match=message.replace(".", r"\.")):
        load(mut.WalleScenario, mut.check_walle_scenario, path)


def load(schema, check, filename):
    """The scenario file, as the app's recipe loads it (``load_checked``)."""
    return load_checked(schema, filename, check, what="scenario file")
