"""Single-file ROS 2 MCAP logs (drake_sim.base.mcap_files): what is written reads back in
order with its schemas and QoS, the file appears only when closed, an aborted or failed log
leaves what was there, and files of other kinds are one clear error."""

import math

import numpy as np
import pytest
from mcap.reader import make_reader
from mcap.writer import Writer

import drake_sim.base.mcap_files as mut
from drake_sim.base import ros_messages as rm
from drake_sim.base.errors import ConfigError


def _scan(t):
    return rm.laser_scan(t, "laser", -math.pi / 2, math.radians(1), 0.1, 30.0, np.full(181, 2.0))


def _write(path, n=3):
    with mut.McapLogWriter(path) as writer:
        writer.write("/tf_static", rm.tf_message([]), 0.0, latched=True)
        for k in range(n):
            t = 0.1 * k
            writer.write("/odom", rm.odometry(t, "odom", "base", [k, 0, 0], [0, 0]), t)
            writer.write("/scan", _scan(t), t)
    return writer


def test_messages_read_back_in_the_order_written_with_counts(tmp_path):
    path = tmp_path / "run.mcap"
    writer = _write(path)
    assert writer.messages == 7 and path.is_file()
    reader = mut.McapLogReader(path)
    reader.open()
    try:
        counts = {c.topic: (c.msgtype, c.msgcount) for c in reader.connections}
        assert counts == {
            "/tf_static": (rm.TF_TYPE, 1),
            "/odom": (rm.ODOM_TYPE, 3),
            "/scan": (rm.SCAN_TYPE, 3),
        }
        order = [(c.topic, time) for c, time, _ in reader.messages()]
        assert [topic for topic, _ in order] == ["/tf_static"] + ["/odom", "/scan"] * 3
        assert [time for _, time in order[1::2]] == [0, 100_000_000, 200_000_000]
        scans = [c for c in reader.connections if c.topic == "/scan"]
        raws = [raw for _, _, raw in reader.messages(scans)]
        assert len(raws) == 3
        assert reader.deserialize(raws[2], rm.SCAN_TYPE).header.stamp.nanosec == 200_000_000
    finally:
        reader.close()


def test_the_file_is_a_ros2_mcap_with_schemas_and_latched_qos(tmp_path):
    path = tmp_path / "run.mcap"
    _write(path)
    with open(path, "rb") as f:
        reader = make_reader(f, validate_crcs=True)
        assert reader.get_header().profile == "ros2"
        summary = reader.get_summary()
        schemas = {s.name: s for s in summary.schemas.values()}
        assert schemas[rm.SCAN_TYPE].encoding == "ros2msg"
        assert b"MSG: std_msgs/Header" in schemas[rm.SCAN_TYPE].data
        channels = {c.topic: c for c in summary.channels.values()}
        assert channels["/scan"].message_encoding == "cdr"
        assert "durability: 1" in channels["/tf_static"].metadata["offered_qos_profiles"]
        assert "durability: 2" in channels["/scan"].metadata["offered_qos_profiles"]
        assert sum(1 for _ in reader.iter_messages()) == 7


def test_the_log_appears_only_when_closed_and_an_abort_keeps_the_old_one(tmp_path):
    path = tmp_path / "run.mcap"
    path.write_bytes(b"the old log")
    writer = mut.McapLogWriter(path)
    writer.write("/scan", _scan(0.0), 0.0)
    assert path.read_bytes() == b"the old log"
    writer.abort()
    assert path.read_bytes() == b"the old log"
    assert [p.name for p in tmp_path.iterdir()] == ["run.mcap"]
    with pytest.raises(RuntimeError), mut.McapLogWriter(path) as writer:
        writer.write("/scan", _scan(0.0), 0.0)
        raise RuntimeError("the run failed")
    assert [p.name for p in tmp_path.iterdir()] == ["run.mcap"]
    assert path.read_bytes() == b"the old log"


def test_a_log_closed_elsewhere_goes_there_and_a_dropped_one_leaves_nothing(tmp_path):
    writer = mut.McapLogWriter(tmp_path / "run.mcap")
    writer.write("/scan", _scan(0.0), 0.0)
    assert writer.close(tmp_path / "run.partial.mcap") == tmp_path / "run.partial.mcap"
    assert [p.name for p in tmp_path.iterdir()] == ["run.partial.mcap"]
    writer = mut.McapLogWriter(tmp_path / "other.mcap")
    del writer  # never closed: its hidden file goes with it
    assert [p.name for p in tmp_path.iterdir()] == ["run.partial.mcap"]


def test_a_topic_keeps_its_type(tmp_path):
    with mut.McapLogWriter(tmp_path / "run.mcap") as writer:
        writer.write("/scan", _scan(0.0), 0.0)
        with pytest.raises(ValueError, match="/scan carries"):
            writer.write("/scan", rm.tf_message([]), 0.1)


def test_other_names_and_unwritable_folders_are_config_errors(tmp_path):
    with pytest.raises(ConfigError, match="FILE.mcap"):
        mut.McapLogWriter(tmp_path / "run.bag")
    blocker = tmp_path / "file"
    blocker.write_text("not a folder")
    with pytest.raises(ConfigError, match="cannot be written"):
        mut.McapLogWriter(blocker / "run.mcap")


def test_a_file_that_is_not_mcap_is_a_config_error(tmp_path):
    path = tmp_path / "noise.mcap"
    path.write_bytes(b"\x89MCAP0\r\n" + b"\x00" * 40)
    reader = mut.McapLogReader(path)
    with pytest.raises(ConfigError, match="noise.mcap"):
        reader.open()


def test_a_ros1_encoded_mcap_reads_with_ros1_names(tmp_path):
    store = rm.ros1_typestore()
    text, _ = store.generate_msgdef("sensor_msgs/msg/LaserScan", ros_version=1)
    Scan = store.types["sensor_msgs/msg/LaserScan"]
    Header = store.types["std_msgs/msg/Header"]
    Time = store.types["builtin_interfaces/msg/Time"]
    message = Scan(
        header=Header(seq=1, stamp=Time(sec=3, nanosec=0), frame_id="laser"),
        angle_min=-1.0, angle_max=1.0, angle_increment=1.0, time_increment=0.0, scan_time=0.0,
        range_min=0.1, range_max=10.0, ranges=np.array([1.0, 2.0, 3.0], np.float32),
        intensities=np.zeros(0, np.float32),
    )  # fmt: skip
    path = tmp_path / "ros1.mcap"
    with open(path, "wb") as f:
        writer = Writer(f)
        writer.start(profile="ros1")
        schema = writer.register_schema("sensor_msgs/LaserScan", "ros1msg", text.encode())
        channel = writer.register_channel("/base_scan", "ros1", schema)
        data = store.serialize_ros1(message, "sensor_msgs/msg/LaserScan")
        writer.add_message(channel, log_time=3_000_000_000, data=bytes(data), publish_time=0)
        writer.finish()
    reader = mut.McapLogReader(path)
    reader.open()
    try:
        (connection,) = reader.connections
        assert connection.msgtype == "sensor_msgs/msg/LaserScan" and connection.msgcount == 1
        (_, _, raw), *_ = list(reader.messages())
        scan = reader.deserialize(raw, connection.msgtype)
        assert list(scan.ranges) == [1.0, 2.0, 3.0] and scan.header.frame_id == "laser"
    finally:
        reader.close()


def test_messages_read_by_the_file_s_own_definitions(tmp_path):
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    store = get_typestore(Stores.EMPTY)
    store.register(get_types_from_msg("int32 value\nstring note", "my_msgs/msg/Ping"))
    Ping = store.types["my_msgs/msg/Ping"]
    path = tmp_path / "custom.mcap"
    with open(path, "wb") as f:
        writer = Writer(f)
        writer.start(profile="ros2")
        schema = writer.register_schema("my_msgs/msg/Ping", "ros2msg", b"int32 value\nstring note")
        channel = writer.register_channel("/ping", "cdr", schema)
        data = store.serialize_cdr(Ping(value=7, note="hi"), "my_msgs/msg/Ping")
        writer.add_message(channel, log_time=1, data=bytes(data), publish_time=1)
        writer.finish()
    reader = mut.McapLogReader(path)
    reader.open()
    try:
        (_, _, raw), *_ = list(reader.messages())
        message = reader.deserialize(raw, "my_msgs/msg/Ping")
        assert (message.value, message.note) == (7, "hi")
    finally:
        reader.close()


def test_a_file_without_statistics_is_counted_by_reading_it(tmp_path):
    path = tmp_path / "plain.mcap"
    store = rm.typestore()
    text, _ = store.generate_msgdef(rm.SCAN_TYPE, ros_version=2)
    with open(path, "wb") as f:
        writer = Writer(f, use_statistics=False, use_summary_offsets=False)
        writer.start(profile="ros2")
        schema = writer.register_schema(rm.SCAN_TYPE, "ros2msg", text.encode())
        channel = writer.register_channel("/scan", "cdr", schema)
        for k in range(3):
            data = store.serialize_cdr(_scan(0.1 * k), rm.SCAN_TYPE)
            writer.add_message(channel, log_time=k, data=bytes(data), publish_time=k)
        writer.finish()
    reader = mut.McapLogReader(path)
    reader.open()
    try:
        assert [(c.topic, c.msgcount) for c in reader.connections] == [("/scan", 3)]
    finally:
        reader.close()
