"""The timed-elastic-band local planner: its settings, its band round an obstacle (clear of it,
non-holonomic, within the limits), its command, and the fallback when no band is feasible."""

import math

import numpy as np
import pytest

from drake_sim.base.errors import ConfigError
from drake_sim.navigation import local_planner as lp
from drake_sim.navigation import teb_planner as mut
from tests.drake_sim.navigation.test_local_planner import _room


def _dut(**teb) -> mut.TebPlanner:
    return mut.TebPlanner(lp.DwaConfig(), mut.TebConfig(**teb))


@pytest.mark.parametrize(
    "key, value, rule",
    [("dt_ref", 0.0, "> 0"), ("weight_obstacle", -1.0, ">= 0"), ("max_poses", 2, "an integer >= 3"),
     ("min_obstacle_dist", math.nan, "> 0"), ("weight_optimaltime", True, ">= 0")],
)  # fmt: skip
def test_bad_settings_name_the_key(key, value, rule):
    with pytest.raises(ConfigError, match=f"'teb.{key}' must be {rule}"):
        mut.check_teb_config(mut.TebConfig(**{key: value}), "nav", prefix="teb.")


def test_the_band_bends_round_an_obstacle_next_to_the_path():
    """A path grazing a box: the optimised band keeps the robot's circle min_obstacle_dist
    clear where the path does not, turns smoothly (arcs between poses) and keeps to the
    speed limit."""
    costmap = _room([(1.7, 1.72, 2.0, 2.2)])  # the path along y = 1.5 passes 0.22 m from it
    dut = _dut()
    path = lp.densify([[1.0, 1.5], [3.0, 1.5]], 0.025)
    poses, intervals = dut._band(np.array([1.0, 1.5, 0.0]), path, costmap)
    field = mut._ClearanceField(costmap)
    problem = mut._BandProblem(poses, 0.2, 0.0, dut.config, dut.teb, field)
    before = field.clearance(poses[:, :2]).min()
    assert before < dut.teb.min_obstacle_dist  # the path itself is too close
    command = dut._optimised(np.array([1.0, 1.5, 0.0]), 0.2, 0.0, (poses, intervals), costmap)
    assert command is not None and command.status == "following"
    band = command.trajectory
    assert field.clearance(band[:, :2]).min() > 0.0
    assert field.clearance(band[:, :2]).min() > before
    step = np.diff(band, axis=0)
    c, s = np.cos(band[:, 2]), np.sin(band[:, 2])
    arc = (c[:-1] + c[1:]) * step[:, 1] - (s[:-1] + s[1:]) * step[:, 0]
    assert np.max(np.abs(arc)) < 0.01  # the non-holonomic constraint holds
    assert 0.0 < command.v <= dut.config.max_vel_x + 1e-9
    assert problem._pattern.shape[1] == 3 * (len(poses) - 2) + len(poses) - 1


def test_the_planner_follows_a_clear_path_forward():
    dut = _dut()
    path = np.array([[0.5, 2.0], [3.5, 2.0]])
    command = dut.compute([0.5, 2.0, 0.0], (0.2, 0.0), path, [3.5, 2.0, 0.0], _room())
    assert command.status == "following"
    assert command.v == pytest.approx(dut.config.max_vel_x, abs=0.03)
    assert abs(command.omega) < 0.2
    assert len(command.trajectory) >= 3  # the band is the predicted trajectory


def test_with_no_feasible_band_the_dwa_decides(monkeypatch):
    dut = _dut()
    monkeypatch.setattr(mut.TebPlanner, "_optimised", lambda *a: None)
    path = np.array([[0.5, 2.0], [3.5, 2.0]])
    command = dut.compute([0.5, 2.0, 0.0], (0.2, 0.0), path, [3.5, 2.0, 0.0], _room())
    assert command.status == "following" and command.v > 0.0  # the DWA's sampled rollout


def test_column_groups_share_no_row():
    pattern = np.array([[1, 1, 0, 0], [0, 1, 1, 0], [0, 0, 1, 1]], dtype=bool)
    groups = mut._colour(pattern)
    assert sorted(np.concatenate(groups).tolist()) == [0, 1, 2, 3]
    for group in groups:
        assert np.all(pattern[:, group].sum(axis=1) <= 1)
