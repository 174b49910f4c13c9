import math

import numpy as np
import pytest
from pydrake.common.value import AbstractValue
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import BasicVector, DiagramBuilder, LeafSystem

from drake_sim.base.errors import ConfigError
from drake_sim.base.map_files import OCCUPIED
from drake_sim.base.resources import config_dir
from drake_sim.navigation import navigator as mut
from drake_sim.navigation.costmap import INSCRIBED
from drake_sim.systems.estimation.slam import NO_SCAN
from drake_sim.systems.sensors.lidar import LaserScan
from drake_sim.worlds.arena import arena_footprints, arena_grid, load_arena
from drake_sim.worlds.footprints import Footprint, cast_rays, clearance

LIDAR_X = -0.064  # m, the lidar behind base_footprint, as on the TurtleBot3 Waffle.
RATE = 100.0  # Hz, the unicycle's steps.


class Unicycle(LeafSystem):
    """A kinematic unicycle: its velocity follows ``[v, omega]`` with a first-order lag of
    ``lag`` s, its pose integrates the velocity at 100 Hz."""

    def __init__(self, pose, lag=0.05):
        super().__init__()
        self._lag = lag
        self._command = self.DeclareVectorInputPort("command", 2)
        state = self.DeclareDiscreteState(BasicVector([*pose, 0.0, 0.0]))
        self.DeclarePeriodicDiscreteUpdateEvent(1 / RATE, 0.0, self._step)
        self.DeclareVectorOutputPort(
            "pose", 3, lambda c, o: o.SetFromVector(c.get_discrete_state(state).value()[:3]),
            {self.discrete_state_ticket(state)},
        )  # fmt: skip
        self.DeclareVectorOutputPort(
            "twist", 2, lambda c, o: o.SetFromVector(c.get_discrete_state(state).value()[3:]),
            {self.discrete_state_ticket(state)},
        )  # fmt: skip

    def _step(self, context, discrete_state):
        x, y, yaw, v, omega = context.get_discrete_state_vector().value()
        v, omega = np.array([v, omega]) + (self._command.Eval(context) - [v, omega]) * (
            1 / RATE / self._lag
        )
        dt = 1 / RATE
        discrete_state.set_value(
            [x + dt * v * math.cos(yaw), y + dt * v * math.sin(yaw), yaw + dt * omega, v, omega]
        )


class ScanSource(LeafSystem):
    """Exact 360-beam scans of ``footprints`` from the lidar at the pose input, at 5 Hz."""

    def __init__(self, footprints, range_max=3.5):
        super().__init__()
        self._footprints = footprints
        self._range_max = range_max
        self._pose = self.DeclareVectorInputPort("pose", 3)
        self._state = self.DeclareAbstractState(AbstractValue.Make(NO_SCAN))
        self.DeclarePeriodicUnrestrictedUpdateEvent(0.2, 0.0, self._scan)
        self.DeclareStateOutputPort("scan", self._state)

    def _scan(self, context, state):
        x, y, yaw = self._pose.Eval(context)
        p = [x + LIDAR_X * math.cos(yaw), y + LIDAR_X * math.sin(yaw)]
        angles = -math.pi + np.arange(360) * (2 * math.pi / 360)
        ranges = cast_rays(self._footprints, np.array([p]), angles + yaw, self._range_max)[0]
        ranges = np.where(ranges >= 0.12, ranges, np.inf)
        scan = LaserScan(context.get_time(), -math.pi, 2 * math.pi / 360, 0.12, self._range_max,
                         ranges)  # fmt: skip
        state.get_mutable_abstract_state(0).set_value(scan)


def _arena(name):
    return load_arena(config_dir() / "arenas" / f"{name}.yaml")


def _run(arena, start, goals, duration, *, extra=(), occupancy_map=None, config=None,
         stop_when_finished=True, on_step=None):  # fmt: skip
    """Simulates the navigator driving the unicycle until 1 s after it has finished (or for
    ``duration`` s); returns (poses (n, 3) every 0.1 s, the final status, the navigator, the
    simulator)."""
    footprints = arena_footprints(arena) + list(extra)
    builder = DiagramBuilder()
    robot = builder.AddSystem(Unicycle(start))
    scanner = builder.AddSystem(ScanSource(footprints))
    dut = builder.AddSystem(
        mut.Navigator(
            map=occupancy_map if occupancy_map is not None else arena_grid(arena, 0.05),
            config=config or mut.NavigatorConfig(),
            X_base_sensor=(LIDAR_X, 0.0, 0.0),
            goals=goals,
        )
    )
    builder.Connect(robot.GetOutputPort("pose"), scanner.get_input_port())
    builder.Connect(robot.GetOutputPort("pose"), dut.GetInputPort("pose"))
    builder.Connect(robot.GetOutputPort("twist"), dut.GetInputPort("twist"))
    builder.Connect(scanner.get_output_port(), dut.GetInputPort("scan"))
    builder.Connect(dut.GetOutputPort("cmd_vel"), robot.get_input_port())
    simulator = Simulator(builder.Build())
    root = simulator.get_context()
    poses = []
    status = None
    finished_at = math.inf
    for t in np.arange(0.1, duration + 1e-9, 0.1):
        simulator.AdvanceTo(t)
        poses.append(robot.GetOutputPort("pose").Eval(robot.GetMyContextFromRoot(root)))
        status = dut.GetOutputPort("status").Eval(dut.GetMyContextFromRoot(root))
        if on_step is not None:
            on_step(t, dut, dut.GetMyMutableContextFromRoot(root), status)
        finished_at = min(finished_at, t) if status.finished else math.inf
        if stop_when_finished and t > finished_at + 1.0:  # 1 s more: it stays stopped
            break
    return np.array(poses), status, dut, simulator


def _yaw_error(a, b):
    return abs((a - b + math.pi) % (2 * math.pi) - math.pi)


def test_visits_goals_in_order_precisely_and_keeps_clear_of_obstacles():
    arena = _arena("room")
    goals = [[0.2, -1.6, math.radians(90)], [2.2, 1.6, math.radians(180)],
             [-2.2, 1.9, math.radians(-90)]]  # fmt: skip
    poses, status, _, _ = _run(arena, arena.start_pose(), goals, 150.0)
    assert status.state == "arrived" and status.finished
    assert [r.reached for r in status.results] == [True, True, True]
    assert status.goal_index == 2
    assert status.costmap.costs.shape == arena_grid(arena, 0.05).cells.shape
    for result, goal in zip(status.results, goals, strict=True):
        assert np.hypot(*(result.final_pose[:2] - goal[:2])) < 0.05
        assert _yaw_error(result.final_pose[2], goal[2]) < math.radians(10)
        # Time to goal within 2.5 x the path length at the robot's top speed (0.26 m/s).
        assert result.path_length_m > 0.5 and result.time_s < 2.5 * result.path_length_m / 0.26
        assert 0.9 * result.path_length_m < result.driven_m < 1.3 * result.path_length_m
    # The robot's centre never comes within the robot radius of a wall or obstacle.
    assert np.min(clearance(arena_footprints(arena), poses[:, :2])) > 0.22
    assert np.allclose(poses[-1], poses[-5], atol=1e-6)  # stopped


def test_avoids_a_box_that_is_not_on_the_map():
    arena = _arena("room")
    # A box across the straight line from the start to the goal, seen only by the lidar, and
    # first beyond the costmap's obstacle_max_range (2.5 m).
    box = Footprint("box", "new_box", (0.4, -0.2), (0.2, 0.6), 0.0, 0.0, 0.3)
    start, goal = [-2.6, -0.2, 0.0], [2.5, -0.2, 0.0]
    paths = []
    poses, status, dut, simulator = _run(
        _arena("room"), start, [goal], 60.0, extra=[box],
        on_step=lambda t, d, c, s: paths.append(s.path.copy()),
    )  # fmt: skip
    assert status.results[0].reached
    assert np.min(box.signed_distance(poses[:, :2])) > 0.22
    assert np.min(clearance(arena_footprints(arena), poses[:, :2])) > 0.22
    # The first plan (on the map alone) went straight through the box; it was replanned.
    assert np.min(box.signed_distance(paths[0])) < 0.0
    assert np.min(box.signed_distance(paths[-1])) > 0.0
    # The box is in the global costmap (obstacle layer), and in the rolling local window.
    context = dut.GetMyContextFromRoot(simulator.get_context())
    face = np.array([[0.21, -0.2], [0.4, 0.41]])
    assert np.all(dut.costmap(context).cost_at(face) >= INSCRIBED)
    assert np.all(arena_grid(arena, 0.05).value_at(face) == 0)  # free on the map
    local = dut.local_costmap(context)
    assert local.costs.shape == (60, 60)
    assert np.allclose(local.cost_at(poses[-1, :2]), dut.costmap(context).cost_at(poses[-1, :2]))


def test_an_unreachable_goal_fails_at_once():
    arena = _arena("room")
    grid = arena_grid(arena, 0.05)
    cells = grid.cells.copy()
    rows, cols = grid.cell_of(np.array([[1.6, 1.4], [2.4, 2.2]]))
    cells[rows[0] : rows[1] + 1, cols[0]] = OCCUPIED  # a closed square pocket on the map
    cells[rows[0] : rows[1] + 1, cols[1]] = OCCUPIED
    cells[rows[0], cols[0] : cols[1] + 1] = OCCUPIED
    cells[rows[1], cols[0] : cols[1] + 1] = OCCUPIED
    pocket = type(grid)(cells=cells, resolution=grid.resolution, origin=grid.origin)
    poses, status, _, _ = _run(arena, arena.start_pose(), [[2.0, 1.8, 0.0]], 1.0,
                               occupancy_map=pocket)  # fmt: skip
    assert status.state == "failed" and status.finished
    assert status.message == "unreachable"
    assert status.results[0].time_s <= 0.2 and not status.results[0].reached
    assert np.allclose(poses[-1], arena.start_pose())


def test_a_goal_inside_an_obstacle_is_unreachable():
    arena = _arena("room")
    _, status, _, _ = _run(arena, arena.start_pose(), [[-0.9, -0.9, 0.0]], 1.0)
    assert status.state == "failed"
    assert status.message.startswith("unreachable")


def test_a_corridor_blocked_by_a_new_obstacle_fails_after_recoveries():
    arena = _arena("maze")
    # Blocks the first corridor of the maze (x in [-3.5, -2.05]) across, north of the start.
    box = Footprint("box", "blocker", (-2.75, 0.2), (0.8, 0.1), 0.0, 0.0, 0.3)
    behaviours = []

    def record(t, dut, context, status):
        if status.state == "recovering" and status.message not in behaviours:
            behaviours.append(status.message)

    poses, status, _, _ = _run(arena, arena.start_pose(), [[-1.25, -2.4, 0.0]], 60.0,
                               extra=[box], on_step=record)  # fmt: skip
    assert status.state == "failed"
    assert status.message.startswith("blocked")
    assert behaviours  # it tried to recover first: cleared, spun round, backed up
    assert np.ptp(poses[:, 2]) > 2 * math.pi - 0.1
    steps = np.diff(poses[:, :2], axis=0)
    backwards = -np.sum(steps * np.column_stack([np.cos(poses[:-1, 2]), np.sin(poses[:-1, 2])]),
                        axis=1)  # fmt: skip
    assert np.sum(np.maximum(backwards, 0.0)) > 0.1
    assert np.min(box.signed_distance(poses[:, :2])) > 0.22
    assert np.min(clearance(arena_footprints(arena), poses[:, :2])) > 0.22


def test_no_progress_is_seen_through_periodic_replans(monkeypatch):
    """A local planner that keeps 'following' with a zero command (a local minimum): the
    progress clock runs on through the replans every second, so the recoveries start (the
    first, clearing the costmap, replans at once; the second, a spin, shows 3 s later)."""
    from drake_sim.navigation.local_planner import DwaPlanner, LocalCommand

    still = LocalCommand(0.0, 0.0, np.zeros((0, 3)), "following")
    monkeypatch.setattr(DwaPlanner, "compute", lambda self, *args: still)
    config = mut.NavigatorConfig()
    config.replan_period, config.recovery.progress_timeout = 1.0, 3.0
    seen = {}

    def record(t, dut, context, status):
        if status.state == "recovering":
            seen.setdefault(status.message, t)

    arena = _arena("room")
    _run(arena, arena.start_pose(), [[2.2, 1.6, 0.0]], 8.0, config=config, on_step=record)
    assert 6.0 < seen.get("blocked: no progress", math.inf) < 6.5


def test_cancel_stops_the_robot_and_set_goal_preempts():
    arena = _arena("room")
    events = []

    def control(t, dut, context, status):
        if abs(t - 2.0) < 1e-6:
            dut.cancel(context)
            events.append("canceled")
        if abs(t - 4.0) < 1e-6:
            events.append(dut.GetOutputPort("cmd_vel").Eval(context).copy())
            dut.set_goal(context, [-1.8, -1.8, 0.0])

    poses, status, _, _ = _run(arena, arena.start_pose(), [[2.0, 0.0, 0.0]], 30.0,
                               on_step=control, stop_when_finished=False)  # fmt: skip
    assert events[0] == "canceled" and np.allclose(events[1], 0.0)
    assert np.allclose(poses[29], poses[38], atol=1e-3)  # still between 3 s and 3.9 s
    first, second = status.results
    assert (first.reached, first.message) == (False, "canceled")
    assert second.reached and status.state == "arrived"
    assert status.goal_index == 1


def test_bad_goals_and_config_values_are_rejected():
    arena = _arena("room")
    with pytest.raises(ConfigError, match="goal"):
        mut.Navigator(map=arena_grid(arena), config=mut.NavigatorConfig(),
                      goals=[[0.0, math.nan, 0.0]])  # fmt: skip
    config = mut.NavigatorConfig()
    config.controller.max_vel_x = -1.0
    with pytest.raises(ConfigError, match="controller.max_vel_x"):
        mut.check_navigator_config(config, "nav.yaml")
    config = mut.NavigatorConfig(replan_period=math.nan)
    with pytest.raises(ConfigError, match="replan_period"):
        mut.check_navigator_config(config)
    for name, value in [
        ("localization_spin", 0.0),
        ("localization_drive", -1.0),
        ("localization_confirm", math.inf),
        ("localization_speed", True),
    ]:
        with pytest.raises(ConfigError, match=f"'{name}' must be a finite number"):
            mut.check_navigator_config(mut.NavigatorConfig(**{name: value}))
    mut.check_navigator_config(mut.NavigatorConfig(localization_drive=0, localization_confirm=0))
    config = mut.NavigatorConfig()
    config.recovery.max_recoveries = -1
    with pytest.raises(ConfigError, match="recovery.max_recoveries"):
        mut.check_navigator_config(config)


def test_load_navigator_config(tmp_path):
    path = tmp_path / "nav.yaml"
    path.write_text("replan_period: 1.0\ncontroller: {max_vel_x: 0.2}\n")
    config = mut.load_navigator_config(path)
    assert config.replan_period == 1.0 and config.controller.max_vel_x == 0.2
    path.write_text("controller: {max_vel_xx: 0.2}\n")
    with pytest.raises(ConfigError, match=r"nav.yaml.*controller.max_vel_xx"):
        mut.load_navigator_config(path)
    path.write_text("recovery: {backup_speed: -0.1}\n")
    with pytest.raises(ConfigError, match=r"nav.yaml.*recovery.backup_speed"):
        mut.load_navigator_config(path)


def _localizing(config, localized: float | None):
    """A navigator that localises first, its inputs fixed (``localized`` None: unconnected)."""
    arena = _arena("room")
    dut = mut.Navigator(
        map=arena_grid(arena, 0.05), config=config, goals=[[0.0, -1.0, 0.0]], localize_first=True
    )
    simulator = Simulator(dut)
    context = simulator.get_mutable_context()
    dut.GetInputPort("pose").FixValue(context, [-2.2, -1.8, 0.0])
    dut.GetInputPort("twist").FixValue(context, [0.0, 0.0])
    dut.GetInputPort("scan").FixValue(context, AbstractValue.Make(NO_SCAN))
    if localized is not None:
        dut.GetInputPort("localized").FixValue(context, [localized])
    return dut, simulator


@pytest.mark.parametrize("confirm", [0.0, 1.0])
def test_from_no_guess_it_spins_until_localised_then_drives(confirm):
    """Settled ends the localising at once with no confirmation asked; else only once the
    robot has driven on that far (it cannot here: its twist stays zero)."""
    config = mut.NavigatorConfig(localization_confirm=confirm)
    dut, simulator = _localizing(config, 0.0)
    simulator.AdvanceTo(1.0)
    context = simulator.get_context()
    assert dut.GetOutputPort("status").Eval(context).state == "localizing"
    assert dut.GetOutputPort("cmd_vel").Eval(context) == pytest.approx([0.0, 0.8])
    dut.GetInputPort("localized").FixValue(simulator.get_mutable_context(), [1.0])
    simulator.AdvanceTo(1.3)
    expected = "following" if confirm == 0 else "localizing"
    assert dut.GetOutputPort("status").Eval(context).state == expected


def test_localising_ends_at_its_timeout_or_with_no_input():
    config = mut.NavigatorConfig(localization_timeout=0.5)
    dut, simulator = _localizing(config, 0.0)
    simulator.AdvanceTo(0.8)
    assert dut.GetOutputPort("status").Eval(simulator.get_context()).state == "following"
    dut, simulator = _localizing(mut.NavigatorConfig(), None)
    simulator.AdvanceTo(0.3)
    assert dut.GetOutputPort("status").Eval(simulator.get_context()).state == "following"


class LocalizedAfter(LeafSystem):
    """``localized`` = 1 once the pose input is ``distance`` m from ``start`` (a localisation
    that needs the robot to move, as in a building of repeated aisles)."""

    def __init__(self, start, distance):
        super().__init__()
        self._pose = self.DeclareVectorInputPort("pose", 3)
        self.DeclareVectorOutputPort("localized", 1, lambda c, o: o.SetFromVector(
            [float(math.dist(self._pose.Eval(c)[:2], start[:2]) >= distance)]))  # fmt: skip


def test_from_no_guess_it_turns_and_drives_legs_until_localised():
    arena = _arena("room")
    start, goal = arena.start_pose(), [0.0, -1.0, 0.0]
    builder = DiagramBuilder()
    robot = builder.AddSystem(Unicycle(start))
    scanner = builder.AddSystem(ScanSource(arena_footprints(arena)))
    oracle = builder.AddSystem(LocalizedAfter(start, 0.8))
    dut = builder.AddSystem(mut.Navigator(map=arena_grid(arena, 0.05), config=mut.NavigatorConfig(),
                                          X_base_sensor=(LIDAR_X, 0.0, 0.0), goals=[goal],
                                          localize_first=True))  # fmt: skip
    for port in ("pose", "twist"):
        builder.Connect(robot.GetOutputPort(port), dut.GetInputPort(port))
    builder.Connect(robot.GetOutputPort("pose"), scanner.get_input_port())
    builder.Connect(robot.GetOutputPort("pose"), oracle.get_input_port())
    builder.Connect(oracle.get_output_port(), dut.GetInputPort("localized"))
    builder.Connect(scanner.get_output_port(), dut.GetInputPort("scan"))
    builder.Connect(dut.GetOutputPort("cmd_vel"), robot.get_input_port())
    simulator = Simulator(builder.Build())
    poses, states = [], []
    for t in np.arange(0.1, 60.0, 0.1):
        simulator.AdvanceTo(t)
        root = simulator.get_context()
        poses.append(robot.GetOutputPort("pose").Eval(robot.GetMyContextFromRoot(root)))
        status = dut.GetOutputPort("status").Eval(dut.GetMyContextFromRoot(root))
        states.append(status.state)
        if status.finished and status.results:
            break
    poses = np.array(poses)
    localizing = poses[: states.index("following")]
    # A full turn on the spot first, then a leg (it was not localised by turning alone).
    first_move = int(np.argmax(np.hypot(*(localizing[:, :2] - start[:2]).T) > 0.01))
    assert localizing[first_move, 2] - start[2] > 2 * math.pi - 0.2
    assert math.dist(localizing[-1, :2], start[:2]) >= 0.8
    # ... and on, settled, for localization_confirm (1 m) more before heading for the goal.
    assert np.sum(np.hypot(*np.diff(localizing[:, :2], axis=0).T)) > 0.8 + 1.0 - 0.05
    assert status.results[0].reached
    assert np.min(clearance(arena_footprints(arena), poses[:, :2])) > 0.22
