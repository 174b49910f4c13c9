"""The run as a ROS 2 log (drake_sim.systems.recording.ros_log): odometry and tf several times
per scan, each scan after its odometry, map -> odom from the estimate, the sensor's static
transform, the map latched (periodic, or a fixed one once), in simulated time."""

import numpy as np
import pytest
from pydrake.common.value import AbstractValue
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import DiagramBuilder
from pydrake.systems.primitives import ConstantValueSource, ConstantVectorSource

import drake_sim.systems.recording.ros_log as mut
from drake_sim.base import ros_messages as rm
from drake_sim.base.map_files import OccupancyMap
from drake_sim.base.mcap_files import McapLogReader, McapLogWriter
from drake_sim.base.planar import compose
from drake_sim.systems.sensors.lidar import LaserScan

ODOMETRY = np.array([1.0, 2.0, 0.5])
ESTIMATE = np.array([1.5, 1.0, 2.0])
MAP = OccupancyMap(np.zeros((4, 6), np.int8), 0.05, (-1.0, -1.0, 0.0))


def _record(path, *, static_map=None, estimate=True, seconds=1.0):
    builder = DiagramBuilder()
    writer = McapLogWriter(path)
    recorder = builder.AddSystem(
        mut.RosLogRecorder(
            writer=writer,
            scan_period=0.2,
            frames=mut.RosLogFrames(base="base_link", laser="laser"),
            X_base_sensor=(-0.05, 0.0, 0.0),
            sensor_height=0.2,
            static_map=static_map,
        )
    )
    scan = LaserScan(0.0, -1.0, 1.0, 0.1, 3.5, [1.0, np.inf, 2.0])
    sources = {
        "scan": ConstantValueSource(AbstractValue.Make(scan)),
        "odometry_pose": ConstantVectorSource(ODOMETRY),
        "odometry_twist": ConstantVectorSource([0.1, 0.0]),
        "true_pose": ConstantVectorSource(ESTIMATE + 0.01),
        "map": ConstantValueSource(AbstractValue.Make(MAP)),
    }
    if estimate:
        sources["estimated_pose"] = ConstantVectorSource(ESTIMATE)
    for name, source in sources.items():
        builder.Connect(builder.AddSystem(source).get_output_port(), recorder.GetInputPort(name))
    simulator = Simulator(builder.Build())
    simulator.AdvanceTo(seconds)
    writer.close()
    reader = McapLogReader(path)
    reader.open()
    try:
        return [(c.topic, t, reader.deserialize(raw, c.msgtype)) for c, t, raw in reader.messages()]
    finally:
        reader.close()


def _yaw(q) -> float:
    return 2 * np.arctan2(q.z, q.w)


def test_odometry_and_tf_four_times_a_scan_each_scan_after_its_odometry(tmp_path):
    messages = _record(tmp_path / "run.mcap")
    topics = [topic for topic, _, _ in messages]
    assert topics.count("/odom") == 20 and topics.count("/tf") == 20
    assert topics.count("/scan") == 5 and topics.count("/ground_truth/pose") == 5
    assert topics[:2] == ["/tf_static", "/odom"]
    for i, topic in enumerate(topics):
        if topic == "/scan":
            assert topics[i - 2 : i] == ["/odom", "/tf"]
            assert messages[i][1] == messages[i - 2][1]  # at the same instant
    scan = next(m for topic, _, m in messages if topic == "/scan")
    assert scan.header.frame_id == "laser" and np.isinf(scan.ranges[1])


def test_tf_has_odom_to_base_and_map_to_odom_from_the_estimate(tmp_path):
    messages = _record(tmp_path / "run.mcap")
    tf = next(m for topic, _, m in messages if topic == "/tf")
    odom, map_odom = tf.transforms
    assert (odom.header.frame_id, odom.child_frame_id) == ("odom", "base_link")
    assert (map_odom.header.frame_id, map_odom.child_frame_id) == ("map", "odom")
    t = map_odom.transform
    planar = [t.translation.x, t.translation.y, _yaw(t.rotation)]
    # map -> odom -> base is the estimate
    np.testing.assert_allclose(compose(planar, ODOMETRY), ESTIMATE, atol=1e-9)
    (static,) = next(m for topic, _, m in messages if topic == "/tf_static").transforms
    assert (static.header.frame_id, static.child_frame_id) == ("base_link", "laser")
    assert static.transform.translation.x == -0.05 and static.transform.translation.z == 0.2


def test_without_an_estimate_tf_has_odometry_alone(tmp_path):
    messages = _record(tmp_path / "run.mcap", estimate=False)
    tf = next(m for topic, _, m in messages if topic == "/tf")
    assert [t.child_frame_id for t in tf.transforms] == ["base_link"]


def test_the_map_input_every_period_or_a_fixed_map_once(tmp_path):
    periodic = _record(tmp_path / "a.mcap", seconds=11.0)
    maps = [(t, m) for topic, t, m in periodic if topic == "/map"]
    assert [round(t / 1e9, 3) for t, _ in maps] == [0.0, 5.0, 10.0]
    grid = maps[0][1]
    assert (grid.info.width, grid.info.height) == (6, 4) and grid.header.frame_id == "map"
    fixed = OccupancyMap(np.full((2, 3), 100, np.int8), 0.1)
    once = _record(tmp_path / "b.mcap", static_map=fixed, seconds=11.0)
    maps = [m for topic, _, m in once if topic == "/map"]
    assert len(maps) == 1 and (maps[0].info.width, maps[0].info.height) == (3, 2)
    assert maps[0].info.resolution == pytest.approx(0.1) and set(maps[0].data) == {100}


def test_map_message_is_the_grid_of_an_occupancy_map():
    message = mut.map_message(MAP, 2.0)
    assert message.__msgtype__ == rm.MAP_TYPE and message.info.origin.position.x == -1.0
