"""A timed-elastic-band local planner (TEB; Rösmann et al. 2012, ROS's ``teb_local_planner``):
the path ahead becomes a band of poses with a time interval between each two, optimised for
time against the distance to obstacles, the velocity and acceleration limits and the
differential drive's kinematics; the first interval's motion is commanded.

Each control cycle, while following (the final approach and the turns on the spot are the
DWA's, ``local_planner``):

1. the band: the global path ahead, up to ``max_global_plan_lookahead_dist`` and inside the
   local costmap, resampled every ``dt_ref`` x ``max_vel_x`` (at most ``max_poses`` poses),
   from the robot's pose (fixed) to the last point (fixed, heading along the path); each
   interval starts at its length over ``max_vel_x``;
2. the optimisation: the inner poses and every interval (as its logarithm), by scipy's
   ``least_squares`` (MINPACK's Levenberg-Marquardt, the Jacobian by forward differences with
   the columns that share no residual perturbed together) over TEB's soft constraints as squared
   residuals, each with teb_local_planner's weight: time (``weight_optimaltime``: the
   intervals), the non-holonomic kinematics (``weight_kinematics_nh``: consecutive headings must
   agree with the chord between them, an arc), driving forward
   (``weight_kinematics_forward_drive``), velocity and acceleration limits
   (``weight_max_vel_*``, ``weight_acc_lim_*``, the first acceleration from the measured
   velocity), and obstacles (``weight_obstacle``: each pose's clearance, from an exact distance
   transform of the local costmap's lethal cells, less the robot's radius, under
   ``min_obstacle_dist``);
3. the command: the first interval's forward speed and turn rate, within the DWA's limits and
   dynamic window; the band is the predicted trajectory.

A band whose first ``feasibility_check_no_poses`` poses (or the command's own rollout, with the
costmap's footprint polygon where it has one) would touch an obstacle is not driven: that cycle
falls back to the sampled DWA (teb_local_planner would ask for a recovery instead; the DWA's
valid rollouts are the safer choice here).

Units: m, rad, s; poses are ``[x, y, yaw]`` in the map frame.
"""

import dataclasses as dc
import math

import numpy as np
from scipy import ndimage
from scipy.optimize import least_squares

from drake_sim.base.errors import ConfigError
from drake_sim.base.planar import wrap_angle
from drake_sim.navigation.costmap import LETHAL
from drake_sim.navigation.local_planner import DwaConfig, DwaPlanner, LocalCommand, outline_clear


@dc.dataclass
class TebConfig:
    """The band's settings (teb_local_planner's names); the limits and goal tolerances are
    the controller's (``DwaConfig``: ``max_vel_x``, ``acc_lim_x``, ...)."""

    dt_ref: float = 0.3  # s, the intervals' reference (the band's spacing at top speed).
    max_poses: int = 20  # the band's poses at most.
    max_global_plan_lookahead_dist: float = 1.2  # m of the global path the band covers.
    min_obstacle_dist: float = 0.05  # m the robot's circle keeps from obstacles.
    feasibility_check_no_poses: int = 5  # poses of the band checked before it is driven.
    no_inner_iterations: int = 15  # the solver's steps per cycle, at most.
    weight_optimaltime: float = 1.0
    weight_kinematics_nh: float = 1000.0
    weight_kinematics_forward_drive: float = 1.0
    weight_max_vel_x: float = 2.0
    weight_max_vel_theta: float = 1.0
    weight_acc_lim_x: float = 1.0
    weight_acc_lim_theta: float = 1.0
    weight_obstacle: float = 50.0


def check_teb_config(config: TebConfig, where: str = "teb", prefix: str = "") -> TebConfig:
    """Returns ``config`` if every value is a finite number in range (weights >= 0, the rest
    > 0, ``max_poses`` >= 3); else raises ``ConfigError`` naming ``where`` and the key."""
    for field in dc.fields(config):
        name, value = field.name, getattr(config, field.name)
        ok = not isinstance(value, bool) and isinstance(value, int | float)
        ok = ok and math.isfinite(value)
        ok = ok and (value >= 0 if name.startswith("weight_") else value > 0)
        if name == "max_poses":
            ok = ok and value >= 3
        if not ok:
            rule = ">= 0" if name.startswith("weight_") else "> 0"
            if name == "max_poses":
                rule = "an integer >= 3"
            raise ConfigError(f"{where}: '{prefix}{name}' must be {rule}, got {value!r}")
    return config


class TebPlanner(DwaPlanner):
    """The DWA with its sampled following replaced by a timed elastic band (module
    docstring)."""

    def __init__(self, config: DwaConfig, teb: TebConfig):
        super().__init__(config)
        self.teb = check_teb_config(teb)
        self._structures: dict[int, tuple] = {}  # band size -> ``band_structure``

    def _follow(self, pose, v0, w0, ahead, local, carrot, costmap) -> LocalCommand:
        band = self._band(pose, ahead, costmap)
        if band is not None:
            command = self._optimised(pose, v0, w0, band, costmap)
            if command is not None:
                return command
        return self._sample(pose, v0, w0, local, carrot, costmap)

    def _band(self, pose, ahead, costmap):
        """(poses (n, 3), intervals (n - 1,)) to start from, or None when the path ahead is
        too short for a band."""
        c, t = self.config, self.teb
        if len(ahead) < 2:
            return None
        steps = np.hypot(*np.diff(ahead, axis=0).T)
        along = np.concatenate([[0.0], np.cumsum(steps)])
        inside = costmap.inside(*costmap.cell_of(ahead))
        last = int(np.argmin(inside)) - 1 if not np.all(inside) else len(ahead) - 1
        length = min(along[max(last, 0)], t.max_global_plan_lookahead_dist)
        spacing = max(t.dt_ref * c.max_vel_x, length / (t.max_poses - 1))
        n = int(length // spacing) + 1
        if n < 3:
            return None
        stations = np.linspace(0.0, length, n)
        xy = np.column_stack([np.interp(stations, along, ahead[:, k]) for k in (0, 1)])
        xy[0] = pose[:2]
        chords = np.diff(xy, axis=0)
        yaw = np.arctan2(chords[:, 1], chords[:, 0])
        yaw = np.concatenate([[pose[2]], yaw[1:], [yaw[-1]]])
        yaw = pose[2] + np.concatenate([[0.0], np.cumsum(wrap_angle(np.diff(yaw)))])
        intervals = np.maximum(np.hypot(*chords.T) / c.max_vel_x, 1e-2)
        return np.column_stack([xy, yaw]), intervals

    def _optimised(self, pose, v0, w0, band, costmap) -> LocalCommand | None:
        """The band optimised and its first interval's command, or None when it is not
        feasible."""
        poses, intervals = band
        field = _ClearanceField(costmap)
        n = len(poses)
        if n not in self._structures:
            self._structures[n] = band_structure(n)
        structure = self._structures[n]
        problem = _BandProblem(poses, v0, w0, self.config, self.teb, field, structure)
        result = least_squares(
            problem.residuals,
            problem.pack(poses, intervals),
            jac=problem.jacobian,
            method="lm",
            max_nfev=self.teb.no_inner_iterations,
            x_scale="jac",
        )
        poses, intervals = problem.unpack(result.x)
        check = poses[: self.teb.feasibility_check_no_poses + 1]
        if np.any(field.clearance(check[:, :2]) <= 0.0):
            return None
        step = poses[1] - poses[0]
        v = (math.cos(pose[2]) * step[0] + math.sin(pose[2]) * step[1]) / intervals[0]
        v, omega = self._limit(v0, w0, max(v, 0.0), step[2] / intervals[0])
        trajectory = self._trajectory(pose, v, omega)
        clear = costmap.cost_at(trajectory[:, :2]) < LETHAL
        clear = np.all(clear) and np.all(field.clearance(trajectory[:, :2]) > 0.0)
        if not (clear and outline_clear(trajectory[None, 1:], costmap)[0]):
            return None  # a footprint polygon is checked as the DWA checks it
        return LocalCommand(v, omega, poses, "following")


class _ClearanceField:
    """The distance (m) from a point to the local costmap's nearest lethal cell less the
    robot's radius (bilinear between cell centres; outside the window, the window's edge)."""

    def __init__(self, costmap):
        lethal = costmap.costs >= LETHAL
        self._grid = costmap
        if np.any(lethal):
            distance = ndimage.distance_transform_edt(~lethal) * costmap.resolution
        else:
            distance = np.full(lethal.shape, 10.0)
        self._distance = distance - costmap.config.robot_radius

    def clearance(self, xy) -> np.ndarray:
        """(k,) clearance of each point of ``xy`` (k, 2)."""
        rows, cols = self._distance.shape
        f = self._grid.to_grid(xy) - 0.5
        c = np.clip(f[:, 0], 0.0, cols - 1.000001)
        r = np.clip(f[:, 1], 0.0, rows - 1.000001)
        c0, r0 = np.floor(c).astype(int), np.floor(r).astype(int)
        c1, r1 = np.minimum(c0 + 1, cols - 1), np.minimum(r0 + 1, rows - 1)
        u, w = c - c0, r - r0
        d = self._distance
        return (1 - w) * ((1 - u) * d[r0, c0] + u * d[r0, c1]) + w * (
            (1 - u) * d[r1, c0] + u * d[r1, c1]
        )


class _BandProblem:
    """The band's least-squares problem: the inner poses and the intervals as one vector,
    the weighted soft constraints as residuals."""

    def __init__(self, poses, v0, w0, dwa: DwaConfig, teb: TebConfig, field, structure=None):
        """``structure``: ``band_structure(len(poses))``, when the caller keeps it."""
        self.first, self.last = poses[0].copy(), poses[-1].copy()
        self.n = len(poses)
        self.v0, self.w0 = v0, w0
        self.dwa, self.teb, self.field = dwa, teb, field
        inner = 3 * (self.n - 2)
        self.dt_slice = slice(inner, inner + self.n - 1)
        self._pattern, self._groups = structure or band_structure(self.n)

    def jacobian(self, x) -> np.ndarray:
        """The residuals' Jacobian by forward differences, the columns that share no residual
        perturbed together (a dozen evaluations instead of one per variable)."""
        f0 = self.residuals(x)
        out = np.zeros((len(f0), len(x)))
        h = 1e-6 * np.maximum(1.0, np.abs(x))
        for group in self._groups:
            step = np.zeros(len(x))
            step[group] = h[group]
            df = self.residuals(x + step) - f0
            for col in group:
                rows = self._pattern[:, col]
                out[rows, col] = df[rows] / h[col]
        return out

    def pack(self, poses, intervals) -> np.ndarray:
        """The variables: the inner poses, then the intervals' logarithms (an interval stays
        positive without bounds, so MINPACK's Levenberg-Marquardt can solve it)."""
        return np.concatenate([poses[1:-1].ravel(), np.log(intervals)])

    def unpack(self, x) -> tuple[np.ndarray, np.ndarray]:
        inner = x[: 3 * (self.n - 2)].reshape(-1, 3)
        return np.vstack([self.first, inner, self.last]), np.exp(x[self.dt_slice])

    def residuals(self, x) -> np.ndarray:
        d, t = self.dwa, self.teb
        poses, dt = self.unpack(x)
        step = np.diff(poses, axis=0)
        c, s = np.cos(poses[:, 2]), np.sin(poses[:, 2])
        nh = (c[:-1] + c[1:]) * step[:, 1] - (s[:-1] + s[1:]) * step[:, 0]
        forward = c[:-1] * step[:, 0] + s[:-1] * step[:, 1]
        length = np.hypot(step[:, 0], step[:, 1])
        v = np.sign(forward) * length / dt
        omega = step[:, 2] / dt
        mid = 0.5 * (dt[:-1] + dt[1:])
        a = np.diff(np.concatenate([[self.v0], v])) / np.concatenate([[dt[0]], mid])
        alpha = np.diff(np.concatenate([[self.w0], omega])) / np.concatenate([[dt[0]], mid])
        clearance = self.field.clearance(poses[1:-1, :2])
        parts = (
            (t.weight_optimaltime, dt),
            (t.weight_kinematics_nh, nh),
            (t.weight_kinematics_forward_drive, np.maximum(0.0, -forward)),
            (t.weight_max_vel_x, np.maximum(0.0, np.abs(v) - d.max_vel_x)),
            (t.weight_max_vel_theta, np.maximum(0.0, np.abs(omega) - d.max_vel_theta)),
            (t.weight_acc_lim_x, np.maximum(0.0, np.abs(a) - d.acc_lim_x)),
            (t.weight_acc_lim_theta, np.maximum(0.0, np.abs(alpha) - d.acc_lim_theta)),
            (t.weight_obstacle, np.maximum(0.0, t.min_obstacle_dist - clearance)),
        )
        return np.concatenate([math.sqrt(w) * r for w, r in parts])


def band_structure(n: int) -> tuple[np.ndarray, list[np.ndarray]]:
    """For a band of ``n`` poses: which variables each residual depends on (``_BandProblem``'s
    order; rows x columns, bool) and the column groups that share no residual (``_colour``).
    The same for every band of that size: ``TebPlanner`` makes it once per size."""
    k = n - 1  # intervals
    pose_cols = [[] if i in (0, n - 1) else list(range(3 * (i - 1), 3 * i)) for i in range(n)]
    dt_col = [3 * (n - 2) + j for j in range(k)]
    rows = []
    rows += [[dt_col[j]] for j in range(k)]  # time
    segment = [pose_cols[j] + pose_cols[j + 1] for j in range(k)]
    rows += segment  # non-holonomic
    rows += segment  # forward
    rows += [segment[j] + [dt_col[j]] for j in range(k)] * 2  # v, omega
    for _ in range(2):  # a, alpha: this interval and the one before
        for j in range(k):
            cols = segment[j] + [dt_col[j]]
            if j:
                cols += segment[j - 1] + [dt_col[j - 1]]
            rows.append(cols)
    rows += [pose_cols[i] for i in range(1, n - 1)]  # obstacles
    pattern = np.zeros((len(rows), 3 * (n - 2) + k), dtype=bool)
    for r, cols in enumerate(rows):
        pattern[r, cols] = True
    return pattern, _colour(pattern)


def _colour(pattern: np.ndarray) -> list[np.ndarray]:
    """Groups of columns of ``pattern`` (rows x columns, bool) no two of which share a row
    (greedy, in column order)."""
    groups, used = [], []
    for col in range(pattern.shape[1]):
        rows = pattern[:, col]
        for k, taken in enumerate(used):
            if not np.any(taken & rows):
                groups[k].append(col)
                taken |= rows
                break
        else:
            groups.append([col])
            used.append(rows.copy())
    return [np.array(g) for g in groups]
