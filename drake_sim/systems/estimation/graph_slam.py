"""The scan-matching SLAM with a pose graph and loop closure (``SlamConfig.loop_closure``).

``ScanMatchingSlam`` tracks the robot against its map scan by scan; every map update it makes is
a keyframe here: a node of a ``PoseGraph``, tied to the previous keyframe by the matcher's step
between them (``sequence_sigma``; ``unmatched_sigma`` when the matcher refused a scan between
them and the step is the odometry's) and, when ``loop_closure.close_loop`` finds the scan on an old
part of the map, to that part's keyframe (``closure_sigma``). Each closure re-optimises the graph
(robust loss); when that moves the current keyframe by more than ``redraw_distance`` or
``redraw_angle_deg``, the matcher's map is drawn again from every keyframe's scan at its
optimised pose and the matcher goes on from the optimised pose, so the walls it matches against
are where the closed loop puts them. A scan's pose in ``trajectory`` is its keyframe's optimised
pose composed with where the matcher put the scan relative to that keyframe; ``finish`` makes
the map agree with the final graph.

With loop closure off, ``make_slam`` gives the plain ``ScanMatchingSlam``.
"""

import copy
import math

import numpy as np

from drake_sim.base.map_files import OccupancyMap
from drake_sim.base.planar import compose, relative_pose
from drake_sim.systems.estimation.loop_closure import candidate, close_loop, scan_points
from drake_sim.systems.estimation.pose_graph import PoseGraph
from drake_sim.systems.estimation.scan_matching_slam import ScanMatchingSlam
from drake_sim.systems.estimation.slam_config import SlamConfig


def make_slam(
    config: SlamConfig | None = None,
    initial_pose=(0.0, 0.0, 0.0),
    X_base_sensor=(0.0, 0.0, 0.0),
    map_center=None,
):
    """A ``GraphSlam`` when ``config.loop_closure.enabled``, else a ``ScanMatchingSlam``."""
    config = config if config is not None else SlamConfig()
    kind = GraphSlam if config.loop_closure.enabled else ScanMatchingSlam
    return kind(config, initial_pose, X_base_sensor=X_base_sensor, map_center=map_center)


class GraphSlam:
    """``ScanMatchingSlam`` plus a pose graph with loop closures (module docstring); the same
    ``update``, ``pose``, ``trajectory``, ``map`` and ``save``.

    Args:
        config: the parameters (``config.loop_closure`` for the graph).
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
        self.local = ScanMatchingSlam(
            config, initial_pose, X_base_sensor=X_base_sensor, map_center=map_center
        )
        self.config = self.local.config
        self.graph = PoseGraph()
        self._inserted: list[tuple] = []  # per keyframe: its scan as the map took it
        self._points: list[np.ndarray] = []  # per keyframe: its hits in the base frame
        self._travel: list[float] = []  # per keyframe: m along the trajectory
        self._segments: list[int] = []  # per keyframe: +1 after each step not matched
        self._reference = None  # the matcher's pose of the last keyframe
        self._rejected = 0  # the matcher's refused scans by then
        self._attached: list[tuple[int, np.ndarray]] = []  # per scan: (keyframe, offset)
        self.loop_closures = 0
        self.redraws = 0

    def __deepcopy__(self, memo):
        """A copy for Drake's state (at every scan): the keyframes' arrays and the graph's
        nodes and edges are never changed in place, so shared; the lists are copied."""
        other = GraphSlam.__new__(GraphSlam)
        other.__dict__.update(self.__dict__)
        other.local = copy.deepcopy(self.local, memo)
        other.graph = self.graph.copy()
        for key in ("_inserted", "_points", "_travel", "_segments", "_attached"):
            setattr(other, key, list(getattr(self, key)))
        return other

    @property
    def pose(self) -> np.ndarray:
        """The current estimate (x, y, yaw) of the base in the world (m, rad)."""
        return self.local.pose

    @property
    def X_base_sensor(self) -> np.ndarray:
        return self.local.X_base_sensor

    @property
    def odometry(self):
        return self.local.odometry

    @property
    def rejected(self) -> int:
        return self.local.rejected

    @property
    def map_updates(self) -> int:
        return self.local.map_updates

    @property
    def scans(self) -> int:
        return len(self._attached)

    @property
    def times(self) -> np.ndarray:
        return self.local.times

    @property
    def trajectory(self) -> np.ndarray:
        """(n, 3): each scan's pose on the optimised graph."""
        if not self._attached:
            return np.zeros((0, 3))
        poses = self.graph.poses
        nodes = np.array([node for node, _ in self._attached])
        offsets = np.array([offset for _, offset in self._attached])
        return compose(poses[nodes], offsets)

    def update(self, ranges, angles, odom_pose, **kwargs) -> np.ndarray:
        """``ScanMatchingSlam.update``, then the graph's work when the map took the scan."""
        before = self.local.map_updates
        pose = self.local.update(ranges, angles, odom_pose, **kwargs)
        if self.local.map_updates > before:
            pose = self._keyframe(pose)
        node = len(self.graph) - 1
        self._attached.append((node, relative_pose(self._reference, pose)))
        return pose

    def finish(self) -> None:
        """Optimises the graph once more and draws the map from it (after the last scan)."""
        if self.loop_closures:
            self._optimize()
            self._redraw(len(self.graph) - 1)

    def map(self, *, crop: bool = True) -> OccupancyMap:
        return self.local.map(crop=crop)

    def save(self, stem):
        return self.local.save(stem)

    def _keyframe(self, pose) -> np.ndarray:
        loops = self.config.loop_closure
        inserted = self.local.last_insert
        node = len(self.graph)
        if node == 0:
            self.graph.add_node(pose)
            self._travel.append(0.0)
            self._segments.append(0)
        else:
            step = relative_pose(self._reference, pose)
            self.graph.add_node(compose(self.graph.pose(node - 1), step))
            matched = self.local.rejected == self._rejected
            sigma = loops.sequence_sigma if matched else loops.unmatched_sigma
            sigma = np.array(sigma) * [1.0, 1.0, math.pi / 180.0]
            self.graph.add_edge(node - 1, node, step, sigma)
            self._travel.append(self._travel[-1] + math.hypot(step[0], step[1]))
            self._segments.append(self._segments[-1] + (0 if matched else 1))
        self._inserted.append(inserted)
        self._points.append(scan_points(*inserted[:4], self.local.X_base_sensor, loops.max_range))
        self._reference = np.array(pose, dtype=float)
        self._rejected = self.local.rejected
        if node % loops.attempt_every == 0 and self._try_closure(node):
            moved = relative_pose(pose, self.graph.pose(node))
            if math.hypot(moved[0], moved[1]) > loops.redraw_distance or abs(
                moved[2]
            ) > math.radians(loops.redraw_angle_deg):
                self._redraw(node)
                pose = self.local.pose
        return pose

    def _try_closure(self, node: int) -> bool:
        """Looks for a loop closure at ``node``; True when the graph was optimised."""
        loops = self.config.loop_closure
        poses, travel = self.graph.poses, np.array(self._travel)
        target = candidate(poses, travel, node, loops)
        if target is None:
            return False
        segments = np.array(self._segments)
        found = close_loop(poses, travel, self._points, node, target, loops, segments)
        if found is None:
            return False
        sigma = np.array(loops.closure_sigma) * [1.0, 1.0, math.pi / 180.0]
        measured = relative_pose(poses[target], found[0])
        self.graph.add_edge(target, node, measured, sigma)
        self.loop_closures += 1
        # A closure the graph already agrees with (within its sigmas) waits for the next one
        # that does not, or for ``finish``: optimising would move nothing worth a redraw.
        error = relative_pose(relative_pose(poses[target], poses[node]), measured) / sigma
        if np.linalg.norm(error) <= 1.0:
            return False
        self._optimize()
        return True

    def _optimize(self) -> None:
        loops = self.config.loop_closure
        self.graph.optimize(loss=loops.loss, loss_scale=loops.loss_scale)

    def _redraw(self, node: int) -> None:
        """The matcher's map from every keyframe at its graph pose; its pose at ``node``'s."""
        poses = self.graph.poses
        self.local.redraw(
            ((pose, *scan) for pose, scan in zip(poses, self._inserted, strict=True)), poses[node]
        )
        self._reference = poses[node].copy()
        self.redraws += 1
