"""The local planner (controller): a sampled dynamic-window approach (DWA), like nav2's DWB.

Each control cycle (``controller_frequency``) ``DwaPlanner.compute`` turns the robot's pose,
its measured velocity, the global path, the goal and the (local) costmap into a ``cmd_vel``:

1. Near the goal it drives the last stretch with a go-to-point law that slows down in proportion
   to the distance left (and may back up a few centimetres after an overshoot), aiming at
   ``goal_precision`` times ``xy_goal_tolerance``; once there (or within the tolerance with the
   goal point off to the side) it turns on the spot to the goal's yaw, and reports ``arrived``
   (zero command) once the yaw is within ``goal_precision`` times ``yaw_goal_tolerance`` and the
   robot has stopped (measured turn rate at most ``min_vel_theta``, speed at most
   ``min_approach_vel``: a fast turn would carry it on). The tolerances are what the acceptance
   measures, so aiming inside them leaves room for the wheel controller's lag and the
   localisation's noise. Once turning to the goal's yaw it goes on turning while the estimate
   stays within twice ``xy_goal_tolerance`` (the caller passes ``at_goal_xy``: nav2's stateful
   goal checker), so an estimate that shifts a little as the robot turns does not send it back
   to the point (across nav2's open depot floor it swung to and fro for 10 s).
2. When the path ahead (the "carrot", ``lookahead_distance`` along it) lies more than
   ``rotate_to_heading_angle`` off the robot's heading it turns on the spot first (like nav2's
   rotation shim), so it never swings wide into a wall.
3. Otherwise it samples ``vx_samples`` x ``vtheta_samples`` constant commands inside the dynamic
   window (the current velocity plus or minus the acceleration limits over one control period,
   within the velocity limits), rolls each out over ``sim_time`` at the control period, drops
   every rollout that leaves the costmap or enters a cell of cost >= ``INSCRIBED`` (the
   robot's circle would touch an obstacle; from a start in the inscribed zone, only LETHAL
   cells count within ``escape_distance`` of it, so that a robot whose estimated pose lies
   there can drive out), and scores the rest like DWB's critics, in cells:
   ``path_distance_bias`` x (end point's distance to the path) + ``goal_distance_bias`` x
   (end point's distance to the carrot) + ``path_align_bias`` x (distance to the path of a
   point ``forward_point_distance`` ahead of the end pose) + ``occdist_scale`` x (largest cost
   on the rollout). An escape from the inscribed zone must end outside it. The best rollout
   is commanded. When no rollout that moves on is valid (a bend of a narrow passage, cut too
   close) it turns on the spot to the path's direction ``forward_point_distance`` ahead;
   already facing it, the status is ``no_valid_trajectory`` and the command is zero (the
   navigator then runs its recovery behaviours).

The DWA is the default. A timed-elastic-band planner (``teb_planner``, the navigator's
``local_planner: teb``) replaces step 3 with an optimised band of poses and time intervals and
keeps steps 1 and 2; it costs some tens of milliseconds a cycle against the DWA's 0.2 to 1.5 ms
(the benchmarks compare the two).

Units: m, rad, s; poses are ``[x, y, yaw]`` in the map frame.
"""

import dataclasses as dc
import math

import numpy as np

from drake_sim.base.errors import ConfigError
from drake_sim.base.planar import wrap_angle
from drake_sim.navigation.costmap import INSCRIBED, LETHAL, footprint_outline

STATUSES = ("following", "rotating_to_goal", "arrived", "no_valid_trajectory")
STEER_ANGLE = 0.1  # rad: blocked ahead, a path direction further off is turned to first.


@dc.dataclass
class DwaConfig:
    """Limits, sampling and critic weights of the DWA (nav2 DWB's names where it has them).

    The speed defaults are below the TurtleBot3's 0.26 m/s and 1.82 rad/s (they track better);
    the acceleration limits are the robot's (``config/turtlebot3.yaml``: 1.0 m/s^2, 4 rad/s^2).
    """

    controller_frequency: float = 10.0  # Hz, control cycles (the rollouts' time step too).
    max_vel_x: float = 0.22  # m/s, forward.
    min_vel_x: float = -0.1  # m/s, <= 0: the fastest backing up (final approach, recovery).
    max_vel_theta: float = (
        1.82  # rad/s (the robot's limit: turns on the spot are most of short moves).
    )
    min_vel_theta: float = 0.15  # rad/s, the slowest turn on the spot (so a turn ends).
    acc_lim_x: float = 1.0  # m/s^2.
    acc_lim_theta: float = 3.2  # rad/s^2.
    sim_time: float = 1.5  # s, rollout horizon.
    vx_samples: int = 10  # linear velocities sampled in the dynamic window.
    vtheta_samples: int = 21  # angular velocities sampled in the dynamic window.
    path_distance_bias: float = 32.0  # per cell: rollout end to the path.
    goal_distance_bias: float = 24.0  # per cell: rollout end to the carrot.
    path_align_bias: float = 16.0  # per cell: forward point to the path.
    occdist_scale: float = 0.02  # per unit of cost: the largest cost on the rollout.
    forward_point_distance: float = 0.325  # m, ahead of the rollout's end, for alignment.
    lookahead_distance: float = 0.8  # m along the path from its nearest point: the carrot.
    rotate_to_heading_angle: float = 0.8  # rad: a carrot further off is turned to on the spot.
    heading_gain: float = 3.0  # rad/s per rad of heading error, when turning or approaching.
    approach_distance: float = 0.35  # m from the goal: the go-to-point final approach.
    approach_gain: float = 2.5  # m/s per m left, in the final approach.
    min_approach_vel: float = 0.03  # m/s, the slowest final approach.
    escape_distance: float = 0.1  # m: from a start in the inscribed zone, only LETHAL blocks.
    xy_goal_tolerance: float = 0.05  # m.
    yaw_goal_tolerance: float = 0.1745  # rad (10 degrees).
    goal_precision: float = 0.3  # in (0, 1]: the fraction of each tolerance aimed at.


def check_dwa_config(
    config: DwaConfig, where: str = "local_planner", prefix: str = ""
) -> DwaConfig:
    """Returns ``config`` if its values are finite and in range; else raises ``ConfigError``
    naming ``where`` and the key (``prefix`` + field name, e.g. ``controller.max_vel_x``)."""

    def fail(name: str, rule: str) -> None:
        value = getattr(config, name)
        raise ConfigError(f"{where}: '{prefix}{name}' must be {rule}, got {value!r}")

    for field in dc.fields(config):
        name, value = field.name, getattr(config, field.name)
        if isinstance(value, bool) or not isinstance(value, int | float):
            fail(name, "a number")
        if not math.isfinite(value):
            fail(name, "finite")
        if name == "min_vel_x":
            if value > 0:
                fail(name, "<= 0")
        elif name in ("vx_samples", "vtheta_samples"):
            if value < 2:
                fail(name, "at least 2")
        elif name.endswith(("_bias", "_scale")):
            if value < 0:
                fail(name, ">= 0")
        elif not value > 0:
            fail(name, "> 0")
    if config.goal_precision > 1:
        fail("goal_precision", "in (0, 1]")
    if config.min_vel_theta > config.max_vel_theta:
        fail("min_vel_theta", f"<= max_vel_theta ({config.max_vel_theta})")
    return config


@dc.dataclass
class LocalCommand:
    """One control cycle's result.

    Attributes:
        v: m/s, the commanded forward speed.
        omega: rad/s, the commanded turn rate.
        trajectory: (k, 3) poses [x, y, yaw] the command is predicted to drive through over
            ``sim_time`` (the chosen rollout; empty with no valid trajectory).
        status: one of ``STATUSES``.
    """

    v: float
    omega: float
    trajectory: np.ndarray
    status: str


def densify(path, spacing: float) -> np.ndarray:
    """Returns the polyline ``path`` (n, 2) resampled with points at most ``spacing`` m apart
    (the original vertices kept)."""
    path = np.asarray(path, dtype=float).reshape(-1, 2)
    if len(path) < 2:
        return path.copy()
    steps = np.diff(path, axis=0)
    counts = np.maximum(1, np.ceil(np.hypot(*steps.T) / spacing).astype(int))
    segment = np.repeat(np.arange(len(steps)), counts)
    offsets = np.arange(len(segment)) - np.repeat(np.cumsum(counts) - counts, counts)
    fraction = (offsets + 1) / counts[segment]
    return np.vstack([path[:1], path[segment] + fraction[:, None] * steps[segment]])


def rollouts(pose, v, omega, dt: float, steps: int) -> np.ndarray:
    """Poses (m, steps, 3) reached by holding each command (``v[i]``, ``omega[i]``) from
    ``pose`` for ``steps`` steps of ``dt`` s (exact arcs, evaluated at each step)."""
    v = np.asarray(v, dtype=float)[:, None]
    omega = np.asarray(omega, dtype=float)[:, None]
    t = dt * np.arange(1, steps + 1)[None, :]
    yaw0 = pose[2]
    yaw = yaw0 + omega * t
    straight = np.abs(omega) < 1e-9
    safe = np.where(straight, 1.0, omega)
    x = np.where(straight, v * t * math.cos(yaw0), v / safe * (np.sin(yaw) - math.sin(yaw0)))
    y = np.where(straight, v * t * math.sin(yaw0), -v / safe * (np.cos(yaw) - math.cos(yaw0)))
    return np.stack([pose[0] + x, pose[1] + y, yaw], axis=-1)


class DwaPlanner:
    """The sampled DWA local planner; see the module docstring. Stateless between cycles."""

    def __init__(self, config: DwaConfig):
        self.config = check_dwa_config(config)

    @property
    def period(self) -> float:
        """s, one control cycle."""
        return 1.0 / self.config.controller_frequency

    def compute(self, pose, velocity, path, goal, costmap, at_goal_xy=False) -> LocalCommand:
        """The command for one cycle.

        Args:
            pose: the robot's [x, y, yaw] (m, m, rad) in the map frame.
            velocity: its measured (v, omega) (m/s, rad/s).
            path: (n, 2) the global path, start to goal (m); may be empty near the goal.
            goal: [x, y, yaw] the goal pose.
            costmap: the local ``Costmap`` (outside it counts as unknown: invalid).
            at_goal_xy: the last cycle was turning to the goal's heading (``rotating_to_goal``):
                it goes on turning while the estimate stays within twice ``xy_goal_tolerance``,
                as nav2's stateful goal checker does (a localisation that shifts a little while
                the robot turns on the spot must not send it back and forth).
        """
        c = self.config
        pose = np.asarray(pose, dtype=float)
        v0, w0 = (float(u) for u in velocity)
        goal = np.asarray(goal, dtype=float)
        to_goal = goal[:2] - pose[:2]
        distance = math.hypot(*to_goal)
        bearing = float(wrap_angle(math.atan2(to_goal[1], to_goal[0]) - pose[2]))
        xy_target = c.goal_precision * c.xy_goal_tolerance
        if (
            distance <= xy_target
            or (distance <= c.xy_goal_tolerance and abs(bearing) > math.pi / 3)
            or (at_goal_xy and distance <= 2 * c.xy_goal_tolerance)
        ):
            return self._rotate_to_goal(pose, v0, w0, goal[2], costmap)
        if distance <= c.approach_distance:
            command = self._approach(pose, v0, w0, distance, bearing, costmap)
            if command is not None:
                return command
        path = densify(path, 0.5 * costmap.resolution)
        if len(path) == 0:
            path = np.array([goal[:2]])
        nearest = int(np.argmin(np.hypot(*(path - pose[:2]).T)))
        steps = np.hypot(*np.diff(path[nearest:], axis=0).T)
        along = np.concatenate([[0.0], np.cumsum(steps)])
        last = nearest + int(np.searchsorted(along, c.lookahead_distance))
        carrot = path[min(last, len(path) - 1)]
        local = path[nearest : last + 1]
        heading = float(wrap_angle(math.atan2(carrot[1] - pose[1], carrot[0] - pose[0]) - pose[2]))
        if abs(heading) > c.rotate_to_heading_angle:
            return self._turn(pose, v0, w0, heading, "following", costmap)
        return self._follow(pose, v0, w0, path[nearest:], local, carrot, costmap)

    def _follow(self, pose, v0, w0, ahead, local, carrot, costmap) -> LocalCommand:
        """Following the path (``ahead``: the dense path from its nearest point; ``local``:
        up to the ``carrot``): the sampled rollouts (``teb_planner`` optimises a band)."""
        return self._sample(pose, v0, w0, local, carrot, costmap)

    def _limit(self, v0, w0, v, omega) -> tuple[float, float]:
        """(v, omega) limited by the velocity limits and by the accelerations over a cycle."""
        c, dt = self.config, self.period
        v = float(np.clip(v, max(c.min_vel_x, v0 - c.acc_lim_x * dt), v0 + c.acc_lim_x * dt))
        v = float(np.clip(v, c.min_vel_x, c.max_vel_x))
        lo, hi = w0 - c.acc_lim_theta * dt, w0 + c.acc_lim_theta * dt
        omega = float(np.clip(np.clip(omega, lo, hi), -c.max_vel_theta, c.max_vel_theta))
        return v, omega

    def _trajectory(self, pose, v, omega) -> np.ndarray:
        steps = max(1, round(self.config.sim_time * self.config.controller_frequency))
        return np.vstack([pose, rollouts(pose, [v], [omega], self.period, steps)[0]])

    def _turn(self, pose, v0, w0, error: float, status: str, costmap=None) -> LocalCommand:
        """Turns on the spot by ``error`` rad: proportional, at least ``min_vel_theta``, and
        slow enough to stop at the target with the angular acceleration limit (still moving
        while ``v0`` decelerates to 0 within the linear acceleration limit)."""
        c = self.config
        speed = min(
            c.heading_gain * abs(error),
            math.sqrt(2 * c.acc_lim_theta * abs(error)),
            c.max_vel_theta,
        )
        speed = max(speed, c.min_vel_theta)
        v, omega = self._limit(v0, w0, 0.0, math.copysign(speed, error))
        trajectory = self._trajectory(pose, v, omega)
        if costmap is not None and not outline_clear(trajectory[None, 1:], costmap)[0]:
            return LocalCommand(0.0, 0.0, np.empty((0, 3)), "no_valid_trajectory")
        return LocalCommand(v, omega, trajectory, status)

    def _rotate_to_goal(self, pose, v0, w0, goal_yaw: float, costmap=None) -> LocalCommand:
        c = self.config
        error = float(wrap_angle(goal_yaw - pose[2]))
        if abs(error) <= c.goal_precision * c.yaw_goal_tolerance:
            if abs(w0) <= c.min_vel_theta and abs(v0) <= c.min_approach_vel:
                return LocalCommand(0.0, 0.0, pose[None, :].copy(), "arrived")
            # Still moving (a fast turn ends here): stop first, arrive once stopped (a turn
            # that stops past the tolerance is corrected by the next cycles).
            return LocalCommand(0.0, 0.0, pose[None, :].copy(), "rotating_to_goal")
        return self._turn(pose, v0, w0, error, "rotating_to_goal", costmap)

    def _passable(self, costs, xy, pose, costmap) -> np.ndarray:
        """Which of the cells at ``xy`` (..., 2), of ``costs``, the robot's centre may cross
        on a move from ``pose``: those below INSCRIBED, and when ``pose`` itself is in the
        inscribed zone, those below LETHAL within ``escape_distance`` of it."""
        if costmap.cost_at(pose[:2]) < INSCRIBED:
            return costs < INSCRIBED
        near = np.hypot(xy[..., 0] - pose[0], xy[..., 1] - pose[1]) <= self.config.escape_distance
        return costs < np.where(near, LETHAL, INSCRIBED)

    def _approach(self, pose, v0, w0, distance, bearing, costmap) -> LocalCommand | None:
        """The go-to-point final approach, or None when the straight line to the goal is not
        clear (the DWA then handles it)."""
        c = self.config
        n = max(2, math.ceil(distance / (0.5 * costmap.resolution)) + 1)
        heading = bearing + pose[2]
        line = pose[:2] + np.outer(
            np.linspace(0.0, distance, n), [math.cos(heading), math.sin(heading)]
        )
        if not np.all(self._passable(costmap.cost_at(line), line, pose, costmap)):
            return None
        ahead = np.column_stack([line, np.full(len(line), pose[2])])
        if not outline_clear(ahead[None], costmap)[0]:
            return None
        backwards = abs(bearing) > math.pi / 2 and distance <= 3 * c.xy_goal_tolerance
        error = float(wrap_angle(bearing - math.pi)) if backwards else bearing
        if abs(error) > c.rotate_to_heading_angle:
            return self._turn(pose, v0, w0, error, "following", costmap)
        speed = max(c.min_approach_vel, c.approach_gain * distance) * math.cos(error)
        speed = -min(speed, -c.min_vel_x) if backwards else min(speed, c.max_vel_x)
        v, omega = self._limit(v0, w0, speed, c.heading_gain * error)
        return LocalCommand(v, omega, self._trajectory(pose, v, omega), "following")

    def _sample(self, pose, v0, w0, local, carrot, costmap) -> LocalCommand:
        c, dt = self.config, self.period
        v_lo = max(0.0, v0 - c.acc_lim_x * dt)
        v_hi = max(v_lo, min(c.max_vel_x, v0 + c.acc_lim_x * dt))
        w_lo = max(-c.max_vel_theta, w0 - c.acc_lim_theta * dt)
        w_hi = min(c.max_vel_theta, w0 + c.acc_lim_theta * dt)
        vs, ws = np.meshgrid(
            np.linspace(v_lo, v_hi, c.vx_samples), np.linspace(w_lo, w_hi, c.vtheta_samples)
        )
        vs, ws = vs.ravel(), ws.ravel()
        steps = max(1, round(c.sim_time * c.controller_frequency))
        poses = rollouts(pose, vs, ws, dt, steps)
        cost = costmap.cost_at(poses[..., :2]).astype(float)
        valid = np.all(self._passable(cost, poses[..., :2], pose, costmap), axis=1)
        valid &= cost[:, -1] < INSCRIBED  # an escape must get out
        valid &= outline_clear(poses, costmap)
        if not np.any(valid & (vs > 1e-6)):  # nothing drives on: turn to the path, or stop
            return self._blocked_ahead(pose, v0, w0, local, costmap)
        poses, cost, vs, ws = poses[valid], cost[valid], vs[valid], ws[valid]
        end = poses[:, -1]
        ahead = end[:, :2] + c.forward_point_distance * np.column_stack(
            [np.cos(end[:, 2]), np.sin(end[:, 2])]
        )
        cell = costmap.resolution
        score = (
            c.path_distance_bias * _distance_to(end[:, :2], local) / cell
            + c.goal_distance_bias * np.hypot(*(end[:, :2] - carrot).T) / cell
            + c.path_align_bias * _distance_to(ahead, local) / cell
            + c.occdist_scale * cost.max(axis=1)
        )
        best = int(np.argmin(score))
        trajectory = np.vstack([pose, poses[best]])
        return LocalCommand(float(vs[best]), float(ws[best]), trajectory, "following")

    def _blocked_ahead(self, pose, v0, w0, local, costmap) -> LocalCommand:
        """No rollout that moves on is valid (a bend of a narrow passage cut too close): turn
        on the spot to the path's direction ``forward_point_distance`` ahead, when that is
        more than ``STEER_ANGLE`` off; else (or if the turn is not clear) nothing is valid."""
        target = _along(local, self.config.forward_point_distance)
        error = float(wrap_angle(math.atan2(target[1] - pose[1], target[0] - pose[0]) - pose[2]))
        if math.hypot(*(target - pose[:2])) > 1e-6 and abs(error) > STEER_ANGLE:
            return self._turn(pose, v0, w0, error, "following", costmap)
        return LocalCommand(0.0, 0.0, np.empty((0, 3)), "no_valid_trajectory")


def outline_clear(poses: np.ndarray, costmap) -> np.ndarray:
    """For each rollout of ``poses`` (m, steps, 3): True when the costmap's footprint polygon
    (``CostmapConfig.footprint``; none: the circle, checked by the centre's cost) touches no
    LETHAL cell at any of its poses, as DWB's footprint check does."""
    footprint = costmap.config.footprint
    if not footprint:
        return np.ones(len(poses), dtype=bool)
    outline = footprint_outline(footprint, 0.5 * costmap.resolution)  # (k, 2)
    c, s = np.cos(poses[..., 2])[..., None], np.sin(poses[..., 2])[..., None]
    x = poses[..., 0][..., None] + c * outline[:, 0] - s * outline[:, 1]
    y = poses[..., 1][..., None] + s * outline[:, 0] + c * outline[:, 1]
    costs = costmap.cost_at(np.stack([x, y], axis=-1))
    return np.all(costs < LETHAL, axis=(1, 2))


def _along(path: np.ndarray, distance: float) -> np.ndarray:
    """The point of the dense ``path`` (n, 2) about ``distance`` m along it (its end if shorter)."""
    along = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(path, axis=0).T))])
    return path[min(int(np.searchsorted(along, distance)), len(path) - 1)]


def _distance_to(points: np.ndarray, path: np.ndarray) -> np.ndarray:
    """Distance (m) from each of ``points`` (m, 2) to the nearest of the dense ``path``."""
    d = points[:, None, :] - path[None, :, :]
    return np.sqrt(np.min(np.sum(d * d, axis=-1), axis=1))
