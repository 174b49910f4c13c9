"""diagrams.flip_scenario: the shipped config/flip.yaml loads, and unknown keys, non-finite and
out-of-range values are ConfigErrors naming the file and the key."""

import dataclasses as dc
import math

import pytest

import diagrams.flip_scenario as mut
from drake_sim.base.errors import ConfigError
from drake_sim.base.resources import config_dir

SHIPPED = config_dir() / "flip.yaml"


def write(tmp_path, text: str):
    path = tmp_path / "flip.yaml"
    path.write_text(text)
    return path


def test_shipped_scenario_loads():
    dut = mut.load_flip_scenario(SHIPPED)
    assert isinstance(dut, mut.FlipScenario)
    assert dut.scene.world == "package://drake_sim_models/worlds/ddrive.world.sdf"
    assert (dut.scene.robot_pose.x, dut.scene.robot_pose.y) == (-3.0, 0.0)
    assert dut.scene.plant.time_step == 0.01
    assert dut.imu.rate == 100.0 and dut.flip.drive_speed == 0.8 and dut.drive.rate == 200.0
    assert dut.teleop.linear_step == 0.1
    assert (dut.log_period, dut.trail_period) == (0.02, 0.1)
    mut.check_flip_scenario(dut)  # and it passes the checks again


def test_shipped_view_scenario_and_defaults_load():
    dut = mut.load_flip_scenario(config_dir() / "view.yaml")
    assert dut.scene.frame_triad_length == 0.15
    assert dut.flip == mut.FlipScenario().flip  # missing sections keep the schema's defaults
    mut.check_flip_scenario(mut.FlipScenario())


def test_empty_file_keeps_every_default(tmp_path):
    dut = mut.load_flip_scenario(write(tmp_path, ""))
    default = mut.FlipScenario()
    for section in ("imu", "odometry", "flip", "drive", "teleop", "log_period", "trail_period"):
        assert getattr(dut, section) == getattr(default, section)
    assert dut.scene.world == default.scene.world and dut.scene.ground == default.scene.ground
    assert dut.scene.plant.time_step == default.scene.plant.time_step


@pytest.mark.parametrize(
    "text, key",
    [
        ("bogus: 1", "unknown key 'bogus'"),
        ("imu: {rte: 100}", "unknown key 'imu.rte'"),
        ("scene: {robot_pose: {z: 1}}", "unknown key 'scene.robot_pose.z'"),
        ("flip: {drive_speed: .nan}", "'flip.drive_speed' must be finite"),
        ("odometry: {rate: .inf}", "'odometry.rate' must be finite"),
        ("flip: {drive_speed: -0.8}", "'flip.drive_speed' must be > 0"),
        ("imu: {orientation_noise: -0.1}", "'imu.orientation_noise' must be > 0"),
        ("drive: {rate: 0}", "'drive.rate' must be > 0"),
        ("teleop: {angular_step: 0}", "'teleop.angular_step' must be > 0"),
        ("log_period: 0", "'log_period' must be finite and > 0"),
        ("trail_period: -1", "'trail_period' must be finite and > 0"),
        ("scene: {ground: {mu_static: 0.5, mu_dynamic: 0.6}}", "'ground.mu_dynamic'"),
        ("scene: {world: nowhere.sdf}", "'world' file not found: nowhere.sdf"),
    ],
)
def test_bad_values_name_the_key(tmp_path, text, key):
    path = write(tmp_path, text)
    with pytest.raises(ConfigError, match=key) as info:
        mut.load_flip_scenario(path)
    assert str(info.value).startswith(str(path))


def test_noise_bias_variance_and_integral_time_may_be_zero(tmp_path):
    text = (
        "imu: {orientation_noise: 0, angular_velocity_bias: 0}\n"
        "odometry: {yaw_variance: 0}\n"
        "drive: {integral_time: 0}\n"
    )
    dut = mut.load_flip_scenario(write(tmp_path, text))
    assert dut.imu.orientation_noise == 0 and dut.imu.angular_velocity_bias == 0
    assert dut.odometry.yaw_variance == 0 and dut.drive.integral_time == 0


@pytest.mark.parametrize(
    "section, field",
    [("imu", "rate"), ("odometry", "grip_time"), ("flip", "flip_timeout"), ("drive", "rate")],
)
def test_check_rejects_non_finite_values_set_in_code(section, field):
    for value in (math.nan, math.inf):
        block = dc.replace(getattr(mut.FlipScenario(), section), **{field: value})
        dut = dc.replace(mut.FlipScenario(), **{section: block})
        with pytest.raises(ConfigError, match=f"^mine: '{section}.{field}' must be finite"):
            mut.check_flip_scenario(dut, "mine")


def test_check_covers_the_scene_and_the_periods():
    scene = dc.replace(mut.FlipScenario().scene, frame_triad_length=-1.0)
    with pytest.raises(ConfigError, match="'frame_triad_length'"):
        mut.check_flip_scenario(mut.FlipScenario(scene=scene))
    with pytest.raises(ConfigError, match="'log_period' must be finite"):
        mut.check_flip_scenario(mut.FlipScenario(log_period=math.nan))
