"""drake_sim.systems.estimation.loop_closure: candidates far back along the trajectory and near
in space; a scan found on the old submap from half a metre and 5 degrees off; no closure where
the match is ambiguous (a corridor) or poor (another place)."""

import math

import numpy as np
import pytest

import drake_sim.systems.estimation.loop_closure as mut
from drake_sim.base.planar import relative_pose
from tests import slam_helpers as helpers

CONFIG = mut.LoopClosureConfig(enabled=True)


def keyframes(world, poses, *, seed=0, range_max=3.5):
    """Each pose's scan hits in the base frame (a full 360 beam scan, 1 cm noise)."""
    ranges, angles = helpers.lidar_scans(world, poses, seed=seed, range_max=range_max)
    return [mut.scan_points(r, angles, range_max, 0.1, np.zeros(3), 20.0) for r in ranges]


def loop(world, n=40, radius=1.5, centre=(0.0, 0.0)):
    """Keyframes on a circle (travel 2 pi radius), ending where they began."""
    a = np.linspace(0.0, 2.0 * math.pi, n + 1)
    poses = np.stack(
        [centre[0] + radius * np.cos(a), centre[1] + radius * np.sin(a), a + math.pi / 2], -1
    )
    travel = radius * a
    return poses, travel


def test_the_candidate_is_the_nearest_keyframe_far_enough_back():
    poses, travel = loop(helpers.room(), radius=2.0)  # 12.6 m around
    current = len(poses) - 1
    assert mut.candidate(poses, travel, current, CONFIG) == 0
    # too little travel between them: none
    assert mut.candidate(poses, travel, current, mut.LoopClosureConfig(min_travel=13.0)) is None
    # too far away: none
    far = poses.copy()
    far[current, :2] += [5.0, 0.0]
    assert mut.candidate(far, travel, current, CONFIG) is None


def test_a_scan_is_found_on_the_old_submap_from_half_a_metre_off():
    world = helpers.room()
    poses, travel = loop(world, radius=1.8, centre=(-1.0, 0.6))  # 11.3 m around
    points = keyframes(world, poses)
    current = len(poses) - 1
    estimate = poses.copy()
    estimate[current] += [0.4, -0.3, math.radians(5.0)]
    found = mut.close_loop(estimate, travel, points, current, 0, CONFIG)
    assert found is not None
    error = relative_pose(poses[current], found[0])
    assert math.hypot(*error[:2]) < 0.02 and abs(math.degrees(error[2])) < 0.3, error
    assert found[1] > 0.8


def test_no_closure_along_a_corridor_or_on_another_place():
    corridor = helpers.World(10.0, 0.8)  # 20 m long, 1.6 m wide, the ends out of range
    poses = np.stack([np.linspace(-6.0, 6.0, 61), np.zeros(61), np.zeros(61)], -1)
    poses = np.vstack([poses, poses[::-1][1:] * [1, 1, 0] + [0, 0, math.pi]])
    travel = np.arange(len(poses)) * 0.2
    points = keyframes(corridor, poses)
    current = len(poses) - 1
    assert mut.candidate(poses, travel, current, CONFIG) is not None
    estimate = poses.copy()
    estimate[current, 0] += 0.4
    assert mut.close_loop(estimate, travel, points, current, 0, CONFIG) is None
    # the room's scans, the current one from elsewhere in it: too poor a match
    world = helpers.room()
    poses, travel = loop(world, radius=1.0, centre=(-2.0, 1.0))
    points = keyframes(world, poses)
    points[-1] = keyframes(world, np.array([[2.5, -1.0, 0.0]]), seed=1)[0]
    assert mut.close_loop(poses, travel, points, len(poses) - 1, 0, CONFIG) is None


@pytest.mark.parametrize(
    "key, value", [("window_xy", 0.0), ("max_ambiguity", 0.0), ("unmatched_sigma", [1.0])]
)
def test_bad_settings_are_named(key, value):
    from drake_sim.base.errors import ConfigError

    with pytest.raises(ConfigError, match=key):
        mut.LoopClosureConfig(**{key: value}).check()
