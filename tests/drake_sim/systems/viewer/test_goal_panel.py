import math

import msgpack
import pytest
from pydrake.geometry import Meshcat

import drake_sim.systems.viewer.goal_panel as mut


@pytest.fixture(scope="module")
def meshcat():
    return Meshcat()


def test_presses_come_back_once_with_the_slider_pose(meshcat):
    dut = mut.GoalPanel(meshcat=meshcat, lower=(-3, -2), upper=(3, 2), start=(-2.0, -1.5, 0.5))
    assert dut.pose() == pytest.approx([-2.0, -1.5, math.radians(30.0)], abs=0.05)
    assert dut.poll() == []
    meshcat.SetSliderValue("x (m)", 1.0)
    meshcat.SetSliderValue("yaw (deg)", 90.0)
    for name in (mut.SEND_GOAL, mut.GLOBAL):
        meshcat._InjectWebsocketMessage(msgpack.packb({"type": "button", "name": name}))
    actions = dut.poll()
    assert [a for a, _ in actions] == ["goal", "global"]
    assert actions[0][1] == pytest.approx([1.0, -1.5, math.pi / 2])
    assert actions[1][1] is None
    assert dut.poll() == []
    dut.remove()
    with pytest.raises(RuntimeError):
        meshcat.GetSliderValue("x (m)")
