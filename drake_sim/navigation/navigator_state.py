"""What the navigator keeps and tells: its state between cycles (``NavState``: costmap, goals,
path, state machine), how each goal ended (``GoalResult``) and its ``status`` output
(``NavigationStatus``).

``Navigator`` (``drake_sim.navigation.navigator``) holds one ``NavState`` in its abstract
state, copies it at each update (``copy.deepcopy``: the costmap's layers are copied, arrays
that are only ever replaced are shared) and replaces it, never mutating it in place.
"""

import copy
import dataclasses as dc
import math

import numpy as np

from drake_sim.navigation.costmap import Costmap
from drake_sim.navigation.localize_drive import LocalizeDrive
from drake_sim.navigation.recovery import StuckMonitor

STATES = ("idle", "localizing", "planning", "following", "recovering", "arrived", "failed")


@dc.dataclass
class GoalResult:
    """How one goal ended.

    Attributes:
        goal: [x, y, yaw] (m, m, rad).
        reached: True when the local planner arrived within the goal tolerances.
        message: "" when reached; else why not ("unreachable: ...", "blocked: ...",
            "canceled", "preempted").
        time_s: s from the goal's start to its end.
        path_length_m: m, the length of the first global path planned to it (0 if none).
        driven_m: m, the distance the robot's pose moved while on this goal.
        final_pose: [x, y, yaw] at the end (the navigator's pose input).
    """

    goal: np.ndarray
    reached: bool
    message: str
    time_s: float
    path_length_m: float
    driven_m: float
    final_pose: np.ndarray


@dc.dataclass(frozen=True)
class NavigationStatus:
    """The navigator's ``status`` output.

    Attributes:
        state: one of ``STATES``.
        goal: the current (or last) goal [x, y, yaw], or None before any.
        message: why the last goal failed ("" otherwise).
        path: (n, 2) m, the current global path (empty without one).
        local_trajectory: (k, 3) the local planner's chosen rollout (empty without one).
        path_length_m: m, the current global path's length.
        goal_index: the index of the current (or last) goal among all goals started (-1
            before any).
        results: one ``GoalResult`` per finished goal, in order.
        pending: goals still queued after the current one.
        costmap: the global ``Costmap`` (map, scans, inflation) for display; read only.
    """

    state: str
    goal: np.ndarray | None
    message: str
    path: np.ndarray
    local_trajectory: np.ndarray
    path_length_m: float
    goal_index: int
    results: tuple
    pending: int
    costmap: Costmap | None = None

    @property
    def finished(self) -> bool:
        """True when no goal is active or queued."""
        return self.state in ("idle", "arrived", "failed") and self.pending == 0


class NavState:
    """What the navigator keeps between cycles (its abstract state)."""

    def __init__(self, costmap: Costmap, goals):
        self.costmap = costmap  # the global costmap: map, scans, inflation.
        self.queue = [np.array(g, dtype=float) for g in goals]  # goals after the current one.
        self.goal = None  # [x, y, yaw] being driven to, or None.
        self.target = None  # where the path ends: the goal, or the nearest reachable cell.
        self.goal_index, self.state, self.message = -1, "idle", ""
        self.command = np.zeros(2)  # [v, omega] cmd_vel.
        self.path = np.zeros((0, 2))  # the global path, densified to half cells.
        self.path_index = 0  # the path point nearest the robot (it only moves on).
        self.path_length = self.first_length = 0.0  # m, the current and the first path's.
        self.trajectory = np.zeros((0, 3))  # the local planner's chosen rollout.
        self.last_scan_time = self.last_plan_time = -math.inf
        self.goal_start = self.driven = 0.0  # s, m.
        self.last_xy = None
        self.monitor = StuckMonitor()
        self.recoveries = 0  # recovery behaviours run for this goal.
        self.at_goal_xy = False  # the goal's position reached: only its heading is left.
        self.behaviour = None  # the running recovery Behaviour.
        self.localize = LocalizeDrive()  # turns and legs while "localizing".
        self.settled_after = None  # m driven while localizing when AMCL last settled.
        self.results: list[GoalResult] = []

    def __deepcopy__(self, memo):
        # Arrays held here (path, goal, poses) are replaced, never changed in place, so they
        # are shared; the costmap's layers and the running behaviour are copied.
        other = copy.copy(self)
        other.costmap = copy_costmap(self.costmap)
        other.queue = list(self.queue)
        other.results = list(self.results)
        other.behaviour = copy.copy(self.behaviour)
        return other


def copy_costmap(costmap: Costmap) -> Costmap:
    """A copy of ``costmap`` with its own layers (its config is shared: never mutated)."""
    other = copy.copy(costmap)
    for name in ("static_layer", "obstacle_layer", "costs"):
        setattr(other, name, getattr(costmap, name).copy())
    return other


def finish_goal(s: NavState, t: float, pose, reached: bool, message: str) -> None:
    """Ends the current goal (if any) with a result; the state becomes "arrived" or "failed"."""
    if s.goal is None:
        return
    pose = np.array(pose, dtype=float)
    elapsed = t - s.goal_start
    result = GoalResult(s.goal, reached, message, elapsed, s.first_length, s.driven, pose)
    s.results.append(result)
    s.state, s.message = ("arrived" if reached else "failed"), message
    s.goal, s.behaviour = None, None
    s.command, s.trajectory = np.zeros(2), np.zeros((0, 3))


def status_of(s: NavState) -> NavigationStatus:
    """The ``status`` output for the state ``s``."""
    last = s.goal if s.goal is not None else (s.results[-1].goal if s.results else None)
    goal = None if last is None else last.copy()
    return NavigationStatus(s.state, goal, s.message, s.path, s.trajectory, s.path_length,
                            s.goal_index, tuple(s.results), len(s.queue), s.costmap)  # fmt: skip
