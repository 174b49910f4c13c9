"""ROS 1 and ROS 2 bags as LaserLog: topics found by type, odometry before each scan, the
sensor's pose from tf_static; bags written here with rosbags' own writers."""

import math
from pathlib import Path

import numpy as np
import pytest

from drake_sim.base import laser_bags as mut
from drake_sim.base import ros_messages as rm
from drake_sim.base.errors import ConfigError
from drake_sim.base.laser_logs import read_log
from drake_sim.base.mcap_files import McapLogWriter

rosbags = pytest.importorskip("rosbags")
from rosbags.rosbag1 import Writer as Writer1  # noqa: E402
from rosbags.rosbag2 import Writer as Writer2  # noqa: E402
from rosbags.typesys import Stores, get_types_from_msg, get_typestore  # noqa: E402

STORE = get_typestore(Stores.ROS1_NOETIC)  # ROS 1's messages, and tf2's (not in the store)
STORE.register(
    get_types_from_msg("geometry_msgs/TransformStamped[] transforms", "tf2_msgs/msg/TFMessage")
)
T = STORE.types
SHARED = Path(__file__).resolve().parents[4] / "shared" / "benchmarks" / "slam_carmen"


def _header(t, frame):
    return T["std_msgs/msg/Header"](
        seq=0, stamp=T["builtin_interfaces/msg/Time"](sec=int(t), nanosec=int(round(t % 1 * 1e9))),
        frame_id=frame,
    )  # fmt: skip


def _quat(yaw):
    return T["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=math.sin(yaw / 2), w=math.cos(yaw / 2))


def _scan(t, ranges):
    return T["sensor_msgs/msg/LaserScan"](
        header=_header(t, "laser"), angle_min=-1.0, angle_max=1.0, angle_increment=1.0,
        time_increment=0.0, scan_time=0.0, range_min=0.1, range_max=10.0,
        ranges=np.array(ranges, dtype=np.float32), intensities=np.zeros(0, dtype=np.float32),
    )  # fmt: skip


def _odom(t, x, y, yaw):
    p = T["geometry_msgs/msg/Point"](x=x, y=y, z=0.0)
    pose = T["geometry_msgs/msg/PoseWithCovariance"](
        pose=T["geometry_msgs/msg/Pose"](position=p, orientation=_quat(yaw)),
        covariance=np.zeros(36),
    )
    zero = T["geometry_msgs/msg/Vector3"](x=0.0, y=0.0, z=0.0)
    twist = T["geometry_msgs/msg/TwistWithCovariance"](
        twist=T["geometry_msgs/msg/Twist"](linear=zero, angular=zero), covariance=np.zeros(36)
    )
    return T["nav_msgs/msg/Odometry"](
        header=_header(t, "odom"), child_frame_id="base_footprint", pose=pose, twist=twist
    )


def _tf(t, parent, child, x, yaw):
    transform = T["geometry_msgs/msg/Transform"](
        translation=T["geometry_msgs/msg/Vector3"](x=x, y=0.0, z=0.2), rotation=_quat(yaw)
    )
    stamped = T["geometry_msgs/msg/TransformStamped"](
        header=_header(t, parent), child_frame_id=child, transform=transform
    )
    return T["tf2_msgs/msg/TFMessage"](transforms=[stamped])


# (topic, type, time, message): odometry, then scans; one scan stamped earlier than the last.
def _messages(odom=True):
    items = [
        ("/tf_static", "tf2_msgs/msg/TFMessage", 1.0, _tf(1.0, "base_footprint", "laser", 0.1, 0.0))
    ]
    if odom:
        items.append(("/wheel_odom", "nav_msgs/msg/Odometry", 1.0, _odom(1.0, 0.5, 0.0, 0.2)))
    else:
        items.append(
            ("/tf", "tf2_msgs/msg/TFMessage", 1.0, _tf(1.0, "odom", "base_link", 0.5, 0.2))
        )
    items += [
        ("/base_scan", "sensor_msgs/msg/LaserScan", 1.1, _scan(1.1, [1.0, float("inf"), 12.0])),
        ("/odom_other", "nav_msgs/msg/Odometry", 1.15, _odom(1.15, 9.0, 9.0, 0.0)),
        ("/base_scan", "sensor_msgs/msg/LaserScan", 1.2, _scan(1.05, [2.0, 3.0, 4.0])),
    ]
    return items


def _write(writer, serialize, path, items):
    with writer as w:
        conns = {}
        for topic, kind, t, msg in items:
            if topic not in conns:
                conns[topic] = w.add_connection(topic, kind, typestore=STORE)
            w.write(conns[topic], int(t * 1e9), serialize(msg, kind))
    return path


def _write_ros1(path, items):
    return _write(Writer1(path), STORE.serialize_ros1, path, items)


def _write_ros2(path, items):
    return _write(Writer2(path, version=8), STORE.serialize_cdr, path, items)


@pytest.mark.parametrize("writer", [_write_ros1, _write_ros2], ids=["ros1", "ros2"])
def test_a_bag_reads_its_scans_with_the_odometry_before_each(tmp_path, writer):
    path = writer(tmp_path / ("run.bag" if writer is _write_ros1 else "run2"), _messages())
    log = read_log(path, odom_topic="/wheel_odom")
    assert log.scan_topic == "/base_scan" and log.odom_topic == "/wheel_odom"
    assert [s.time for s in log.scans] == pytest.approx([1.1, 1.05])  # the bag's order
    first, second = log.scans
    np.testing.assert_allclose(first.angles, [-1.0, 0.0, 1.0])
    assert first.ranges[0] == 1.0 and np.all(np.isinf(first.ranges[1:]))  # inf and > max
    np.testing.assert_allclose(first.odometry, [0.5, 0.0, 0.2], atol=1e-9)
    np.testing.assert_allclose(second.odometry, [0.5, 0.0, 0.2], atol=1e-9)  # not /odom_other
    np.testing.assert_allclose(log.laser_pose, [0.1, 0.0, 0.0], atol=1e-9)


def test_a_ros1_bag_is_read_in_the_order_it_was_written(tmp_path):
    # Stamps that run backwards (Intel's do): the odometry written just before a scan is its
    # odometry, and the scans keep the written order, whatever their stamps say.
    items = [
        ("/odom", "nav_msgs/msg/Odometry", 2.0, _odom(2.0, 1.0, 0.0, 0.0)),
        ("/scan", "sensor_msgs/msg/LaserScan", 1.5, _scan(1.5, [1.0, 2.0, 3.0])),
        ("/odom", "nav_msgs/msg/Odometry", 1.0, _odom(1.0, 2.0, 0.0, 0.0)),
        ("/scan", "sensor_msgs/msg/LaserScan", 1.2, _scan(1.2, [1.0, 2.0, 3.0])),
    ]
    log = read_log(_write_ros1(tmp_path / "backwards.bag", items))
    assert [s.time for s in log.scans] == pytest.approx([1.5, 1.2])
    assert [s.odometry[0] for s in log.scans] == pytest.approx([1.0, 2.0])


def test_an_unreadable_record_is_a_config_error(tmp_path, monkeypatch):
    path = _write_ros1(tmp_path / "run.bag", _messages())

    def broken(reader, connections):
        raise EOFError("short read")
        yield

    monkeypatch.setattr(mut, "_records", broken)
    with pytest.raises(ConfigError, match=r"run.bag: the bag's records cannot be read \(short"):
        read_log(path)


def test_without_an_odometry_topic_the_tf_to_the_base_is_read(tmp_path):
    items = [m for m in _messages(odom=False) if m[0] != "/odom_other"]
    log = read_log(_write_ros1(tmp_path / "tf.bag", items))
    assert log.odom_topic == "tf (to base_link)"
    np.testing.assert_allclose(log.scans[1].odometry, [0.5, 0.0, 0.2], atol=1e-9)


def test_topics_are_checked(tmp_path):
    path = _write_ros1(tmp_path / "run.bag", _messages())
    with pytest.raises(ConfigError, match=r"no topic '/scan' \(--scan-topic; the bag has"):
        read_log(path, scan_topic="/scan")
    with pytest.raises(ConfigError, match="holds sensor_msgs/msg/LaserScan, not nav_msgs"):
        read_log(path, odom_topic="/base_scan")
    no_scans = _write_ros1(tmp_path / "odom.bag", [m for m in _messages() if "scan" not in m[0]])
    with pytest.raises(ConfigError, match="no sensor_msgs/msg/LaserScan topic"):
        read_log(no_scans)
    junk = tmp_path / "junk.bag"
    junk.write_bytes(b"#ROSBAG V2.0\nnot really")
    with pytest.raises(ConfigError, match="not a ROS bag that can be read"):
        read_log(junk)


def test_a_lone_mcap_file_reads_like_a_bag(tmp_path):
    path = tmp_path / "run.mcap"
    with McapLogWriter(path) as w:
        laser = rm.transform(0.0, "base_footprint", "base_scan", [-0.06, 0.01, 0.1], 0.17)
        w.write("/tf_static", rm.tf_message([laser]), 0.0, latched=True)
        for k, t in enumerate([0.2, 0.4]):
            w.write("/odom", rm.odometry(t, "odom", "base_footprint", [k, 0.0, 0.1], [0, 0]), t)
            scan = rm.laser_scan(t, "base_scan", -1.0, 1.0, 0.1, 10.0, [1.0, np.inf, 12.0])
            w.write("/scan", scan, t)
    log = read_log(path)
    assert log.scan_topic == "/scan" and log.odom_topic == "/odom"
    assert [s.time for s in log.scans] == pytest.approx([0.2, 0.4])
    np.testing.assert_allclose(log.scans[1].odometry, [1.0, 0.0, 0.1], atol=1e-9)
    np.testing.assert_allclose(log.laser_pose, [-0.06, 0.01, 0.1], atol=1e-9)
    assert log.scans[0].ranges[0] == 1.0 and np.all(np.isinf(log.scans[0].ranges[1:]))
    junk = tmp_path / "junk.mcap"
    junk.write_bytes(b"not an mcap file at all")
    with pytest.raises(ConfigError, match="junk.mcap: not an MCAP file"):
        read_log(junk)


@pytest.mark.skipif(not (SHARED / "fr079.orig.bag").exists(), reason="../shared/ SLAM logs absent")
def test_the_freiburg_bag_reads_with_its_laser_offset():
    log = read_log(SHARED / "fr079.orig.bag", angles="gmapping")
    assert len(log.scans) == 4934
    np.testing.assert_allclose(log.laser_pose, [0.04, 0.0, 0.0], atol=1e-6)
    np.testing.assert_allclose(np.degrees(log.scans[0].angles[[0, 1]]), [-90.0, -89.5])
