import math

import numpy as np
import pytest

from drake_sim.base.errors import ConfigError
from drake_sim.navigation import costmap as cm
from drake_sim.navigation import recovery as mut


def _open_costmap(wall_x=None):
    """A 4 m x 4 m free costmap, with a wall (column of lethal cells) at ``wall_x`` m."""
    static = np.full((80, 80), cm.FREE_SPACE, dtype=np.uint8)
    if wall_x is not None:
        static[:, int(wall_x / 0.05)] = cm.LETHAL
    return cm.Costmap(static, 0.05, (0.0, 0.0, 0.0), cm.CostmapConfig())


def _drive(behaviour, pose, costmap, config, duration):
    """Steps ``behaviour`` at 10 Hz on an ideal unicycle; returns (final pose, steps taken)."""
    pose = np.array(pose, dtype=float)
    for step in range(round(duration * 10)):
        done, v, omega = mut.step_behaviour(behaviour, pose, 0.1 * step, costmap, config)
        if done:
            return pose, step
        pose = pose + 0.1 * np.array([v * math.cos(pose[2]), v * math.sin(pose[2]), omega])
    return pose, None


def test_rotate_turns_a_full_turn_on_the_spot_then_stops():
    config = mut.RecoveryConfig()
    behaviour = mut.start_behaviour("rotate", [2.0, 2.0, 3.0], 0.0)
    pose, steps = _drive(behaviour, [2.0, 2.0, 3.0], _open_costmap(), config, 20.0)
    assert steps is not None
    assert np.allclose(pose[:2], [2.0, 2.0])
    assert 2 * math.pi <= pose[2] - 3.0 < 2 * math.pi + 0.11
    assert behaviour.turned >= 2 * math.pi


def test_back_up_moves_back_the_distance_unless_something_is_behind():
    config = mut.RecoveryConfig()
    behaviour = mut.start_behaviour("back_up", [2.0, 2.0, 0.0], 0.0)
    pose, steps = _drive(behaviour, [2.0, 2.0, 0.0], _open_costmap(), config, 20.0)
    assert steps is not None and pose[0] == pytest.approx(2.0 - 0.15, abs=0.006)
    assert pose[1] == pytest.approx(2.0) and pose[2] == 0.0
    # A wall 0.3 m behind: backing 0.15 m would bring it within the robot's radius (0.22 m).
    behaviour = mut.start_behaviour("back_up", [2.0, 2.0, 0.0], 0.0)
    pose, steps = _drive(behaviour, [2.0, 2.0, 0.0], _open_costmap(wall_x=1.7), config, 20.0)
    assert steps is not None and pose[0] > 2.0 - 0.15 + 0.05


def test_a_robot_that_cannot_move_gives_up_after_the_time_limit():
    config = mut.RecoveryConfig()
    behaviour = mut.start_behaviour("rotate", [2.0, 2.0, 0.0], 0.0)
    limit = config.rotate_angle / config.rotate_speed + config.time_margin
    for t in np.arange(0.0, limit + 0.5, 0.1):
        done, _, omega = mut.step_behaviour(behaviour, [2.0, 2.0, 0.0], t, _open_costmap(), config)
        if done:
            break
    assert done and t > limit - 0.2


def test_clear_costmap_is_instantaneous_and_unknown_kinds_are_refused():
    behaviour = mut.start_behaviour("clear_costmap", [0.0, 0.0, 0.0], 1.0)
    assert mut.step_behaviour(behaviour, [0, 0, 0], 1.0, _open_costmap(), mut.RecoveryConfig()) == (
        True, 0.0, 0.0)  # fmt: skip
    with pytest.raises(ValueError, match="spin"):
        mut.start_behaviour("spin", [0.0, 0.0, 0.0], 0.0)
    assert mut.BEHAVIOURS == ("clear_costmap", "rotate", "back_up")


@pytest.mark.parametrize(
    "key, value",
    [("progress_timeout", 0.0), ("backup_speed", -0.1), ("rotate_angle", math.nan),
     ("max_recoveries", -1), ("max_recoveries", 1.5), ("time_margin", math.inf)],
)  # fmt: skip
def test_bad_config_values_are_rejected(key, value):
    with pytest.raises(ConfigError, match=f"nav.yaml: 'recovery.{key}'"):
        mut.check_recovery_config(mut.RecoveryConfig(**{key: value}), "nav.yaml", "recovery.")
    assert mut.check_recovery_config(mut.RecoveryConfig(max_recoveries=0)).max_recoveries == 0
