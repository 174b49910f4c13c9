"""The SLAM node: scan-matching SLAM (``ScanMatchingSlam``, or ``GraphSlam`` with loop closure on)
as a Drake system.

Like hector_mapping it takes each laser scan and the wheel odometry, matches the scan against the
map built so far, and grows the map. Its ``pose`` output is what ROS gets by chaining the
``map -> odom`` correction with the odometry: the pose matched at the last scan, moved on by the
odometry since, so it is current between scans.
"""

import copy

import numpy as np
from pydrake.common.value import AbstractValue
from pydrake.systems.framework import LeafSystem

from drake_sim.base.map_files import OccupancyMap
from drake_sim.base.planar import compose, relative_pose
from drake_sim.systems.estimation.graph_slam import GraphSlam, make_slam
from drake_sim.systems.estimation.scan_matching_slam import ScanMatchingSlam
from drake_sim.systems.estimation.slam_config import SlamConfig
from drake_sim.systems.sensors.lidar import LaserScan

SCAN_DELAY = 1e-4
"""s after each scan that the SLAM reads it: the lidar's scan and the odometry's pose of the
same instant are both held by then (events at one instant all see the state before it)."""


NO_SCAN = LaserScan(
    time=np.nan, angle_min=0.0, angle_increment=0.0, range_min=0.0, range_max=0.0, ranges=[]
)
"""A scan with no beams: what a scan port holds before the first scan."""

EMPTY_MAP = OccupancyMap(cells=np.full((0, 0), -1, dtype=np.int8), resolution=1.0)
"""A map with no cells (a ``map`` port's model value)."""


class _SlamState:
    """What the SLAM system keeps between scans (its abstract state)."""

    def __init__(self, slam: ScanMatchingSlam | GraphSlam, odometry):
        self.slam = slam
        self.last_scan_time = -np.inf
        self.odometry_at_scan = np.asarray(odometry, dtype=float)  # [x, y, yaw]
        self.history: list[list[float]] = []  # [t, slam x, y, yaw, odometry x, y, yaw] per scan

    def __deepcopy__(self, memo):
        """A copy for Drake's state (three at every scan) that shares the SLAM: a state once
        set is never changed (``SlamSystem._update`` sets a new one, ``successor``), so its
        clones need not copy the maps (copied, they were an eighth of an exploring run's
        time)."""
        other = _SlamState.__new__(_SlamState)
        other.slam = self.slam
        other.last_scan_time = self.last_scan_time
        other.odometry_at_scan = self.odometry_at_scan.copy()
        other.history = list(self.history)  # rows are never changed once appended: shared
        return other

    def successor(self) -> "_SlamState":
        """A copy of its own to update with the next scan (the SLAM copied)."""
        other = copy.deepcopy(self)
        other.slam = copy.deepcopy(self.slam)
        return other


class SlamSystem(LeafSystem):
    """Scan-matching SLAM on a ``LaserScan`` stream and wheel odometry.

    .. pydrake_system::

        name: SlamSystem
        input_ports:
        - scan
        - odometry
        output_ports:
        - pose
        - scan_pose
        - map

    ``scan`` is the ``Lidar``'s ``LaserScan``; ``odometry`` the robot's ``[x, y, yaw]`` from
    wheel odometry (m, m, rad), in any fixed frame. Each new scan is processed ``SCAN_DELAY``
    after it was taken (``period``: the lidar's). ``scan_pose`` is the robot's ``[x, y, yaw]``
    in the map frame matched at the last scan; ``pose`` is that moved on by the odometry since;
    ``map`` the ``OccupancyMap`` built so far. The map frame is the world frame when
    ``initial_pose`` is the robot's true start pose. The map's square (``config.map_size``)
    is centred on ``map_center`` ((x, y) m; None: the initial pose).
    """

    def __init__(
        self,
        *,
        config: SlamConfig,
        period: float,
        initial_pose,
        X_base_sensor=(0.0, 0.0, 0.0),
        map_center=None,
    ):
        super().__init__()
        self._config = config
        self._initial_pose = np.asarray(initial_pose, dtype=float)
        self._map_center = None if map_center is None else np.asarray(map_center, dtype=float)
        self._X_base_sensor = tuple(float(v) for v in X_base_sensor)
        self._scan = self.DeclareAbstractInputPort("scan", AbstractValue.Make(NO_SCAN))
        self._odometry = self.DeclareVectorInputPort("odometry", 3)
        self._state = self.DeclareAbstractState(AbstractValue.Make(self._new_state(None)))
        self.DeclareInitializationUnrestrictedUpdateEvent(self._initialize)
        self.DeclarePeriodicUnrestrictedUpdateEvent(period, SCAN_DELAY, self._update)
        ticket = {self.abstract_state_ticket(self._state)}
        self.DeclareVectorOutputPort(
            "pose", 3, self._calc_pose, ticket | {self.all_input_ports_ticket()}
        )
        self.DeclareVectorOutputPort(
            "scan_pose",
            3,
            lambda context, out: out.SetFromVector(self._get(context).slam.pose),
            ticket,
        )
        self.DeclareAbstractOutputPort(
            "map",
            lambda: AbstractValue.Make(EMPTY_MAP),
            lambda context, out: out.set_value(self._get(context).slam.map()),
            ticket,
        )

    def _new_state(self, odometry) -> _SlamState:
        slam = make_slam(
            self._config,
            self._initial_pose,
            X_base_sensor=self._X_base_sensor,
            map_center=self._map_center,
        )
        return _SlamState(slam, self._initial_pose if odometry is None else odometry)

    def _get(self, context) -> _SlamState:
        return context.get_abstract_state(self._state).get_value()

    def slam(self, context) -> ScanMatchingSlam | GraphSlam:
        """The SLAM (its map, pose and trajectory) in ``context``; read only."""
        return self._get(context).slam

    def history(self, context) -> np.ndarray:
        """(n, 7) rows ``[t, slam x, y, yaw, odometry x, y, yaw]``, one per processed scan."""
        return np.array(self._get(context).history, dtype=float).reshape(-1, 7)

    def _initialize(self, context, state):
        fresh = self._new_state(np.array(self._odometry.Eval(context)))
        state.get_mutable_abstract_state(self._state).set_value(fresh)

    def _update(self, context, state):
        scan: LaserScan = self._scan.Eval(context)
        current = self._get(context)
        if scan.ranges.size == 0 or not scan.time > current.last_scan_time:
            return
        odometry = np.array(self._odometry.Eval(context))
        new = current.successor()
        new.slam.update(
            scan.ranges,
            scan.angles(),
            odometry,
            range_max=scan.range_max,
            range_min=scan.range_min,
            time=scan.time,
        )
        new.last_scan_time = scan.time
        new.odometry_at_scan = odometry
        new.history.append([scan.time, *new.slam.pose, *odometry])
        state.get_mutable_abstract_state(self._state).set_value(new)

    def _calc_pose(self, context, output):
        current = self._get(context)
        moved = relative_pose(current.odometry_at_scan, self._odometry.Eval(context))
        output.SetFromVector(compose(current.slam.pose, moved))
