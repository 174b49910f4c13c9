"""Loop closure for the scan-matching SLAM: find where the robot is on a part of the map it
made long ago, and check it before saying so.

Each map update of the SLAM is a keyframe (a node of ``pose_graph.PoseGraph``) holding its
scan's hits in the base frame. Every ``attempt_every`` keyframes, the nearest older keyframe
(by the graph's current poses, within ``search_radius`` m) that lies at least ``min_travel`` m
back along the trajectory is a candidate; the hits of the keyframes within ``submap_travel`` m
of it along the trajectory (and not across a step the scan matcher did not check), placed at
their graph poses and cropped to where the scan can reach, make a submap (a likelihood field,
``correlative_search.make_table``), and the current scan is searched over the window around
its estimate (``window_xy`` m each way, ``window_yaw_deg``) exhaustively by branch and bound,
then refined by Gauss-Newton (``scan_matcher.match_scan``). The match is a loop closure only
when its points score at least ``min_score`` on the submap (mean likelihood: 1 when every
point sits on a hit), and when the runner-up pose more than ``ambiguity_distance`` m away
scores clearly lower (``max_ambiguity``): a corridor seen end-on matches along its length, and
a closure there would be a guess.
"""

import dataclasses as dc
import math

import numpy as np

from drake_sim.base.errors import ConfigError
from drake_sim.systems.estimation.correlative_search import ambiguous, make_table, search
from drake_sim.systems.estimation.scan_matcher import MatchMap, match_scan, transform_points


@dc.dataclass
class LoopClosureConfig:
    """Parameters of the SLAM's loop closure and pose graph (``graph_slam.GraphSlam``)."""

    enabled: bool = False  # Off: the SLAM is the scan matcher alone, as before.
    min_travel: float = 10.0  # m along the trajectory between a keyframe and a candidate.
    search_radius: float = 3.0  # m: candidates this near the current estimate.
    attempt_every: int = 2  # keyframes between two attempts.
    window_xy: float = 1.0  # m each way around the estimate.
    window_yaw_deg: float = 15.0  # degrees each way.
    yaw_step_deg: float = 0.5  # degrees between the yaws searched.
    submap_travel: float = 5.0  # m along the trajectory each side of the candidate.
    max_range: float = 20.0  # m: hits farther from their sensor are left out of the search.
    resolution: float = 0.05  # m: cells of the search's likelihood field ...
    sigma: float = 0.08  # m: ... and its width.
    min_score: float = 0.6  # mean likelihood of the scan's points on the submap.
    max_ambiguity: float = 0.9  # the runner-up's score over the best's, at most.
    ambiguity_distance: float = 0.3  # m: how far the runner-up must be.
    # Standard deviations of a keyframe-to-keyframe step of the scan matcher (m, m, degrees)
    # and of a loop closure.
    sequence_sigma: list[float] = dc.field(default_factory=lambda: [0.02, 0.02, 0.5])
    closure_sigma: list[float] = dc.field(default_factory=lambda: [0.05, 0.05, 1.0])
    # ... and of a step that rests on the odometry alone (the matcher refused a scan in it):
    # an odometry jump there is where a closure's correction belongs.
    unmatched_sigma: list[float] = dc.field(default_factory=lambda: [1.0, 1.0, 30.0])
    loss: str = "cauchy"  # The pose graph's robust loss: cauchy, huber or linear.
    loss_scale: float = 3.0  # sigmas.
    # After an optimisation that moves the current keyframe this far (m, degrees), the SLAM's
    # map is drawn again from every keyframe at its optimised pose.
    redraw_distance: float = 0.3
    redraw_angle_deg: float = 3.0

    def check(self, where: str = "LoopClosureConfig") -> None:
        """Raises ``ConfigError`` naming the first out-of-range key."""
        for key in (
            "min_travel",
            "search_radius",
            "window_xy",
            "window_yaw_deg",
            "yaw_step_deg",
            "submap_travel",
            "max_range",
            "resolution",
            "sigma",
            "loss_scale",
        ):
            if not getattr(self, key) > 0:
                raise ConfigError(f"{where}: '{key}' must be positive, got {getattr(self, key)}")
        if self.attempt_every < 1:
            raise ConfigError(f"{where}: 'attempt_every' must be at least 1")
        if not 0 < self.min_score <= 1 or not 0 < self.max_ambiguity <= 1:
            raise ConfigError(f"{where}: 'min_score' and 'max_ambiguity' must be in (0, 1]")
        for key in ("sequence_sigma", "closure_sigma", "unmatched_sigma"):
            value = getattr(self, key)
            if len(value) != 3 or min(value) <= 0:
                raise ConfigError(f"{where}: '{key}' needs 3 positive numbers (m, m, degrees)")
        if self.loss not in ("huber", "cauchy", "linear"):
            raise ConfigError(f"{where}: 'loss' must be huber, cauchy or linear, not {self.loss}")
        if self.redraw_distance < 0 or self.redraw_angle_deg < 0:
            raise ConfigError(f"{where}: 'redraw_distance' and 'redraw_angle_deg' must be >= 0")


def scan_points(ranges, angles, range_max, range_min, X_base_sensor, max_range) -> np.ndarray:
    """(n, 2) the hits of a scan in the base frame (returns within the limits and
    ``max_range``)."""
    ranges = np.asarray(ranges, dtype=float)
    hit = np.isfinite(ranges) & (ranges >= range_min) & (ranges < min(range_max, max_range))
    angles = np.asarray(angles, dtype=float)[hit]
    sensor = ranges[hit, None] * np.stack([np.cos(angles), np.sin(angles)], -1)
    return transform_points(X_base_sensor, sensor)


def candidate(
    poses: np.ndarray, travel: np.ndarray, current: int, config: LoopClosureConfig
) -> int | None:
    """The keyframe to try closing ``current``'s loop with (module docstring), or None."""
    old = np.flatnonzero(travel[:current] <= travel[current] - config.min_travel)
    if not len(old):
        return None
    distance = np.hypot(*(poses[old, :2] - poses[current, :2]).T)
    nearest = int(np.argmin(distance))
    return int(old[nearest]) if distance[nearest] <= config.search_radius else None


def close_loop(
    poses: np.ndarray,
    travel: np.ndarray,
    points: list[np.ndarray],
    current: int,
    target: int,
    config: LoopClosureConfig,
    segments: np.ndarray | None = None,
) -> tuple[np.ndarray, float] | None:
    """The pose of keyframe ``current`` on the submap around keyframe ``target`` and its score,
    if the match passes the checks (module docstring); else None.

    Args:
        poses: (n, 3) the keyframes' poses in the world (the graph's).
        travel: (n,) m along the trajectory at each keyframe.
        points: each keyframe's hits in its base frame.
        segments: (n,) keyframes of one number were matched one to the next; the submap keeps
            to ``target``'s. Across a step the matcher did not check (the odometry's alone, a
            jump perhaps) the poses may disagree, and a submap drawn across it shows two
            copies of its walls; a closure found on the other copy than ``target``'s own
            would tie the loop to the wrong one.
    """
    near = np.abs(travel - travel[target]) <= config.submap_travel
    near &= travel <= travel[current] - config.min_travel
    if segments is not None:
        near &= segments == segments[target]
    world = [transform_points(poses[k], points[k]) for k in np.flatnonzero(near)]
    world = np.concatenate([w for w in world if len(w)] or [np.zeros((0, 2))])
    scan = points[current]
    if len(scan):  # the submap's hits no pose of the window can put a scan point on: dropped
        placed = transform_points(poses[current], scan)
        turn = math.radians(config.window_yaw_deg)  # a point r away moves at most r * turn
        reach = config.window_xy + float(np.hypot(*scan.T).max()) * turn
        low, high = placed.min(0) - reach - 0.5, placed.max(0) + reach + 0.5
        world = world[np.all((world >= low) & (world <= high), axis=1)]
    if len(world) < 10 or len(scan) < 10:
        return None
    table = make_table(
        world,
        config.resolution,
        sigma=config.sigma,
        margin=config.window_xy + config.resolution,
    )
    found = search(
        table,
        scan,
        poses[current],
        window_xy=config.window_xy,
        window_yaw=math.radians(config.window_yaw_deg),
        yaw_step=math.radians(config.yaw_step_deg),
    )
    if found.score < config.min_score:
        return None
    level = MatchMap(table.fine, table.resolution, table.origin)
    refined = match_scan([level], scan, found.pose, iterations=10)
    pose, score = refined.pose, float(refined.scores[0])
    if score < found.score:
        pose, score = found.pose, found.score
    if score < config.min_score or ambiguous(
        table,
        scan,
        pose,
        score,
        distance=config.ambiguity_distance,
        max_ratio=config.max_ambiguity,
        yaw_step=math.radians(config.yaw_step_deg),
    ):
        return None
    return pose, score
