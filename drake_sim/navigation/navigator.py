"""The navigator (move_base / nav2's bt_navigator in one system): costmaps, global planner, local
planner and recovery behaviours driving the robot to its goals.

``Navigator`` is a LeafSystem updated at the controller frequency. Each cycle it inserts the
latest scan (when new) into its global costmap (static layer from the map, obstacle layer from
the scans, inflation), replans when the goal changes, every ``replan_period`` and as soon as the
path ahead is blocked, and runs the DWA (``local_planner``) on the rolling local window of the
costmap. When stuck it runs the recovery behaviours (``recovery``) and then fails the goal
("blocked"); a goal that cannot be planned to even without the obstacle layer fails at once
("unreachable"). Goals given to the constructor are visited in order; ``set_goal`` (like
RViz's "2D Nav Goal") preempts them and ``cancel`` stops.

Everything the navigator keeps (costmap, path, state machine, per-goal results) is one Python
object in its abstract state (``navigator_state.NavState``), copied and replaced by each update,
never mutated in place.
"""

import copy
import dataclasses as dc
import math
from pathlib import Path

import numpy as np
from pydrake.common.value import AbstractValue
from pydrake.systems.framework import LeafSystem

from drake_sim.base.config import load_typed
from drake_sim.base.errors import ConfigError
from drake_sim.base.map_files import OccupancyMap
from drake_sim.base.planar import compose
from drake_sim.navigation.costmap import Costmap, CostmapConfig, check_costmap_config
from drake_sim.navigation.global_planner import (
    START_IN_OBSTACLE,
    GlobalPlannerConfig,
    check_global_planner_config,
    plan_path,
    traversal_costs,
)
from drake_sim.navigation.local_planner import DwaConfig, DwaPlanner, check_dwa_config, densify
from drake_sim.navigation.localize_drive import scan_points
from drake_sim.navigation.localize_drive import step as localize_step
from drake_sim.navigation.navigator_state import NavState, copy_costmap, finish_goal, status_of
from drake_sim.navigation.recovery import (
    BEHAVIOURS,
    RecoveryConfig,
    StuckMonitor,
    check_recovery_config,
    start_behaviour,
    step_behaviour,
)
from drake_sim.navigation.teb_planner import TebConfig, TebPlanner, check_teb_config
from drake_sim.systems.estimation.slam import NO_SCAN, SCAN_DELAY
from drake_sim.systems.sensors.lidar import LaserScan


@dc.dataclass
class NavigatorConfig:
    """The navigator's costmaps, planners and recovery settings (the ``navigator`` section of
    ``config/navigation_scenario.yaml``)."""

    costmap: CostmapConfig = dc.field(default_factory=CostmapConfig)
    planner: GlobalPlannerConfig = dc.field(default_factory=GlobalPlannerConfig)
    controller: DwaConfig = dc.field(default_factory=DwaConfig)
    recovery: RecoveryConfig = dc.field(default_factory=RecoveryConfig)
    replan_period: float = 2.0  # s between replans while following (0: never on a timer).
    # The local planner: "dwa" (sampled, ``controller``) or "teb" (a timed elastic band,
    # ``teb``, with the controller's limits, tolerances and final approach).
    local_planner: str = "dwa"
    teb: TebConfig = dc.field(default_factory=TebConfig)
    # From no first guess (global localisation), until the localisation has settled (its
    # ``localized`` input, for localization_confirm m of driving on) or localization_timeout
    # s have passed, the robot turns full turns at localization_spin rad/s and between them
    # drives legs of up to localization_drive m (0: turns only) at localization_speed m/s into
    # the most open direction it sees (``localize_drive``); then it drives to its goals.
    localization_spin: float = 0.8
    localization_timeout: float = 120.0
    localization_drive: float = 1.5
    localization_speed: float = 0.15
    # Settled must hold while the robot drives this far on (m; a wrong pose among repeated
    # shelves loses its weight as the view changes): the legs go on until then.
    localization_confirm: float = 1.0


LOCAL_PLANNERS = ("dwa", "teb")
"""The local planners ``NavigatorConfig.local_planner`` names."""


def check_navigator_config(config: NavigatorConfig, where: str = "navigator") -> NavigatorConfig:
    """Returns ``config`` if every value is in range; else raises ``ConfigError`` naming
    ``where`` and the dotted key."""
    check_costmap_config(config.costmap, where, prefix="costmap.")
    check_global_planner_config(config.planner, where, prefix="planner.")
    check_dwa_config(config.controller, where, prefix="controller.")
    check_recovery_config(config.recovery, where, prefix="recovery.")
    check_teb_config(config.teb, where, prefix="teb.")
    if config.local_planner not in LOCAL_PLANNERS:
        raise ConfigError(
            f"{where}: 'local_planner' must be one of {', '.join(LOCAL_PLANNERS)}, "
            f"got {config.local_planner!r}"
        )
    for name in ("localization_spin", "localization_timeout", "localization_drive",
                 "localization_speed", "localization_confirm"):  # fmt: skip
        value = getattr(config, name)
        zero_ok = name in ("localization_drive", "localization_confirm")
        number = isinstance(value, int | float) and not isinstance(value, bool)
        if not (number and math.isfinite(value) and (value >= 0 if zero_ok else value > 0)):
            rule = ">= 0" if zero_ok else "> 0"
            raise ConfigError(f"{where}: '{name}' must be a finite number {rule}, got {value!r}")
    if not (math.isfinite(config.replan_period) and config.replan_period >= 0):
        raise ConfigError(
            f"{where}: 'replan_period' must be finite and >= 0, got {config.replan_period!r}"
        )
    return config


def load_navigator_config(filename: Path | str) -> NavigatorConfig:
    """Loads and checks a navigator YAML file; ``ConfigError`` names the file and the key."""
    return check_navigator_config(load_typed(NavigatorConfig, filename=filename), str(filename))


class Navigator(LeafSystem):
    """Drives the robot to goals on a map, avoiding obstacles seen by its lidar.

    .. pydrake_system::

        name: Navigator
        input_ports:
        - pose
        - twist
        - scan
        - localized (optional)
        output_ports:
        - cmd_vel
        - status

    ``pose`` is the robot's ``[x, y, yaw]`` (m, m, rad) in the map frame (the localisation's
    estimate); ``twist`` its measured ``[v, omega]`` (m/s, rad/s, from the odometry); ``scan``
    the lidar's ``LaserScan``, the lidar at ``X_base_sensor`` = (x, y, yaw) on the base;
    ``localized`` (1 or 0, AMCL's) is read only with ``localize_first``: the robot then turns
    and drives short legs ("localizing", ``localize_drive``) until it is 1 (or unconnected)
    or ``localization_timeout`` has passed, before its goals.
    ``cmd_vel`` is ``[v, omega]`` for the ``DiffDriveController``; ``status`` a
    ``NavigationStatus``. Updated every 1 / ``controller_frequency`` s, ``SCAN_DELAY`` after
    the tick (so a scan taken at the tick is seen by it).
    """

    def __init__(
        self,
        *,
        map: OccupancyMap,  # noqa: A002 (the contract's name)
        config: NavigatorConfig,
        X_base_sensor=(0.0, 0.0, 0.0),
        goals=(),
        localize_first: bool = False,
    ):
        super().__init__()
        self._config = check_navigator_config(config)
        if config.local_planner == "teb":
            self._dwa = TebPlanner(config.controller, config.teb)
        else:
            self._dwa = DwaPlanner(config.controller)
        self._X_base_sensor = np.array(X_base_sensor, dtype=float).reshape(3)
        goals = [_check_goal(g) for g in goals]
        model = NavState(Costmap.from_map(map, config.costmap), goals)
        if localize_first:
            model.state = "localizing"
        self._pose = self.DeclareVectorInputPort("pose", 3)
        self._localized = self.DeclareVectorInputPort("localized", 1)
        self._twist = self.DeclareVectorInputPort("twist", 2)
        self._scan = self.DeclareAbstractInputPort("scan", AbstractValue.Make(NO_SCAN))
        self._state = self.DeclareAbstractState(AbstractValue.Make(model))
        self.DeclarePeriodicUnrestrictedUpdateEvent(self._dwa.period, SCAN_DELAY, self._update)
        ticket = {self.abstract_state_ticket(self._state)}
        self.DeclareVectorOutputPort(
            "cmd_vel", 2, lambda context, out: out.SetFromVector(self._get(context).command),
            ticket,
        )  # fmt: skip
        self.DeclareAbstractOutputPort(
            "status", lambda: AbstractValue.Make(status_of(model)),
            lambda context, out: out.set_value(status_of(self._get(context))), ticket,
        )  # fmt: skip

    def _get(self, context) -> NavState:
        return context.get_abstract_state(self._state).get_value()

    def costmap(self, context) -> Costmap:
        """The global costmap in ``context`` (read only)."""
        return self._get(context).costmap

    def local_costmap(self, context) -> Costmap:
        """The rolling local costmap around the current pose input."""
        return self._get(context).costmap.local_window(self._pose.Eval(context)[:2])

    def set_goal(self, context, goal) -> None:
        """Drives to ``goal`` [x, y, yaw] (m, m, rad) from the next cycle on, preempting the
        current goal and any queued ones (RViz's "2D Nav Goal")."""
        goal = _check_goal(goal)
        new = copy.deepcopy(self._get(context))
        finish_goal(new, context.get_time(), self._pose.Eval(context), False, "preempted")
        new.queue = [goal]
        new.state = "planning"
        context.get_mutable_abstract_state(self._state).set_value(new)

    def cancel(self, context) -> None:
        """Stops: the current goal ends (not reached, "canceled") and the queue is dropped."""
        new = copy.deepcopy(self._get(context))
        finish_goal(new, context.get_time(), self._pose.Eval(context), False, "canceled")
        new.queue = []
        new.state = "idle"
        context.get_mutable_abstract_state(self._state).set_value(new)

    def _update(self, context, state):
        s = copy.deepcopy(self._get(context))
        t = context.get_time()
        pose = np.array(self._pose.Eval(context))
        scan: LaserScan = self._scan.Eval(context)
        if s.state == "localizing" and self._localize(s, t, context, scan):
            state.get_mutable_abstract_state(self._state).set_value(s)
            return
        if scan.ranges.size and scan.time > s.last_scan_time:
            sensor = compose(pose, self._X_base_sensor)
            s.costmap.update_scan(sensor, scan.ranges, scan.angles(), scan.range_max)
            s.last_scan_time = scan.time
        if s.goal is not None and s.last_xy is not None:
            s.driven += math.hypot(*(pose[:2] - s.last_xy))
        s.last_xy = pose[:2].copy()
        if s.goal is None and s.queue:
            self._start_goal(s, t, pose)
        elif s.state == "recovering":
            self._recover(s, t, pose)
        elif s.state == "following":
            self._follow(s, t, pose, np.array(self._twist.Eval(context)))
        if s.goal is None:
            s.command = np.zeros(2)
        state.get_mutable_abstract_state(self._state).set_value(s)

    def _localize(self, s: NavState, t: float, context, scan: LaserScan) -> bool:
        """While "localizing": True with this cycle's command set (turns and legs, the map
        pose unused: no costmap update either), False once settled or timed out."""
        c = self._config
        if not self._localized.HasValue(context) or t >= c.localization_timeout:
            s.state = "idle"
            return False
        if not self._localized.Eval(context)[0]:
            s.settled_after = None
        elif s.settled_after is None:
            s.settled_after = s.localize.driven
        confirm = min(c.localization_confirm, c.localization_drive)
        if s.settled_after is not None and s.localize.driven - s.settled_after >= confirm:
            s.state = "idle"
            return False
        points = np.zeros((0, 2))
        if scan.ranges.size:
            points = scan_points(scan.ranges, scan.angles(), self._X_base_sensor)
        s.localize, v, omega = localize_step(
            s.localize, self._twist.Eval(context), points, self._dwa.period,
            radius=c.costmap.robot_radius, leg=c.localization_drive,
            speed=min(c.localization_speed, c.controller.max_vel_x), spin=c.localization_spin,
        )  # fmt: skip
        s.command = np.array([v, omega])
        return True

    def _start_goal(self, s: NavState, t: float, pose) -> None:
        s.goal = s.queue.pop(0)
        s.goal_index += 1
        s.goal_start, s.driven, s.recoveries, s.at_goal_xy = t, 0.0, 0, False
        s.first_length, s.message = 0.0, ""
        s.path, s.trajectory, s.behaviour = np.zeros((0, 2)), np.zeros((0, 3)), None
        s.state = "planning"
        self._replan(s, t, pose, first=True)

    def _replan(self, s: NavState, t: float, pose, first: bool = False) -> bool:
        """Plans from ``pose`` to the goal; on failure fails the goal ("unreachable") or starts
        a recovery. Returns True if there is a new path."""
        c = self._config
        result = plan_path(s.costmap, pose[:2], s.goal[:2], c.planner)
        if result.success:
            s.path = densify(result.path, 0.5 * s.costmap.resolution)
            s.path_index, s.path_length = 0, result.length_m
            s.target = np.array([*s.path[-1], s.goal[2]])
            if first or s.first_length == 0.0:
                s.first_length = result.length_m
            s.last_plan_time = t
            if first or s.state != "following":  # a periodic replan keeps the progress clock
                s.monitor = StuckMonitor.start(pose[:2], t)
            s.state, s.message = "following", ""
            return True
        s.path = np.zeros((0, 2))
        if result.message != START_IN_OBSTACLE:
            static = copy_costmap(s.costmap)
            static.clear_obstacles()
            if not plan_path(static, pose[:2], s.goal[:2], c.planner).success:
                finish_goal(s, t, pose, False, _unreachable(result.message))
                return False
        self._start_recovery(s, t, pose, f"blocked: no path ({result.message})")
        return False

    def _follow(self, s: NavState, t: float, pose, twist) -> None:
        c = self._config
        window = int(np.ceil(1.0 / (0.5 * s.costmap.resolution)))
        ahead = s.path[s.path_index : s.path_index + window]
        if len(ahead):
            s.path_index += int(np.argmin(np.hypot(*(ahead - pose[:2]).T)))
        remaining = s.path[s.path_index :]
        due = c.replan_period > 0 and t - s.last_plan_time >= c.replan_period - 1e-9
        blocked = _blocked(s.costmap, remaining, c.planner, pose)
        near_goal = math.hypot(*(pose[:2] - s.target[:2])) <= c.controller.approach_distance
        if (due and not near_goal) or blocked:
            if not self._replan(s, t, pose):
                return
            remaining = s.path
        command = self._dwa.compute(
            pose, twist, remaining, s.target, s.costmap.local_window(pose[:2]), s.at_goal_xy
        )
        s.at_goal_xy = command.status == "rotating_to_goal"  # (nav2's stateful goal checker)
        s.command = np.array([command.v, command.omega])
        s.trajectory = command.trajectory
        if command.status == "arrived":
            finish_goal(s, t, pose, True, "")
            return
        s.monitor, stuck = s.monitor.check(pose[:2], t, command.status, c.recovery)
        if stuck:
            self._start_recovery(s, t, pose, f"blocked: {stuck}")

    def _start_recovery(self, s: NavState, t: float, pose, reason: str) -> None:
        c = self._config.recovery
        s.command = np.zeros(2)
        s.trajectory = np.zeros((0, 3))
        if s.recoveries >= c.max_recoveries:
            finish_goal(s, t, pose, False, reason)
            return
        kind = BEHAVIOURS[s.recoveries % len(BEHAVIOURS)]
        s.recoveries += 1
        s.message = reason
        s.state = "recovering"
        if kind == "clear_costmap":
            s.costmap.clear_obstacles()
            self._replan(s, t, pose)
        else:
            s.behaviour = start_behaviour(kind, pose, t)

    def _recover(self, s: NavState, t: float, pose) -> None:
        if s.behaviour is None:  # a clear_costmap whose replan failed again
            self._replan(s, t, pose)
            return
        done, v, omega = step_behaviour(s.behaviour, pose, t, s.costmap, self._config.recovery)
        s.command = np.array([v, omega])
        if done:
            s.behaviour = None
            s.command = np.zeros(2)
            self._replan(s, t, pose)


def _blocked(costmap: Costmap, dense_path, config: GlobalPlannerConfig, pose) -> bool:
    """True if a point of the dense (half-cell spaced) path lies in a cell the global planner
    may not cross (its escape cells round the robot excepted), or outside the costmap."""
    if len(dense_path) == 0:
        return False
    passable = traversal_costs(costmap, config, pose[:2])
    rows, cols = costmap.cell_of(dense_path)
    inside = costmap.inside(rows, cols)
    return bool(not np.all(inside) or np.any(passable[rows, cols] < 0))


def _check_goal(goal) -> np.ndarray:
    goal = np.asarray(goal, dtype=float).reshape(-1)
    if goal.shape != (3,) or not np.all(np.isfinite(goal)):
        raise ConfigError(f"navigator: a goal must be 3 finite numbers [x, y, yaw], got {goal}")
    return goal


def _unreachable(reason: str) -> str:
    return "unreachable" if reason in ("", "unreachable") else f"unreachable: {reason}"
