"""Driving while localising: full turns, then legs into the most open direction."""

import math

import numpy as np
import pytest

from drake_sim.navigation import localize_drive as mut

RADIUS = 0.2
KW = dict(radius=RADIUS, leg=1.5, speed=0.15, spin=0.8)


def corridor(half_width=0.6, behind=-0.5, ahead=None, step=0.02) -> np.ndarray:
    """Scan points (base frame) of a corridor along x: walls at y = +-half_width, closed at
    x = ``behind`` (and at x = ``ahead`` when given)."""
    xs = np.arange(behind, 3.5, step)
    points = [np.column_stack([xs, np.full_like(xs, s * half_width)]) for s in (-1, 1)]
    ys = np.arange(-half_width, half_width, step)
    points.append(np.column_stack([np.full_like(ys, behind), ys]))
    if ahead is not None:
        points.append(np.column_stack([np.full_like(ys, ahead), ys]))
    return np.vstack(points)


def test_clear_length_is_the_free_run_of_the_robot_s_circle():
    points = corridor(ahead=2.0)
    assert mut.clear_length(points, 0.0, RADIUS) == pytest.approx(2.0 - RADIUS - mut.MARGIN)
    # Across the corridor: the wall 0.6 m away.
    assert mut.clear_length(points, math.pi / 2, RADIUS) == pytest.approx(0.3)
    assert mut.clear_length(np.zeros((0, 2)), 1.0, RADIUS) == math.inf
    # A point just outside the swept band does not count.
    side = np.array([[1.0, RADIUS + mut.MARGIN + 0.01]])
    assert mut.clear_length(side, 0.0, RADIUS) == math.inf


def test_scan_points_are_in_the_base_frame():
    points = mut.scan_points([1.0, np.inf, 2.0], [0.0, 0.5, math.pi / 2], (-0.1, 0.0, 0.0))
    assert points == pytest.approx(np.array([[0.9, 0.0], [-0.1, 2.0]]))


def _run(points_of, cycles, dt=0.1, state=None):
    """Closed loop of ``step`` with a robot that does what it is told (twist = command);
    ``points_of(x, y, yaw)`` gives the scan. Returns the poses (odometry frame) and states."""
    state = state or mut.LocalizeDrive()
    pose, twist = np.zeros(3), (0.0, 0.0)
    poses, states = [pose.copy()], [state]
    for _ in range(cycles):
        state, v, omega = mut.step(state, twist, points_of(*pose), dt, **KW)
        twist = (v, omega)
        pose = pose + dt * np.array([v * math.cos(pose[2]), v * math.sin(pose[2]), omega])
        poses.append(pose.copy())
        states.append(state)
    return np.array(poses), states


def _world_corridor(x, y, yaw, **kw):
    """The corridor's points seen from the robot at (x, y, yaw)."""
    world = corridor(**kw)
    c, s = math.cos(yaw), math.sin(yaw)
    d = world - [x, y]
    return np.column_stack([d[:, 0] * c + d[:, 1] * s, -d[:, 0] * s + d[:, 1] * c])


def test_a_full_turn_then_a_leg_down_the_open_corridor():
    poses, states = _run(_world_corridor, 200)
    phases = [s.phase for s in states]
    first_drive = phases.index("drive")
    assert set(phases[:first_drive]) <= {"spin", "turn"}
    # A full turn before the first leg (the yaw integrated from the twist).
    assert states[first_drive].yaw >= 2 * math.pi - 0.1
    # The leg goes down the corridor (+x; the turn ended a little past a full one), 1.5 m,
    # then it turns again.
    assert poses[:, 0].max() == pytest.approx(1.5, abs=0.05)
    assert np.abs(poses[:, 1]).max() < 0.1
    assert phases[-1] == "spin" and max(np.diff(poses[:, 2])) > 0


def test_the_next_leg_does_not_go_back_the_way_it_came():
    # The robot 1.5 m down an open-ended corridor, having come from -x: it goes on along +x.
    def points_of(x, y, yaw):
        return _world_corridor(x + 1.5, y, yaw, behind=-3.0)

    came = mut.LocalizeDrive(yaw=0.0, back=math.pi)
    poses, _ = _run(points_of, 250, state=came)
    assert poses[-1, 0] > 0.5


def test_boxed_in_it_only_turns_and_a_closing_way_ahead_stops_a_leg():
    boxed = corridor(half_width=0.35, behind=-0.35, ahead=0.35)
    poses, states = _run(lambda *pose: boxed, 250)
    assert np.abs(poses[:, :2]).max() == 0.0 and {s.phase for s in states} == {"spin"}
    # Driving towards a wall 0.5 m ahead: it stops MARGIN short of touching it.
    state = mut.LocalizeDrive(phase="drive", left=1.5)
    poses, states = _run(lambda x, y, yaw: _world_corridor(x, y, yaw, ahead=0.5), 60, state=state)
    assert poses[:, 0].max() <= 0.5 - RADIUS - mut.MARGIN + 0.02
    assert states[-1].phase in ("spin", "turn", "drive") and "spin" in {s.phase for s in states}


def test_turns_only_with_no_leg():
    state, v, omega = mut.step(mut.LocalizeDrive(left=0.01), (0.0, 0.8), corridor(), 0.1,
                               **{**KW, "leg": 0.0})  # fmt: skip
    assert (state.phase, v, omega) == ("spin", 0.0, 0.8) and state.left == 2 * math.pi
