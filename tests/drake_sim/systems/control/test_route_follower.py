import math

import numpy as np
import pytest
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import BasicVector, DiagramBuilder, LeafSystem

from drake_sim.base.errors import ConfigError
from drake_sim.systems.control import route_follower as mut


class Unicycle(LeafSystem):
    """A kinematic unicycle integrating ``[v, omega]`` at 100 Hz."""

    def __init__(self, pose):
        super().__init__()
        self._command = self.DeclareVectorInputPort("command", 2)
        state = self.DeclareDiscreteState(BasicVector(np.asarray(pose, dtype=float)))
        self.DeclarePeriodicDiscreteUpdateEvent(0.01, 0.0, self._step)
        self.DeclareStateOutputPort("pose", state)

    def _step(self, context, discrete_state):
        x, y, yaw = context.get_discrete_state_vector().value()
        v, omega = self._command.Eval(context)
        discrete_state.set_value(
            [x + 0.01 * v * math.cos(yaw), y + 0.01 * v * math.sin(yaw), yaw + 0.01 * omega]
        )


def _drive(waypoints, start, duration, config=None):
    builder = DiagramBuilder()
    robot = builder.AddSystem(Unicycle(start))
    dut = builder.AddSystem(
        mut.RouteFollower(waypoints=waypoints, config=config or mut.RouteFollowerConfig())
    )
    builder.Connect(robot.get_output_port(), dut.get_input_port())
    builder.Connect(dut.GetOutputPort("command"), robot.get_input_port())
    diagram = builder.Build()
    simulator = Simulator(diagram)
    poses = []
    for t in np.arange(0.1, duration, 0.1):
        simulator.AdvanceTo(t)
        poses.append(
            robot.get_output_port().Eval(robot.GetMyContextFromRoot(simulator.get_context()))
        )
    context = dut.GetMyContextFromRoot(simulator.get_context())
    return np.array(poses), dut, context


def test_drives_through_every_waypoint_in_order_and_stops():
    waypoints = [[1.0, 0.0], [1.0, 1.0], [-0.5, 1.0]]
    poses, dut, context = _drive(waypoints, [0.0, 0.0, 0.0], 40.0)
    assert dut.GetOutputPort("done").Eval(context)[0] == 1.0
    assert np.allclose(dut.GetOutputPort("command").Eval(context), 0.0)
    assert np.hypot(*(poses[-1, :2] - waypoints[-1])) < 0.06
    for waypoint in waypoints:  # passed close to each
        assert np.min(np.hypot(*(poses[:, :2] - waypoint).T)) < 0.06
    # Straight legs: never further off the segments than a waypoint's tolerance and a bit.
    legs = np.array([[0.0, 0.0], *waypoints])
    for pose in poses:
        distances = [
            _segment_distance(pose[:2], a, b) for a, b in zip(legs[:-1], legs[1:], strict=True)
        ]
        assert min(distances) < 0.06  # the tolerance at a waypoint, then straight


def _segment_distance(p, a, b):
    t = np.clip(np.dot(p - a, b - a) / np.dot(b - a, b - a), 0.0, 1.0)
    return float(np.hypot(*(p - (a + t * (b - a)))))


def test_turns_on_the_spot_when_the_heading_is_far_off():
    config = mut.RouteFollowerConfig()
    v, omega, turning = mut.route_command([0, 0, 0], [-1.0, 0.1], False, config)
    assert v == 0.0 and turning and omega == pytest.approx(config.turn_rate)
    v, omega, turning = mut.route_command([0, 0, 0], [1.0, 0.0], False, config)
    assert v == pytest.approx(config.speed) and omega == 0.0 and not turning
    # Hysteresis: a small error while turning keeps turning until it is a third of the limit.
    error = 0.5 * config.turn_in_place
    _, _, turning = mut.route_command([0, 0, 0], [math.cos(error), math.sin(error)], True, config)
    assert turning
    # Slows down near the waypoint.
    v, _, _ = mut.route_command([0, 0, 0], [0.05, 0.0], False, config)
    assert v == pytest.approx(0.05)


def test_an_empty_route_is_done_at_once():
    _, dut, context = _drive([], [0.0, 0.0, 0.0], 0.3)
    assert dut.GetOutputPort("done").Eval(context)[0] == 1.0
    assert dut.waypoint_index(context) == 0


@pytest.mark.parametrize("key", ["speed", "rate", "tolerance", "turn_in_place"])
@pytest.mark.parametrize("value", [0.0, -1.0, math.nan, math.inf])
def test_bad_config_values_are_rejected(key, value):
    config = mut.RouteFollowerConfig(**{key: value})
    with pytest.raises(ConfigError, match=key):
        mut.check_route_follower_config(config)
    assert mut.check_route_follower_config(mut.RouteFollowerConfig())
