"""ROS 2 messages from plain values (drake_sim.base.ros_messages): stamps, planar poses as
quaternions, scans with no-return beams and occupancy grids in ROS's cell order, each
serialised and read back as CDR."""

import math

import numpy as np
import pytest

import drake_sim.base.ros_messages as mut


def _round_trip(message):
    store = mut.typestore()
    data = store.serialize_cdr(message, message.__msgtype__)
    return store.deserialize_cdr(data, message.__msgtype__)


def _yaw(q) -> float:
    return 2 * math.atan2(q.z, q.w)


def test_a_stamp_splits_seconds_into_whole_seconds_and_nanoseconds():
    t = mut.stamp(12.3456789)
    assert (t.sec, t.nanosec) == (12, 345678900)
    assert mut.nanoseconds(0.2) == 200_000_000


def test_a_scan_keeps_its_beams_and_no_return_as_inf():
    ranges = np.r_[np.linspace(0.5, 3.0, 359), np.inf]
    scan = _round_trip(
        mut.laser_scan(1.5, "base_scan", -math.pi, math.radians(1), 0.12, 3.5, ranges)
    )
    assert scan.header.frame_id == "base_scan" and scan.header.stamp.sec == 1
    assert scan.angle_max == pytest.approx(-math.pi + math.radians(359), abs=1e-6)
    assert np.allclose(scan.ranges[:-1], ranges[:-1], atol=1e-6) and np.isinf(scan.ranges[-1])
    assert scan.range_min == pytest.approx(0.12) and scan.range_max == pytest.approx(3.5)


def test_odometry_and_transforms_carry_planar_poses():
    odom = _round_trip(mut.odometry(2.0, "odom", "base_footprint", [1.0, -2.0, 2.5], [0.2, -0.3]))
    assert (odom.header.frame_id, odom.child_frame_id) == ("odom", "base_footprint")
    p = odom.pose.pose
    assert (p.position.x, p.position.y) == (1.0, -2.0) and _yaw(p.orientation) == pytest.approx(2.5)
    assert odom.twist.twist.linear.x == 0.2 and odom.twist.twist.angular.z == -0.3
    tf = _round_trip(mut.tf_message([mut.transform(0.0, "base", "laser", [0.1, 0.0, -3.0], 0.17)]))
    (t,) = tf.transforms
    assert (t.header.frame_id, t.child_frame_id) == ("base", "laser")
    assert t.transform.translation.z == 0.17 and _yaw(t.transform.rotation) == pytest.approx(-3.0)


def test_an_occupancy_grid_is_row_major_from_its_origin():
    cells = np.full((3, 4), -1, np.int8)
    cells[0, 1] = 100  # the first row is the one at the origin (nav_msgs/OccupancyGrid)
    cells[2, 3] = 0
    grid = _round_trip(mut.occupancy_grid(5.0, "map", cells, 0.05, [-1.0, 2.0, 0.0]))
    assert (grid.info.width, grid.info.height) == (4, 3)
    assert grid.info.resolution == pytest.approx(0.05)
    assert (grid.info.origin.position.x, grid.info.origin.position.y) == (-1.0, 2.0)
    assert grid.data[1] == 100 and grid.data[11] == 0 and (grid.data == -1).sum() == 10


def test_a_pose_stamped_and_the_ros1_store():
    pose = _round_trip(mut.pose_stamped(3.0, "map", [1.0, 2.0, 0.5]))
    assert pose.header.frame_id == "map" and _yaw(pose.pose.orientation) == pytest.approx(0.5)
    assert "sensor_msgs/msg/LaserScan" in mut.ros1_typestore().types
