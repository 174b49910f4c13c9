"""``RosLogRecorder``: the lidar robot's run written as a ROS 2 log, the topics a TurtleBot3
publishes and slam_toolbox or AMCL adds, so that Foxglove and RViz (through ``ros2 bag play``)
show the run and ``python -m drake_sim.mapping --log`` maps it again.

Topics (REP 105 frames; the names are ``RosLogFrames``'):

* ``/scan`` ``sensor_msgs/LaserScan`` in the lidar's frame, one per scan, stamped with the scan's
  time; ``inf`` where a beam saw nothing (REP 117).
* ``/odom`` ``nav_msgs/Odometry`` (``odom`` -> base) and ``/tf`` with the same transform and,
  when an estimate is connected, ``map`` -> ``odom`` (the estimate composed with the inverse
  odometry, what slam_toolbox and AMCL publish): ``odometry_per_scan`` times per scan, the
  last of them with the scan, just before it.
* ``/tf_static``: base -> lidar (planar offset, the lidar's height), latched.
* ``/map`` ``nav_msgs/OccupancyGrid``, latched: a fixed map once at the start (map_server's),
  or the ``map`` input every ``map_period`` (slam_toolbox's ``map_update_interval``).
* ``/ground_truth/pose`` ``geometry_msgs/PoseStamped`` in ``map`` with each scan: the
  simulator's true pose (what Gazebo's ground-truth plugins publish), for scoring.

Every message goes out ``offset`` after the scan instant (after the lidar's update and the
estimator's, which run at the scan's time and ``SCAN_DELAY`` after it).
"""

import dataclasses as dc

import numpy as np
from pydrake.common.value import AbstractValue
from pydrake.systems.framework import EventStatus, LeafSystem

from drake_sim.base import ros_messages as rm
from drake_sim.base.map_files import OccupancyMap
from drake_sim.base.mcap_files import McapLogWriter
from drake_sim.base.planar import compose, relative_pose
from drake_sim.systems.estimation.slam import SCAN_DELAY
from drake_sim.systems.sensors.lidar import LaserScan


@dc.dataclass(frozen=True)
class RosLogFrames:
    """The frame names the log uses (REP 105; the base and lidar are the robot's own)."""

    base: str = "base_footprint"
    laser: str = "base_scan"
    odom: str = "odom"
    map: str = "map"


def map_message(occupancy_map: OccupancyMap, seconds: float, frame: str = "map"):
    """``nav_msgs/OccupancyGrid`` of ``occupancy_map``."""
    m = occupancy_map
    return rm.occupancy_grid(seconds, frame, m.cells, m.resolution, m.origin)


class RosLogRecorder(LeafSystem):
    """Writes the topics of the module's list to ``writer`` as the simulation runs.

    .. pydrake_system::

        name: RosLogRecorder
        input_ports:
        - scan
        - odometry_pose
        - odometry_twist
        - estimated_pose (optional)
        - true_pose (optional)
        - map (optional)

    Args:
        writer: the log (``McapLogWriter``); the caller closes it when the run ends.
        scan_period: s between scans (the lidar's).
        frames: the frame names.
        X_base_sensor: the lidar's planar pose ``[x, y, yaw]`` on the base; ``sensor_height``
            m above it.
        odometry_per_scan: odometry messages per scan.
        map_period: s between ``/map`` messages of the ``map`` input.
        static_map: a fixed map written once at the start (the ``map`` input then unused).
        offset: s after each scan instant the messages go out (after the estimator's update,
            ``SCAN_DELAY`` after the scan, has run).
    """

    def __init__(
        self,
        *,
        writer: McapLogWriter,
        scan_period: float,
        frames: RosLogFrames = RosLogFrames(),
        X_base_sensor=(0.0, 0.0, 0.0),
        sensor_height: float = 0.0,
        odometry_per_scan: int = 4,
        map_period: float = 5.0,
        static_map: OccupancyMap | None = None,
        offset: float = 2 * SCAN_DELAY,
    ):
        super().__init__()
        self._writer = writer
        self._frames = frames
        self._sensor = (np.asarray(X_base_sensor, dtype=float), float(sensor_height))
        self._per_scan = int(odometry_per_scan)
        self._tick_period = scan_period / self._per_scan
        self._offset = offset
        self._static_map = static_map
        self._scan = self.DeclareAbstractInputPort("scan", AbstractValue.Make(_NO_SCAN))
        self._odometry = self.DeclareVectorInputPort("odometry_pose", 3)
        self._twist = self.DeclareVectorInputPort("odometry_twist", 2)
        self._estimate = self.DeclareVectorInputPort("estimated_pose", 3)
        self._truth = self.DeclareVectorInputPort("true_pose", 3)
        self._map = self.DeclareAbstractInputPort("map", AbstractValue.Make(_NO_MAP))
        self.DeclareInitializationPublishEvent(self._start)
        self.DeclarePeriodicPublishEvent(self._tick_period, offset, self._tick)
        if static_map is None:
            self.DeclarePeriodicPublishEvent(map_period, offset, self._write_map)

    def _start(self, context) -> EventStatus:
        f, (xy_yaw, z) = self._frames, self._sensor
        laser = rm.transform(0.0, f.base, f.laser, xy_yaw, z)
        self._writer.write("/tf_static", rm.tf_message([laser]), 0.0, latched=True)
        if self._static_map is not None:
            self._writer.write("/map", map_message(self._static_map, 0.0, f.map), 0.0, latched=True)
        return EventStatus.Succeeded()

    def _tick(self, context) -> EventStatus:
        t, f = context.get_time(), self._frames
        odometry = np.asarray(self._odometry.Eval(context))
        self._writer.write(
            "/odom", rm.odometry(t, f.odom, f.base, odometry, self._twist.Eval(context)), t
        )
        transforms = [rm.transform(t, f.odom, f.base, odometry)]
        if self._estimate.HasValue(context):
            estimate = np.asarray(self._estimate.Eval(context))
            map_odom = compose(estimate, relative_pose(odometry, np.zeros(3)))
            transforms.append(rm.transform(t, f.map, f.odom, map_odom))
        self._writer.write("/tf", rm.tf_message(transforms), t)
        tick = round((t - self._offset) / self._tick_period)
        scan = self._scan.Eval(context)
        if tick % self._per_scan == 0 and np.isfinite(scan.time):
            self._writer.write(
                "/scan",
                rm.laser_scan(
                    scan.time,
                    f.laser,
                    scan.angle_min,
                    scan.angle_increment,
                    scan.range_min,
                    scan.range_max,
                    scan.ranges,
                ),  # fmt: skip
                t,
            )
            if self._truth.HasValue(context):
                truth = rm.pose_stamped(t, f.map, self._truth.Eval(context))
                self._writer.write("/ground_truth/pose", truth, t)
        return EventStatus.Succeeded()

    def _write_map(self, context) -> EventStatus:
        if self._map.HasValue(context):
            occupancy_map = self._map.Eval(context)
            if occupancy_map.cells.size:
                t = context.get_time()
                message = map_message(occupancy_map, t, self._frames.map)
                self._writer.write("/map", message, t, latched=True)
        return EventStatus.Succeeded()


_NO_SCAN = LaserScan(np.nan, 0.0, 0.01, 0.0, 1.0, np.zeros(0))
_NO_MAP = OccupancyMap(np.zeros((0, 0), np.int8), 1.0)
