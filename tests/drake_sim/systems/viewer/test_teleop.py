"""Keyboard teleop in Meshcat (drake_sim.systems.viewer.teleop), driving the robot through
cmd_vel."""

import msgpack
import numpy as np
import pytest
from pydrake.geometry import StartMeshcat
from pydrake.systems.analysis import Simulator

import drake_sim.systems.viewer.teleop as mut
from drake_sim.runs.flip import FlipRun
from tests.flip_helpers import default_robot, flip_scenario


@pytest.fixture(scope="module")
def meshcat():
    return StartMeshcat()


def _press(meshcat, label, times=1):
    for _ in range(times):
        meshcat._InjectWebsocketMessage(msgpack.packb({"type": "button", "name": label}))


def test_keys_set_the_command(meshcat):
    config = mut.TeleopConfig()
    dut = mut.MeshcatTeleop(meshcat=meshcat, config=config)
    simulator = Simulator(dut)
    forward, _, left, _, stop = (label for label, _, _ in mut.BUTTONS)
    _press(meshcat, forward, 3)
    _press(meshcat, left)
    simulator.AdvanceTo(0.2)
    command = dut.GetOutputPort("command").Eval(simulator.get_context())
    np.testing.assert_allclose(command, [3 * config.linear_step, config.angular_step])
    _press(meshcat, stop)
    simulator.AdvanceTo(0.4)
    np.testing.assert_array_equal(dut.GetOutputPort("command").Eval(simulator.get_context()), 0)
    dut.remove_buttons()
    assert not set(meshcat.GetButtonNames()) & {label for label, _, _ in mut.BUTTONS}


def test_teleop_drives_the_robot(meshcat):
    """Five presses of W: 0.5 m/s forward; the flip controller is off, so the robot drives
    straight on and does not flip."""
    run = FlipRun(flip_scenario(), default_robot(), meshcat=meshcat, controller="teleop")
    _press(meshcat, mut.BUTTONS[0][0], 5)
    assert run.run(2.0) == "duration", run.failure
    twist = run.diagram.GetOutputPort("odometry_twist").Eval(run.context)
    assert twist[0] == pytest.approx(0.5, abs=0.02)
    truth = run.log("true_pose").data()
    assert truth[0, -1] - truth[0, 0] > 0.5
    run.diagram.GetSubsystemByName("teleop").remove_buttons()
