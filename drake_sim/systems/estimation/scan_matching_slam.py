"""2D SLAM by scan-to-map matching with odometry as the prior, in the spirit of hector_slam.

Every scan: predict the base pose by composing the odometry's motion since the previous scan
(in the robot frame) onto the last estimate, match the scan against the map pyramid from that
prediction (``scan_matcher.match_scan``, coarse to fine, a weak prior towards the prediction),
and keep the match unless it strays from the prediction by more than the gate
(``max_correction`` m, ``max_correction_deg``) or scores too low, in which case the prediction
stands (odometry bridges a bad scan). Where the scan's surfaces all face one way (a corridor,
``scan_matcher.normal_spread``) and it has no depth steps along them (no door jambs:
``scan_matcher.depth_edges``), the position along them is the prediction's. The map (one
``LogOddsGrid`` per pyramid level, as in hector_slam) takes the scan only when the robot has
moved ``map_update_distance`` or turned ``map_update_angle_deg`` since the last map update,
and always for the first scans: updating with every scan writes each scan's small errors into
the map it is matched against.

Each hit goes into the grids half a cell beyond the beam's end along the surface's normal
(``SlamConfig.hit_offset``, ``scan_matcher.surface_normals``), and each level is matched at
the points where its grid put the hits. With hector's marking (the cell holding the end point) a
wall whose face lies on a cell edge is drawn two cells thick, the pose can slide across that
double cell, and it did, by a constant 1.2 cm, with the map drawn that far off: the shipped
arenas, seed 0, pose RMSE 0.017 / 0.019 / 0.036 m (room, maze, warehouse), and of the map's
occupied cells within the outer walls' faces 0.33 to 0.53 occupied in the truth. Half a cell
along the normal: 0.87 to 0.97 of those cells true, and with ``range_margin`` too, RMSE over
seeds 0 to 2 0.005 / 0.006 to 0.023 / 0.013 to 0.018 m (``benchmarks/mapping_benchmark.py``).
Half a cell along the *beam* instead was as good on average but drifted in yaw on one maze
run (5 cm RMSE): a beam meeting a wall at a grazing angle moves along the wall, not into it,
and lands on the edge again.

The defaults were chosen by measurement on a synthetic 8 m x 6 m room (30 m route, 2 % and
0.5 deg/m of odometry drift; ``tests/slam_helpers.py``), RMSE of the pose against the truth over
6 to 14 seeds: hector's probability maps with 0.05 m finest cells: 0.035 to 0.1 m; plus one
0.025 m level: 0.017 to 0.087 m (a fine map's peaks sit at its cell centres); Gaussian-blurred
maps: no better (0.5 cell) or worse (0.7 cell: 0.09 to 0.1 m); likelihood fields (``field``)
with each level starting from the better of the coarser result and the prediction: 0.016 to
0.045 m, the defaults. On the shipped arenas (``benchmarks/slam_benchmark.py``, ray-marched
scans): 0.016 to 0.017 m with hector's marking, 0.004 to 0.011 m with the hit offset and range
margin below, about 4 to 5 ms per scan.

The map frame is the world frame: the first scan is inserted at ``initial_pose``, and the grids
(``map_size`` m square) are centred on it, or on ``map_center`` (``slam_config.map_square``:
the place, when a square centred on the start misses it), on one lattice (multiples of the
coarsest cell) wherever it is centred. A scan whose returns reach beyond the grids (within
``map_size`` of the sensor) extends them first (``occupancy_grid.grow_to_cover``), on that lattice.
"""

import copy
import math
from pathlib import Path

import numpy as np

from drake_sim.base.map_files import OccupancyMap, save_map
from drake_sim.base.planar import compose, relative_pose, same_pose
from drake_sim.systems.estimation.correlative_search import (
    ambiguous,
    make_table,
    occupied_points,
    search,
)
from drake_sim.systems.estimation.loop_closure import scan_points
from drake_sim.systems.estimation.match_updates import update_level
from drake_sim.systems.estimation.occupancy_grid import LogOddsGrid, grow_to_cover
from drake_sim.systems.estimation.scan_matcher import (
    MatchMap,
    MatchResult,
    depth_edges,
    match_scan,
    normal_spread,
    surface_normals,
    transform_points,
)
from drake_sim.systems.estimation.slam_config import SlamConfig


class ScanMatchingSlam:
    """Online 2D SLAM: feed it scans and odometry, read the pose and the map.

    Args:
        config: the parameters.
        initial_pose: (x, y, yaw) of the base in the world at the first scan (m, rad).
        X_base_sensor: (x, y, yaw) of the lidar frame in the base frame (m, rad).
        map_center: (x, y) m, the centre of the square maps (None: ``initial_pose``'s).
    """

    def __init__(
        self,
        config: SlamConfig | None = None,
        initial_pose=(0.0, 0.0, 0.0),
        X_base_sensor=(0.0, 0.0, 0.0),
        map_center=None,
    ):
        self.config = config = config if config is not None else SlamConfig()
        config.check()
        self.X_base_sensor = np.array(X_base_sensor, dtype=float)
        self._pose = np.array(initial_pose, dtype=float)
        center = self._pose[:2] if map_center is None else np.asarray(map_center, dtype=float)
        if center.shape != (2,) or not np.all(np.isfinite(center)):
            raise ValueError(f"map_center must be finite (x, y), got {map_center!r}")
        coarsest = config.resolution * 2 ** (config.levels - 1)
        corner = [
            round(math.floor((v - config.map_size / 2) / coarsest) * coarsest, 9) for v in center
        ]
        self.grids = [
            LogOddsGrid(
                resolution=config.resolution * 2.0**k,
                size=(config.map_size, config.map_size),
                origin=tuple(corner),
                p_hit=config.p_hit,
                p_miss=config.p_miss,
                clamp=config.clamp,
                hit_offset=config.hit_offset,
            )
            for k in range(-config.fine_levels, config.levels)
        ]
        for grid in self.grids:
            grid.track_changes = True  # for the match levels' updates (``_pyramid``)
        self.map_level = config.fine_levels  # Index in ``grids`` of the map at ``resolution``.
        self._match_maps: list[MatchMap | None] = [None] * len(self.grids)
        self._match_versions = [-1] * len(self.grids)
        self._odom = None
        self._last_map_pose = None
        self._trajectory = []
        self._times = []
        self.map_updates = 0
        self.rejected = 0  # Matches rejected by the gate (the odometry's prediction was kept).
        self.degenerate = 0  # Matches with a direction the scan did not constrain.
        self.recovered = 0  # Rejected matches a search around the prediction found again.
        self.last_match: MatchResult | None = None
        # The last scan put into the map: (ranges, angles, range_max, range_min, normals).
        self.last_insert: tuple | None = None
        self._maps_shared = False  # ``grids`` and ``_match_maps`` shared with a copy

    def __deepcopy__(self, memo):
        """A copy (``SlamSystem`` makes one per scan): the trajectory's poses and times never
        change once appended, so shared (copied deeply, 120 s of exploring the warehouse copied
        581,000 arrays, 8.7 of its 39 s); the grids and match levels too, until either side
        changes them (``_own_maps``: a scan that updates the map, one in four or five)."""
        other = ScanMatchingSlam.__new__(ScanMatchingSlam)
        memo[id(self)] = other
        for key, value in self.__dict__.items():
            shared = key in ("_trajectory", "_times", "grids", "_match_maps")
            setattr(other, key, list(value) if shared else copy.deepcopy(value, memo))
        self._maps_shared = other._maps_shared = True
        return other

    def _own_maps(self) -> None:  # Before the grids or levels change: copies them if shared.
        if self._maps_shared:
            self.grids = [copy.deepcopy(grid) for grid in self.grids]
            self._match_maps = [copy.deepcopy(level) for level in self._match_maps]
            self._maps_shared = False

    @property
    def pose(self) -> np.ndarray:
        """The current estimate (x, y, yaw) of the base in the world (m, rad)."""
        return self._pose.copy()

    @property
    def odometry(self) -> np.ndarray | None:
        """The odometry reading of the last scan (the one kept, see ``update``), None before."""
        return None if self._odom is None else self._odom.copy()

    @property
    def trajectory(self) -> np.ndarray:
        """(n, 3): the estimate after each scan."""
        return np.array(self._trajectory).reshape(-1, 3)

    @property
    def times(self) -> np.ndarray:
        """(n,): the times passed to ``update`` (NaN where none was), s."""
        return np.array(self._times, dtype=float)

    @property
    def scans(self) -> int:
        """Number of scans processed."""
        return len(self._trajectory)

    def update(
        self,
        ranges,
        angles,
        odom_pose,
        *,
        range_max: float,
        range_min: float = 0.0,
        time: float | None = None,
        alternative_odom_pose=None,
    ) -> np.ndarray:
        """Processes one scan and returns the new base pose (x, y, yaw) (m, rad).

        Args:
            ranges: (n,) m in the sensor frame; ``inf`` = no return, NaN = no information.
            angles: (n,) beam angles in the sensor frame, rad.
            odom_pose: (x, y, yaw) of the base from the odometry (its own frame; only its
                motion since the previous scan is used).
            range_max, range_min: the sensor's limits, m.
            time: s, recorded beside the pose.
            alternative_odom_pose: another reading of the odometry for this scan (a log whose
                odometry may have jumped: the reading without the jump); the scan is matched
                from both predictions and the better accepted match is kept (the odometry's
                when both find the same pose, or its prediction if neither is accepted), and
                the odometry goes on from the reading kept.
        """
        ranges = np.asarray(ranges, dtype=float)
        angles = np.asarray(angles, dtype=float)
        odom_pose = np.array(odom_pose, dtype=float)
        # Returns near the limit are biased short (one with noise past it is dropped, one with
        # noise short of it kept): they count as none (``SlamConfig.range_margin``).
        if range_max - self.config.range_margin > range_min:
            range_max = range_max - self.config.range_margin
        hit = np.isfinite(ranges) & (ranges >= range_min) & (ranges < range_max)
        # Surface normals at the hits, in the sensor frame (the beams elsewhere).
        normals = np.stack([np.cos(angles), np.sin(angles)], -1)
        sensor_points = ranges[hit, None] * normals[hit]
        normals[hit] = surface_normals(sensor_points)
        if self._odom is not None:
            prediction = compose(self._pose, relative_pose(self._odom, odom_pose))
            rejected = self.rejected
            pose, accepted, score = self._scored_match(sensor_points, normals[hit], prediction)
            if alternative_odom_pose is not None:
                alternative = np.array(alternative_odom_pose, dtype=float)
                other = compose(self._pose, relative_pose(self._odom, alternative))
                second = self._scored_match(sensor_points, normals[hit], other)
                better = second[2] > score and not same_pose(second[0], pose)
                if second[1] and (not accepted or better):
                    (pose, accepted, score), odom_pose = second, alternative
                self.rejected = rejected + (0 if accepted else 1)  # one count per scan
            self._pose = pose
        self._odom = odom_pose
        if self._map_due():
            self._insert(ranges, angles, range_max, range_min, normals)
            self._pyramid()  # now, while the maps are this copy's own (``__deepcopy__``)
        self._trajectory.append(self._pose.copy())
        self._times.append(np.nan if time is None else float(time))
        return self.pose

    def map(self, *, crop: bool = True) -> OccupancyMap:
        """The map at ``config.resolution``, trinary, cropped to the seen cells."""
        return self.grids[self.map_level].to_occupancy_map(crop=crop)

    def save(self, stem: Path | str) -> tuple[Path, Path]:
        """Writes the map as map_server files ``stem.pgm`` and ``stem.yaml``."""
        return save_map(self.map(), stem)

    def _scored_match(self, sensor_points, normals, prediction) -> tuple[np.ndarray, bool, float]:
        """(``_match``'s pose, whether the match was accepted, its finest map's score)."""
        rejected = self.rejected
        pose = self._match(sensor_points, normals, prediction)
        accepted = self.rejected == rejected
        score = float(self.last_match.scores[self.map_level]) if accepted else -math.inf
        return pose, accepted, score

    def _match(self, sensor_points, normals, prediction) -> np.ndarray:
        """Matches the end points (n, 2, sensor frame) with their surfaces' normals."""
        config = self.config
        if len(sensor_points) < config.min_points:
            self.rejected += 1
            return prediction
        points = transform_points(self.X_base_sensor, sensor_points)
        c, s = math.cos(self.X_base_sensor[2]), math.sin(self.X_base_sensor[2])
        directions = normals @ np.array([[c, s], [-s, c]])
        result = self._gated_match(points, directions, prediction)
        if result is None:
            result = self._recover(points, directions, prediction)
            if result is None:
                self.rejected += 1
                return prediction
            self.recovered += 1
        return self._remap(result.pose, prediction, points, sensor_points)

    def _gated_match(self, points, directions, prediction) -> MatchResult | None:
        """The match from ``prediction``, or None when the gate rejects it."""
        config = self.config
        result = match_scan(
            self._pyramid(),
            points,
            prediction,
            iterations=config.iterations,
            prior_weight=config.prior_weight,
            hit_directions=directions,
            hit_offset=config.hit_offset,
        )
        self.last_match = result
        offset = relative_pose(prediction, result.pose)
        if (
            math.hypot(offset[0], offset[1]) > config.max_correction
            or abs(offset[2]) > math.radians(config.max_correction_deg)
            or result.scores[self.map_level] < config.min_score
        ):
            return None
        return result

    def _recover(self, points, directions, prediction) -> MatchResult | None:
        """After a rejected match: the exhaustive search's best pose within the recovery window
        (``SlamConfig.recovery_window``), matched and gated from there; None if there is none
        or another pose as far off as a loop closure's runner-up scores nearly as well
        (``correlative_search.ambiguous`` with the loop closures' settings)."""
        config = self.config
        window, turn = config.recovery_window, math.radians(config.recovery_window_deg)
        if window <= 0:
            return None
        grid = self.grids[self.map_level]
        placed = transform_points(prediction, points)
        reach = window + float(np.hypot(*points.T).max()) * turn + grid.resolution
        world = occupied_points(
            grid.log_odds, grid.resolution, grid.origin, placed.min(0) - reach,
            placed.max(0) + reach,
        )  # fmt: skip
        if len(world) < config.min_points:
            return None
        table = make_table(world, grid.resolution, sigma=1.5 * grid.resolution, margin=reach)
        found = search(
            table, points, prediction, window_xy=window, window_yaw=turn,
            yaw_step=math.radians(0.5),
        )  # fmt: skip
        closure = config.loop_closure
        if found.score < config.recovery_min_score or ambiguous(
            table, points, found.pose, found.score, distance=closure.ambiguity_distance,
            max_ratio=closure.max_ambiguity, yaw_step=math.radians(0.5),
        ):  # fmt: skip
            return None
        return self._gated_match(points, directions, found.pose)

    def _remap(self, pose, prediction, points, sensor_points) -> np.ndarray:
        """``pose``, with the prediction's position along a direction the scan cannot see: its
        surfaces' normals (``points``, base frame) all face across it, and it has no depth
        steps along it (``sensor_points``, the same in the sensor frame)."""
        values, vectors = normal_spread(points)
        if values[1] > 0 and values[0] >= self.config.degenerate_ratio * values[1]:
            return pose
        if depth_edges(sensor_points) >= self.config.degenerate_edges:
            return pose
        self.degenerate += 1
        c, s = math.cos(pose[2]), math.sin(pose[2])
        along = np.array([[c, -s], [s, c]]) @ vectors[:, 0]  # In the world.
        remapped = pose.copy()
        remapped[:2] -= along * (along @ (pose[:2] - prediction[:2]))
        return remapped

    def _map_due(self) -> bool:
        if self.map_updates < self.config.initial_map_updates or self._last_map_pose is None:
            return True
        moved = relative_pose(self._last_map_pose, self._pose)
        return math.hypot(moved[0], moved[1]) >= self.config.map_update_distance or abs(
            moved[2]
        ) >= math.radians(self.config.map_update_angle_deg)

    def redraw(self, scans, pose) -> None:
        """Draws the map again from nothing: ``scans`` are (base pose, then ``last_insert``'s
        five items) in order; the estimate becomes ``pose`` (a pose graph moved them all)."""
        self._own_maps()
        for grid in self.grids:
            grid.clear()
        self._match_maps = [None] * len(self.grids)
        updates = self.map_updates
        for base_pose, *scan in scans:
            self._insert(*scan, pose=base_pose)
        self.map_updates = updates
        self._pose = np.array(pose, dtype=float)
        self._last_map_pose = self._pose.copy()

    def _insert(self, ranges, angles, range_max, range_min, normals, *, pose=None) -> None:
        self._own_maps()
        pose = self._pose if pose is None else np.asarray(pose, dtype=float)
        sensor_pose = compose(pose, self.X_base_sensor)
        hits = scan_points(
            ranges, angles, range_max, range_min, self.X_base_sensor, self.config.map_size
        )
        if grow_to_cover(self.grids, transform_points(pose, hits), self.grids[-1].resolution):
            self._match_maps = [None] * len(self.grids)  # made again from the grown grids
        for grid in self.grids:
            grid.insert_scan(
                sensor_pose,
                ranges,
                angles,
                range_max,
                range_min=range_min,
                no_return_range=self.config.no_return_range or None,
                hit_directions=normals,
            )
        self._last_map_pose = pose.copy()
        self.last_insert = (ranges, angles, range_max, range_min, normals)
        self.map_updates += 1

    def _pyramid(self) -> list[MatchMap]:
        """The levels matched against, made once from the grids and then updated with what a
        map update changed (``match_updates.update_level``; whole again with ``smoothing``)."""
        if self._match_versions != [grid.version for grid in self.grids]:
            self._own_maps()
        for k, grid in enumerate(self.grids):
            if self._match_versions[k] != grid.version:
                changes, box = grid.take_changes(), grid.take_changed_box()
                level = self._match_maps[k]
                if level is None or self.config.smoothing > 0:
                    level = MatchMap.from_grid(grid, self.config.smoothing, field=self.config.field)
                else:
                    level = update_level(level, grid, changes, box, field=self.config.field)
                self._match_maps[k] = level
                self._match_versions[k] = grid.version
        return self._match_maps
