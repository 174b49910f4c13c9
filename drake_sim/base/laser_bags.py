"""ROS 1 and ROS 2 bags as ``LaserLog`` (``drake_sim.base.laser_scans``), read with ``rosbags``
(a lone ``.mcap`` file, which ``rosbags`` does not open, with ``drake_sim.base.mcap_files``).

The scan topic is the ``sensor_msgs/LaserScan`` topic (the one with the most messages when there
are several) unless named; the odometry is a ``nav_msgs/Odometry`` topic unless named, else the
``tf`` transform from any frame to the scans' base frame. The base frame is the odometry's
``child_frame_id`` (``base_link`` when the log has only tf), and the sensor's pose on it comes
from ``tf_static`` or ``tf`` (a direct transform from the base to the scan's ``frame_id``;
identity if there is none). Quaternions become yaw (a tilted sensor is the caller's to refuse).

A ROS 1 bag is read in the order its messages were written, not sorted by their stamps: a log's
stamps may run backwards (Intel's do in hundreds of places, odometry and scans alike), and the
order of writing is the order of events, so each scan is paired with the odometry written just
before it. (Sorted by stamp, Intel's bag paired some scans with odometry 0.2 to 0.4 m old.)
A lone ``.mcap`` file is read in its written order too; a rosbag2 folder in the order of its
log times (when each message was recorded, not its header's stamp), as ``rosbags`` gives it.
"""

import io
import math
from pathlib import Path

import numpy as np

from drake_sim.base.errors import ConfigError
from drake_sim.base.laser_scans import LaserLog, LaserScanRecord, no_echo_to_inf
from drake_sim.base.mcap_files import McapLogReader
from drake_sim.base.ros_messages import ODOM_TYPE, SCAN_TYPE, TF_TYPE


def read_bag(
    path: Path | str,
    *,
    scan_topic: str | None = None,
    odom_topic: str | None = None,
    range_max: float | None = None,
) -> LaserLog:
    """Reads a bag's scans with the odometry before each (see the module's notes).

    Raises:
        ConfigError: not a bag ``rosbags`` can open, no LaserScan topic, a named topic absent
            or of another type.
    """
    from rosbags.highlevel import AnyReader
    from rosbags.typesys import Stores, get_typestore

    path = Path(path)
    try:
        if path.is_file() and path.suffix.lower() == ".mcap":  # a lone file, not rosbag2's folder
            reader = McapLogReader(path)
        else:
            reader = AnyReader([path], default_typestore=get_typestore(Stores.ROS2_HUMBLE))
        reader.open()
    except ConfigError:
        raise
    except Exception as e:  # rosbags raises its own error types per format
        raise ConfigError(f"{path}: not a ROS bag that can be read ({e})") from None
    try:
        return _read(reader, path, scan_topic, odom_topic, range_max)
    finally:
        reader.close()


def _read(reader, path, scan_topic, odom_topic, range_max) -> LaserLog:
    topics = {}
    for c in reader.connections:
        topics.setdefault(c.topic, [c.msgtype, 0])[1] += c.msgcount
    scan_topic = _pick(topics, scan_topic, SCAN_TYPE, path, "--scan-topic")
    if odom_topic is None:
        odoms = [t for t, (kind, _) in topics.items() if kind == ODOM_TYPE]
        odom_topic = max(odoms, key=lambda t: topics[t][1]) if odoms else None
    else:
        _pick(topics, odom_topic, ODOM_TYPE, path, "--odom-topic")
    tf_topics = {t for t, (kind, _) in topics.items() if kind == TF_TYPE}
    wanted = {scan_topic, *tf_topics} | ({odom_topic} if odom_topic else set())
    connections = [c for c in reader.connections if c.topic in wanted]
    scans, transforms = [], {}
    odometry, base = None, None
    scan_frame = None
    for connection, raw in _in_written_order(reader, connections, path):
        try:
            message = reader.deserialize(raw, connection.msgtype)
        except Exception as e:  # a truncated or corrupt record
            raise ConfigError(
                f"{path}: a message on {connection.topic} cannot be read ({e})"
            ) from None
        if connection.topic == scan_topic:
            scan_frame = scan_frame or message.header.frame_id
            scans.append(_scan(message, odometry, range_max))
        elif connection.topic == odom_topic:
            base = base or message.child_frame_id
            pose = message.pose.pose
            odometry = np.array([pose.position.x, pose.position.y, _yaw(pose.orientation)])
        else:
            for t in message.transforms:
                parent, child = t.header.frame_id.lstrip("/"), t.child_frame_id.lstrip("/")
                planar = np.array(
                    [
                        t.transform.translation.x,
                        t.transform.translation.y,
                        _yaw(t.transform.rotation),
                    ]
                )
                transforms.setdefault((parent, child), planar)
                if odom_topic is None and child == (base or "base_link"):
                    base = child
                    odometry = planar
    base = (base or "base_link").lstrip("/")
    laser = transforms.get((base, (scan_frame or "").lstrip("/")), np.zeros(3))
    odom_name = odom_topic or f"tf (to {base})"
    return LaserLog(path, scans, np.asarray(laser, dtype=float), scan_topic, odom_name)


def _in_written_order(reader, connections, path):
    """(connection, raw message) of ``connections``: a ROS 1 bag's in the order they were
    written (by chunk and offset, from the bag's index), any other log's in time order.

    Raises:
        ConfigError: a record cannot be read (a truncated or corrupt bag).
    """
    try:
        yield from _records(reader, connections)
    except ConfigError:
        raise
    except Exception as e:  # rosbags' own error types, or a short read
        raise ConfigError(f"{path}: the bag's records cannot be read ({e})") from None


def _records(reader, connections):
    from rosbags.rosbag1 import Reader as Ros1Reader

    bags = getattr(reader, "readers", ())
    if len(bags) != 1 or not isinstance(bags[0], Ros1Reader):
        for connection, _, raw in reader.messages(connections=connections):
            yield connection, raw
        return
    from rosbags.rosbag1.reader import Header, RecordType, read_bytes, read_uint32

    bag = bags[0]
    entries = sorted(
        (entry.chunk_pos, entry.offset, k)
        for k, connection in enumerate(connections)
        for entry in bag.indexes[connection.id]
    )
    loaded, data = None, None
    for chunk_pos, offset, k in entries:
        if chunk_pos != loaded:
            chunk = bag.chunks[chunk_pos]
            bag.bio.seek(chunk.datapos)
            data = io.BytesIO(chunk.decompressor(read_bytes(bag.bio, chunk.datasize)))
            loaded = chunk_pos
        data.seek(offset)
        while True:  # a chunk may hold connection records before a message
            header = Header.read(data)
            if header.get_uint8("op") != RecordType.CONNECTION:
                break
            data.seek(read_uint32(data), io.SEEK_CUR)
        if header.get_uint8("op") != RecordType.MSGDATA:
            raise ValueError("the bag's index points at no message")
        yield connections[k], read_bytes(data, read_uint32(data))


def _pick(topics: dict, name: str | None, kind: str, path: Path, flag: str) -> str:
    if name is not None:
        if name not in topics:
            known = ", ".join(sorted(topics)) or "none"
            raise ConfigError(f"{path}: no topic {name!r} ({flag}; the bag has: {known})")
        if topics[name][0] != kind:
            raise ConfigError(f"{path}: {name} holds {topics[name][0]}, not {kind} ({flag})")
        return name
    found = [t for t, (k, _) in topics.items() if k == kind]
    if not found:
        raise ConfigError(f"{path}: no {kind} topic in the bag")
    return max(found, key=lambda t: topics[t][1])


def _scan(message, odometry, range_max) -> LaserScanRecord:
    count = len(message.ranges)
    maximum = float(message.range_max) if range_max is None else float(range_max)
    if not (math.isfinite(maximum) and maximum > 0):
        maximum = math.inf
    stamp = message.header.stamp
    return LaserScanRecord(
        time=stamp.sec + stamp.nanosec * 1e-9,
        ranges=no_echo_to_inf(message.ranges, maximum),
        angles=message.angle_min + message.angle_increment * np.arange(count),
        range_min=max(float(message.range_min), 0.0),
        range_max=maximum,
        odometry=None if odometry is None else odometry.copy(),
    )


def _yaw(q) -> float:
    return math.atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z))
