"""ROS 2 messages of a planar robot's log, built from plain values: ``sensor_msgs/LaserScan``,
``nav_msgs/Odometry``, ``tf2_msgs/TFMessage``, ``geometry_msgs/PoseStamped`` and
``nav_msgs/OccupancyGrid``, as ``rosbags``' typestore (Humble's message definitions) builds and
serialises them, with no ROS installed.

Poses are planar ``[x, y, yaw]`` (m, m, rad); a transform may carry a height ``z`` (the lidar's
above the base, so RViz draws the scan where it was). Times are seconds, written as ROS
``builtin_interfaces/Time`` (whole seconds and nanoseconds).
"""

import math
from functools import cache

import numpy as np

SCAN_TYPE = "sensor_msgs/msg/LaserScan"
ODOM_TYPE = "nav_msgs/msg/Odometry"
TF_TYPE = "tf2_msgs/msg/TFMessage"
POSE_TYPE = "geometry_msgs/msg/PoseStamped"
MAP_TYPE = "nav_msgs/msg/OccupancyGrid"


@cache
def typestore():
    """The ``rosbags`` typestore of ROS 2 Humble's standard messages (one per process)."""
    from rosbags.typesys import Stores, get_typestore  # noqa: PLC0415 (import on first use)

    return get_typestore(Stores.ROS2_HUMBLE)


@cache
def ros1_typestore():
    """The typestore of ROS 1 Noetic's standard messages (a ROS 1 log's)."""
    from rosbags.typesys import Stores, get_typestore  # noqa: PLC0415 (import on first use)

    return get_typestore(Stores.ROS1_NOETIC)


def _type(name: str):
    return typestore().types[name]


def nanoseconds(seconds: float) -> int:
    """``seconds`` as integer nanoseconds (a log's timestamps)."""
    return round(seconds * 1e9)


def stamp(seconds: float):
    """``builtin_interfaces/Time`` of ``seconds`` (>= 0)."""
    ns = nanoseconds(seconds)
    return _type("builtin_interfaces/msg/Time")(sec=ns // 1_000_000_000, nanosec=ns % 1_000_000_000)


def header(seconds: float, frame_id: str):
    """``std_msgs/Header``."""
    return _type("std_msgs/msg/Header")(stamp=stamp(seconds), frame_id=frame_id)


def _quaternion(yaw: float):
    return _type("geometry_msgs/msg/Quaternion")(
        x=0.0, y=0.0, z=math.sin(yaw / 2), w=math.cos(yaw / 2)
    )


def _pose(pose, z: float = 0.0):
    x, y, yaw = (float(v) for v in pose)
    point = _type("geometry_msgs/msg/Point")(x=x, y=y, z=float(z))
    return _type("geometry_msgs/msg/Pose")(position=point, orientation=_quaternion(yaw))


def laser_scan(seconds, frame_id, angle_min, angle_increment, range_min, range_max, ranges):
    """``sensor_msgs/LaserScan``; ``inf`` ranges stay ``inf`` (REP 117: no return)."""
    ranges = np.asarray(ranges, dtype=np.float32)
    return _type(SCAN_TYPE)(
        header=header(seconds, frame_id),
        angle_min=float(angle_min),
        angle_max=float(angle_min + angle_increment * max(len(ranges) - 1, 0)),
        angle_increment=float(angle_increment),
        time_increment=0.0,
        scan_time=0.0,
        range_min=float(range_min),
        range_max=float(range_max),
        ranges=ranges,
        intensities=np.zeros(0, dtype=np.float32),
    )


def odometry(seconds, frame_id, child_frame_id, pose, twist):
    """``nav_msgs/Odometry``: ``pose`` [x, y, yaw] in ``frame_id``, ``twist`` [v, omega] in
    ``child_frame_id``; covariances zero (unknown)."""
    v, omega = (float(t) for t in twist)
    vector = _type("geometry_msgs/msg/Vector3")
    twist_msg = _type("geometry_msgs/msg/Twist")(
        linear=vector(x=v, y=0.0, z=0.0), angular=vector(x=0.0, y=0.0, z=omega)
    )
    return _type(ODOM_TYPE)(
        header=header(seconds, frame_id),
        child_frame_id=child_frame_id,
        pose=_type("geometry_msgs/msg/PoseWithCovariance")(
            pose=_pose(pose), covariance=np.zeros(36)
        ),
        twist=_type("geometry_msgs/msg/TwistWithCovariance")(
            twist=twist_msg, covariance=np.zeros(36)
        ),
    )


def transform(seconds, parent: str, child: str, pose, z: float = 0.0):
    """``geometry_msgs/TransformStamped``: ``child``'s planar ``pose`` in ``parent``."""
    x, y, yaw = (float(v) for v in pose)
    vector = _type("geometry_msgs/msg/Vector3")(x=x, y=y, z=float(z))
    return _type("geometry_msgs/msg/TransformStamped")(
        header=header(seconds, parent),
        child_frame_id=child,
        transform=_type("geometry_msgs/msg/Transform")(
            translation=vector, rotation=_quaternion(yaw)
        ),
    )


def tf_message(transforms):
    """``tf2_msgs/TFMessage`` of ``transform``s."""
    return _type(TF_TYPE)(transforms=list(transforms))


def pose_stamped(seconds, frame_id, pose):
    """``geometry_msgs/PoseStamped``."""
    return _type(POSE_TYPE)(header=header(seconds, frame_id), pose=_pose(pose))


def occupancy_grid(seconds, frame_id, cells, resolution, origin):
    """``nav_msgs/OccupancyGrid`` of ``cells`` (rows from the origin's, -1 unknown, 0..100),
    ``resolution`` m per cell and ``origin`` [x, y, yaw] of cell [0, 0]'s outer corner."""
    cells = np.asarray(cells, dtype=np.int8)
    rows, cols = cells.shape
    info = _type("nav_msgs/msg/MapMetaData")(
        map_load_time=stamp(seconds),
        resolution=float(resolution),
        width=cols,
        height=rows,
        origin=_pose(origin),
    )
    return _type(MAP_TYPE)(
        header=header(seconds, frame_id), info=info, data=np.ascontiguousarray(cells).ravel()
    )
