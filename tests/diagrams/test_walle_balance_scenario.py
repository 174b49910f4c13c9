"""Wall-E's balance scenario: loading and checking (diagrams.walle_balance_scenario)."""

import pytest
import yaml

import diagrams.walle_balance_scenario as mut
from drake_sim.base.errors import ConfigError
from drake_sim.base.resources import config_dir

SCENARIO_FILE = config_dir() / "walle_balance.yaml"


def test_shipped_file_loads_and_says_what_the_defaults_say():
    """Every value of config/walle_balance.yaml is there, and where the schema has a default
    the file agrees with it (one place for each value), but for the follow variant's gentler
    acceleration."""
    dut = mut.load_walle_balance_scenario(SCENARIO_FILE)
    defaults = mut.WalleBalanceScenario()
    assert dut.driver == "balance" and dut.balance.controller == "lqr"
    assert dut.balance == defaults.balance
    assert dut.pitch_estimator == defaults.pitch_estimator
    assert dut.imu == defaults.imu
    assert dut.plant.time_step == defaults.plant.time_step
    assert dut.pushes == []
    assert dut.drive.max_linear_acceleration < defaults.drive.max_linear_acceleration


def test_pushes_and_overrides(tmp_path):
    path = tmp_path / "pushed.yaml"
    path.write_text(
        "driver: none\n"
        "balance: {controller: pid, pid: {max_lean: 8.0}}\n"
        "pushes: [{time: 2.0, force: [4.9, 0.0, 0.0], duration: 0.2}, {time: 5.0}]\n"
    )
    dut = mut.load_walle_balance_scenario(path, defaults=mut.WalleBalanceScenario())
    assert dut.driver == "none"
    assert dut.balance.controller == "pid" and dut.balance.pid.max_lean == 8.0
    assert dut.balance.pid.pitch_damping == mut.WalleBalanceScenario().balance.pid.pitch_damping
    assert dut.pushes[0] == mut.Push(time=2.0, force=[4.9, 0.0, 0.0], duration=0.2)
    assert dut.pushes[1].force == [0.0, 0.0, 0.0]


@pytest.mark.parametrize(
    "text, message",
    [
        ("driver: fly", "'driver'"),
        ("balance: {controller: mpc}", "balance.controller"),
        ("balance: {rate: 0.0}", "balance.rate"),
        ("balance: {lqr: {pitch_tolerance: -1.0}}", "balance.lqr.pitch_tolerance"),
        ("balance: {lqr: {integral_tolerance: -0.1}}", "balance.lqr.integral_tolerance"),
        ("pitch_estimator: {time_constant: .nan}", "time_constant"),
        ("imu: {angular_velocity_noise: -0.1}", "imu.angular_velocity_noise"),
        ("drive: {response_time: 0.0}", "drive.response_time"),
        ("start: {pitch: 95.0}", "start.pitch"),
        ("pushes: [{force: [1.0, 2.0]}]", r"pushes\[0\].force"),
        ("pushes: [{duration: 0.0}]", r"pushes\[0\]"),
        ("plant: {time_step: 0.0}", "plant.time_step"),
        ("ground: {mu_static: 0.5, mu_dynamic: 0.8}", "ground"),
        ("log_period: 0.0", "log_period"),
        ("colour: red", "colour"),
    ],
)
def test_bad_values_name_the_key(tmp_path, text, message):
    path = tmp_path / "bad.yaml"
    path.write_text(text + "\n")
    with pytest.raises(ConfigError, match=message) as info:
        mut.load_walle_balance_scenario(path)
    assert str(path) in str(info.value)


def test_zero_noise_and_no_integral_are_allowed(tmp_path):
    quiet = {
        "imu": {"angular_velocity_noise": 0.0, "angular_velocity_bias": 0.0},
        "balance": {"pid": {"pitch_integral_time": 0.0}, "lqr": {"integral_tolerance": 0.0}},
    }
    (tmp_path / "quiet.yaml").write_text(yaml.safe_dump(quiet))
    dut = mut.load_walle_balance_scenario(tmp_path / "quiet.yaml")
    assert (dut.imu.angular_velocity_noise, dut.balance.lqr.integral_tolerance) == (0.0, 0.0)
