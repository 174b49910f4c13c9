"""planning.plan_plot: a PNG of any robot's plan (its own joint count and names), with the
Panda's position limits drawn for a Panda plan."""

import numpy as np
import pytest

from planning.plan import Plan
from planning.plan_plot import _panda_position_limits, plot_plan

pytest.importorskip("matplotlib")


def test_a_three_joint_plan_is_plotted(tmp_path):
    plan = Plan(
        waypoints=np.array([[0.0, 0.0, 0.0], [0.5, -0.2, 0.1]]),
        max_velocity=np.ones(3),
        max_acceleration=np.ones(3),
        finger_positions=np.zeros(0),
        robot={"name": "toy", "group": "arm", "joints": ["a", "b", "c"], "fingers": []},
    )
    path = tmp_path / "toy.png"
    plot_plan(plan, path, position_limits=(-np.ones(3), np.ones(3)))
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_the_panda_limits_are_its_description_s():
    lower, upper = _panda_position_limits()
    assert lower.shape == upper.shape == (7,)
    assert lower[3] == pytest.approx(-3.0718) and upper[0] == pytest.approx(2.8973)
