import math

import numpy as np
import pytest

from drake_sim.base.errors import ConfigError
from drake_sim.base.planar import wrap_angle
from drake_sim.navigation import costmap as cm
from drake_sim.navigation import local_planner as mut


def _room(boxes=(), size=4.0, resolution=0.05):
    """A walled square room [0, size]^2 with axis-aligned boxes (x0, y0, x1, y1)."""
    n = round(size / resolution)
    centres = (np.arange(n) + 0.5) * resolution
    xs, ys = np.meshgrid(centres, centres)
    occupied = (xs < 0.1) | (ys < 0.1) | (xs > size - 0.1) | (ys > size - 0.1)
    for x0, y0, x1, y1 in boxes:
        occupied |= (xs >= x0) & (xs <= x1) & (ys >= y0) & (ys <= y1)
    static = np.where(occupied, cm.LETHAL, cm.FREE_SPACE)
    return cm.Costmap(static, resolution, (0.0, 0.0, 0.0), cm.CostmapConfig())


def test_rollouts_are_exact_arcs_and_lines():
    poses = mut.rollouts([1.0, 2.0, 0.5], [0.2, 1.0], [0.0, 1.0], math.pi / 10, 10)
    assert poses.shape == (2, 10, 3)
    assert poses[0, -1] == pytest.approx(
        [1.0 + 0.2 * math.pi * math.cos(0.5), 2.0 + 0.2 * math.pi * math.sin(0.5), 0.5]
    )
    # A half circle of radius 1 from heading 0.5: ends 2 m to the left of the start.
    assert poses[1, -1, :2] == pytest.approx([1.0 - 2 * math.sin(0.5), 2.0 + 2 * math.cos(0.5)])
    assert poses[1, -1, 2] == pytest.approx(0.5 + math.pi)


def test_densify_keeps_vertices_and_spacing():
    path = mut.densify([[0.0, 0.0], [1.0, 0.0], [1.0, 0.33]], 0.1)
    assert np.max(np.hypot(*np.diff(path, axis=0).T)) <= 0.1 + 1e-12
    for vertex in ([0.0, 0.0], [1.0, 0.0], [1.0, 0.33]):
        assert np.min(np.hypot(*(path - vertex).T)) < 1e-12
    assert len(mut.densify([[1.0, 2.0]], 0.1)) == 1


def test_drives_along_a_clear_path_within_the_acceleration_limits():
    dut = mut.DwaPlanner(mut.DwaConfig())
    path = np.array([[0.5, 2.0], [3.5, 2.0]])
    command = dut.compute([0.5, 2.0, 0.0], (0.0, 0.0), path, [3.5, 2.0, 0.0], _room())
    assert command.status == "following"
    assert 0.0 < command.v <= dut.config.acc_lim_x * dut.period + 1e-12
    assert abs(command.omega) <= dut.config.acc_lim_theta * dut.period + 1e-12
    command = dut.compute([0.5, 2.0, 0.0], (0.2, 0.0), path, [3.5, 2.0, 0.0], _room())
    assert command.v == pytest.approx(dut.config.max_vel_x)
    assert abs(command.omega) < 0.2
    assert command.trajectory.shape[1] == 3 and command.trajectory[-1, 0] > 0.8


def test_turns_on_the_spot_to_a_path_behind():
    dut = mut.DwaPlanner(mut.DwaConfig())
    path = np.array([[2.0, 2.0], [0.5, 2.0]])
    command = dut.compute([2.0, 2.0, 0.0], (0.0, 0.0), path, [0.5, 2.0, 0.0], _room())
    assert command.status == "following" and command.v == 0.0 and command.omega != 0.0
    # Moving: it slows down within the acceleration limit, already turning.
    command = dut.compute([2.0, 2.0, 0.0], (0.2, 0.0), path, [0.5, 2.0, 0.0], _room())
    assert command.v == pytest.approx(0.2 - dut.config.acc_lim_x * dut.period)
    assert abs(command.omega) == pytest.approx(dut.config.acc_lim_theta * dut.period)


def test_no_valid_trajectory_when_boxed_in():
    boxed = _room()
    boxed.costs[:] = cm.INSCRIBED
    dut = mut.DwaPlanner(mut.DwaConfig())
    command = dut.compute([2.0, 2.0, 0.0], (0.1, 0.0), [[2, 2], [3, 2]], [3, 2, 0], boxed)
    assert command.status == "no_valid_trajectory"
    assert (command.v, command.omega) == (0.0, 0.0)


def test_rotates_to_the_goal_yaw_then_arrives():
    dut = mut.DwaPlanner(mut.DwaConfig())
    goal = [2.0, 2.0, 1.0]
    command = dut.compute([2.01, 2.0, 0.0], (0.0, 0.0), [[2.0, 2.0]], goal, _room())
    assert command.status == "rotating_to_goal" and command.v == 0.0 and command.omega > 0
    command = dut.compute([2.01, 2.0, 2.5], (0.0, 0.0), [[2.0, 2.0]], goal, _room())
    assert command.status == "rotating_to_goal" and command.omega < 0
    command = dut.compute([2.01, 2.0, 0.98], (0.0, 0.0), [[2.0, 2.0]], goal, _room())
    assert command.status == "arrived" and (command.v, command.omega) == (0.0, 0.0)


def test_a_turn_to_the_goal_yaw_goes_on_while_the_estimate_shifts_a_little():
    """nav2's stateful goal checker: once turning to the goal's heading, an estimate that
    drifts a little past ``xy_goal_tolerance`` (AMCL across open floor while the robot turns)
    does not send the robot back to the goal point; one that leaves twice the tolerance does."""
    c = mut.DwaConfig(xy_goal_tolerance=0.025)
    dut = mut.DwaPlanner(c)
    goal = [2.0, 2.0, 1.0]
    pose = [2.0 - 0.03 * math.cos(2.5), 2.0 - 0.03 * math.sin(2.5), 2.5]  # 3 cm short of it
    fresh = dut.compute(pose, (0.0, 0.0), [[2.0, 2.0]], goal, _room())
    assert fresh.status == "following" and fresh.v > 0  # drives on to the point
    turning = dut.compute(pose, (0.0, 0.0), [[2.0, 2.0]], goal, _room(), at_goal_xy=True)
    assert turning.status == "rotating_to_goal" and turning.v == 0.0 and turning.omega < 0
    far = [2.06, 2.0, 2.5]
    again = dut.compute(far, (0.0, 0.0), [[2.0, 2.0]], goal, _room(), at_goal_xy=True)
    assert again.status == "following"


def test_drives_out_of_the_inscribed_zone_but_never_into_it():
    costmap = _room(boxes=[(2.0, 1.0, 2.4, 3.0)])  # a box 0.15 m ahead of x = 1.85
    dut = mut.DwaPlanner(mut.DwaConfig())
    path, goal = np.array([[1.85, 2.0], [1.0, 2.0]]), [1.0, 2.0, math.pi]
    assert costmap.cost_at([1.85, 2.0]) == cm.INSCRIBED
    command = dut.compute([1.85, 2.0, math.pi], (0.0, 0.0), path, goal, costmap)
    assert command.status == "following" and command.v > 0.0
    # From just outside the inscribed zone, no rollout may enter it (not even a little).
    command = dut.compute([1.74, 2.0, 0.0], (0.2, 0.0), [[1.74, 2.0], [1.9, 2.0]], goal, costmap)
    assert command.status == "no_valid_trajectory" or np.all(
        costmap.cost_at(command.trajectory[:, :2]) < cm.INSCRIBED
    )


def test_blocked_ahead_it_turns_to_the_path_then_gives_up_facing_it():
    """A narrow bend cut too close: every rollout that moves on enters the inscribed zone
    (here the robot is 1 mm outside it, heading 0.5 rad towards the box; at 20 Hz the window of
    turn rates is narrow). It turns on the spot to the path rather than standing still, and
    with the path itself leading into the zone nothing is valid (the recoveries take over)."""
    costmap = _room(boxes=[(1.0, 2.3, 3.0, 3.0)])
    dut = mut.DwaPlanner(mut.DwaConfig(controller_frequency=20.0))
    y = 2.099
    assert costmap.cost_at([1.5, y]) < cm.INSCRIBED <= costmap.cost_at([1.5, y + 0.002])
    path = np.array([[1.5, y], [3.5, y]])
    command = dut.compute([1.5, y, 0.5], (0.0, 0.0), path, [3.5, y, 0.0], costmap)
    assert command.status == "following" and command.v == 0.0
    assert command.omega == pytest.approx(-dut.config.acc_lim_theta * dut.period)
    up = np.array([[1.5, y], [1.5, y + 1.0]])  # the path ahead runs into the box's zone
    command = dut.compute([1.5, y, math.pi / 2], (0.0, 0.0), up, [1.5, y + 1.0, 0.0], costmap)
    assert command.status == "no_valid_trajectory" and (command.v, command.omega) == (0, 0)


def _simulate(dut, costmap, start, path, goal, duration, lag=0.05):
    """Closed loop: the unicycle follows the command with a first-order lag (s), at 100 Hz."""
    pose = np.array(start, dtype=float)
    velocity = np.zeros(2)
    command = np.zeros(2)
    poses, statuses = [pose.copy()], []
    for step in range(round(duration * 100)):
        if step % round(100 * dut.period) == 0:
            result = dut.compute(pose, velocity, path, goal, costmap)
            command = np.array([result.v, result.omega])
            statuses.append(result.status)
            if result.status == "arrived":
                break
        velocity += (command - velocity) * (0.01 / lag)
        v, omega = velocity
        pose += 0.01 * np.array([v * math.cos(pose[2]), v * math.sin(pose[2]), omega])
        poses.append(pose.copy())
    return np.array(poses), statuses


def test_closed_loop_avoids_a_box_on_the_path_and_stops_precisely_at_the_goal():
    # A box sits across the straight path: the path (from a global planner) goes round it;
    # the DWA must follow it without entering the inscribed zone, and stop within tolerance.
    costmap = _room(boxes=[(1.8, 1.4, 2.2, 2.6)])
    path = np.array([[0.6, 2.0], [1.3, 2.0], [1.5, 3.05], [2.5, 3.05], [2.7, 2.0], [3.4, 2.0]])
    goal = [3.4, 2.0, -math.pi / 2]
    dut = mut.DwaPlanner(mut.DwaConfig())
    poses, statuses = _simulate(dut, costmap, [0.6, 2.0, 0.0], path, goal, 60.0)
    assert statuses[-1] == "arrived"
    assert "rotating_to_goal" in statuses
    assert np.hypot(*(poses[-1, :2] - goal[:2])) < 0.05
    assert abs(wrap_angle(poses[-1, 2] - goal[2])) < math.radians(10)
    assert np.all(costmap.cost_at(poses[:, :2]) < cm.INSCRIBED)
    # Time: well under 2.5 x the path length over the robot's top speed (0.26 m/s).
    length = np.sum(np.hypot(*np.diff(path, axis=0).T))
    assert len(poses) / 100 < 2.5 * length / 0.26


@pytest.mark.parametrize("yaw", [0.0, math.pi, -2.0])
def test_final_approach_from_any_heading_is_precise(yaw):
    costmap = _room()
    goal = [2.3, 2.1, 0.7]
    dut = mut.DwaPlanner(mut.DwaConfig())
    poses, statuses = _simulate(dut, costmap, [2.0, 2.0, yaw], [[2.0, 2.0], goal[:2]], goal, 20)
    assert statuses[-1] == "arrived"
    assert np.hypot(*(poses[-1, :2] - goal[:2])) < 0.05
    assert abs(wrap_angle(poses[-1, 2] - goal[2])) < math.radians(10)


def test_default_config_is_valid():
    config = mut.check_dwa_config(mut.DwaConfig())
    assert config.max_vel_x <= 0.26 and config.max_vel_theta <= 1.82
    assert config.xy_goal_tolerance == 0.05


@pytest.mark.parametrize(
    "key, value",
    [
        ("max_vel_x", 0.0),
        ("max_vel_x", math.nan),
        ("acc_lim_theta", -1.0),
        ("sim_time", math.inf),
        ("min_vel_x", 0.1),
        ("vx_samples", 1),
        ("occdist_scale", -0.1),
        ("goal_precision", 1.5),
        ("min_vel_theta", 5.0),
    ],
)
def test_bad_config_values_are_rejected(key, value):
    with pytest.raises(ConfigError, match=key):
        mut.check_dwa_config(mut.DwaConfig(**{key: value}), "nav.yaml: controller")
    with pytest.raises(ConfigError, match="nav.yaml"):
        mut.check_dwa_config(mut.DwaConfig(**{key: value}), "nav.yaml: controller")


LONG = [[-0.5, -0.1], [-0.5, 0.1], [0.1, 0.1], [0.1, -0.1]]  # 0.6 m long behind the centre


def _with_footprint(costmap, footprint=LONG):
    import dataclasses as dc

    inscribed = cm.footprint_radii(footprint)[0]
    config = dc.replace(costmap.config, footprint=footprint, robot_radius=inscribed)
    return cm.Costmap(costmap.static_layer, costmap.resolution, costmap.origin, config)


def test_a_footprint_polygon_is_checked_at_every_pose():
    """A long robot next to a wall: its centre may go where its circle would, but a turn that
    swings its tail through the wall is refused, and so is every rollout whose outline would
    touch it."""
    room = _room(boxes=[(1.45, 0.0, 1.5, 4.0)])  # a wall at x = 1.45 .. 1.5
    long = _with_footprint(room)
    pose = np.array([1.2, 2.0, math.pi / 2])  # facing +y, the tail 0.5 m behind, x 1.1 .. 1.3
    dut = mut.DwaPlanner(mut.DwaConfig())
    # Turning to face -x swings the tail (0.5 m) to x = 1.7: through the wall.
    path = np.array([[1.2, 2.0], [0.2, 2.0]])
    assert dut.compute(pose, (0.0, 0.0), path, [0.2, 2.0, 0.0], room).status == "following"
    blocked = dut.compute(pose, (0.0, 0.0), path, [0.2, 2.0, 0.0], long)
    assert blocked.status == "no_valid_trajectory"
    # Driving on along the wall stays clear: every pose's outline is off the wall.
    path = np.array([[1.2, 2.0], [1.2, 3.5]])
    command = dut.compute(pose, (0.1, 0.0), path, [1.2, 3.5, math.pi / 2], long)
    assert command.status == "following" and command.v > 0
    outline = cm.footprint_outline(LONG, 0.01)
    for x, y, yaw in command.trajectory:
        c, s = math.cos(yaw), math.sin(yaw)
        points = np.column_stack([x + c * outline[:, 0] - s * outline[:, 1],
                                  y + s * outline[:, 0] + c * outline[:, 1]])  # fmt: skip
        assert np.all(long.cost_at(points) < cm.LETHAL)


def test_footprint_radii_and_checks():
    assert cm.footprint_radii(LONG) == pytest.approx((0.1, math.hypot(0.5, 0.1)))
    assert len(cm.footprint_outline(LONG, 0.05)) == 2 * (12 + 4)
    with pytest.raises(ConfigError, match="a polygon around the robot's origin"):
        cm.check_costmap_config(cm.CostmapConfig(footprint=[[1, 1], [2, 1], [2, 2]]))
    with pytest.raises(ConfigError, match="a polygon of 3 or more"):
        cm.check_costmap_config(cm.CostmapConfig(footprint=[[1, 1], [2, 1]]))
