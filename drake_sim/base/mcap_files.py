"""Single-file ROS 2 MCAP logs (``FILE.mcap``), written and read with the ``mcap`` library and
``rosbags``' message serialisation, no ROS installed.

``McapLogWriter`` writes what ``ros2 bag record -s mcap`` writes into its bag's ``.mcap``: the
``ros2`` profile, each message type's schema as ``ros2msg`` text (the type's definition and
those it uses), CDR messages, one channel per topic with its offered QoS (``transient_local``
for latched topics such as ``/tf_static`` and ``/map``), zstd-compressed chunks and a summary.
Such a file is what Foxglove opens as it is and ``ros2 bag play FILE.mcap`` replays from ROS 2
Iron on (Humble wants rosbag2's folder with its ``metadata.yaml``, which this does not write);
neither was run here: the tests check the file with the ``mcap`` library and ``rosbags``.

The file appears only when ``close`` completes: until then the bytes go to a hidden temporary
file beside it, which ``abort`` (or an error) removes, so a stopped run never replaces a
complete log with a partial one (``drake_sim.base.files``).

``McapLogReader`` reads such a file (any single-file MCAP of CDR or ROS 1 messages) with the
three things ``drake_sim.base.laser_bags`` uses of a ``rosbags`` reader: ``connections``,
``messages`` and ``deserialize``. ``rosbags`` itself reads a rosbag2 folder, not a lone file.
"""

import contextlib
import dataclasses as dc
import os
import tempfile
import weakref
from pathlib import Path

from drake_sim.base.errors import ConfigError
from drake_sim.base.files import file_mode, signals_held
from drake_sim.base.ros_messages import nanoseconds, ros1_typestore, typestore


def offered_qos(latched: bool) -> str:
    """rosbag2's ``offered_qos_profiles`` of a reliable topic, transient local (latched) or
    volatile."""
    forever = "{sec: 2147483647, nsec: 4294967295}"
    return (
        f"- history: 3\n  depth: 0\n  reliability: 1\n  durability: {1 if latched else 2}\n"
        f"  deadline: {forever}\n  lifespan: {forever}\n  liveliness: 1\n"
        f"  liveliness_lease_duration: {forever}\n  avoid_ros_namespace_conventions: false\n"
    )


class McapLogWriter:
    """Writes ROS 2 messages into ``path`` (a ``.mcap`` file) as they come; see the module.

    Usable as a context manager: a normal exit closes (the file appears), an error aborts.

    Raises:
        ConfigError: ``path`` does not end in ``.mcap``, or its folder cannot be written.
    """

    def __init__(self, path: Path | str):
        from mcap.writer import CompressionType, Writer  # noqa: PLC0415 (import on first use)

        self.path = Path(path)
        if self.path.suffix.lower() != ".mcap":
            raise ConfigError(f"{self.path}: a ROS 2 log is written as MCAP: name it FILE.mcap")
        try:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            fd, self._tmp = tempfile.mkstemp(
                prefix=f".{self.path.name}.", suffix=".tmp", dir=self.path.parent
            )
        except OSError as e:
            raise ConfigError(f"log cannot be written: {self.path} ({e.strerror or e})") from None
        self._file = os.fdopen(fd, "wb")
        # A run that dies without closing or aborting leaves no hidden file behind.
        self._cleanup = weakref.finalize(self, _remove, self._tmp)
        self._writer = Writer(self._file, compression=CompressionType.ZSTD)
        self._writer.start(profile="ros2", library="drake_sim")
        self._schemas: dict[str, int] = {}
        self._channels: dict[str, tuple[int, str]] = {}
        self._sequence = 0
        self.messages = 0

    def write(self, topic: str, message, seconds: float, *, latched: bool = False) -> None:
        """Adds ``message`` (a ``ros_messages`` message) on ``topic`` at ``seconds``. A topic
        keeps the type and QoS of its first message (``latched``: transient local)."""
        msgtype = message.__msgtype__
        channel = self._channels.get(topic)
        if channel is None:
            channel = (self._channel(topic, msgtype, latched), msgtype)
            self._channels[topic] = channel
        elif channel[1] != msgtype:
            raise ValueError(f"{topic} carries {channel[1]}, not {msgtype}")
        time = nanoseconds(seconds)
        self._writer.add_message(
            channel[0],
            log_time=time,
            data=bytes(typestore().serialize_cdr(message, msgtype)),
            publish_time=time,
            sequence=self._sequence,
        )
        self._sequence += 1
        self.messages += 1

    def _channel(self, topic: str, msgtype: str, latched: bool) -> int:
        schema = self._schemas.get(msgtype)
        if schema is None:
            text, _ = typestore().generate_msgdef(msgtype, ros_version=2)
            schema = self._writer.register_schema(msgtype, "ros2msg", text.encode())
            self._schemas[msgtype] = schema
        return self._writer.register_channel(
            topic, "cdr", schema, metadata={"offered_qos_profiles": offered_qos(latched)}
        )

    def close(self, path: Path | str | None = None) -> Path:
        """Finishes the file and moves it to ``path`` (default: the one given at the start),
        replacing what was there; returns where it went.

        Raises:
            ConfigError: the file cannot be written (the temporary file is then removed).
        """
        target = Path(path) if path is not None else self.path
        try:
            self._writer.finish()
            self._file.flush()
            os.fsync(self._file.fileno())
            self._file.close()
            os.chmod(self._tmp, file_mode(target))
            with signals_held():
                os.replace(self._tmp, target)
                self._cleanup.detach()
        except OSError as e:
            self.abort()
            raise ConfigError(f"log cannot be written: {target} ({e.strerror or e})") from None
        return target

    def abort(self) -> None:
        """Drops the log: the temporary file is removed, ``path`` is left as it was."""
        with contextlib.suppress(OSError):
            self._file.close()
        self._cleanup()

    def __enter__(self):
        return self

    def __exit__(self, kind, value, traceback):
        if kind is None:
            self.close()
        else:
            self.abort()


def _remove(name: str) -> None:
    with contextlib.suppress(OSError):
        os.unlink(name)


@dc.dataclass
class McapConnection:
    """One channel of an MCAP file, named as ``rosbags`` names a connection."""

    id: int
    topic: str
    msgtype: str  # "sensor_msgs/msg/LaserScan" (ROS 1 names get their "msg/").
    msgcount: int
    encoding: str  # "cdr" or "ros1".


class McapLogReader:
    """A single-file MCAP log opened for ``drake_sim.base.laser_bags`` (see the module).

    Channels of other message encodings (JSON, Protobuf) are left out.

    Raises:
        ConfigError (``open``): not an MCAP file that can be read.
    """

    def __init__(self, path: Path | str):
        self.path = Path(path)
        self.connections: list[McapConnection] = []
        self._file = None
        self._store = None

    def open(self) -> None:
        """Reads the file's channels (from its summary, or by a pass over the messages)."""
        from mcap.reader import make_reader  # noqa: PLC0415 (import on first use)

        self._file = open(self.path, "rb")  # noqa: SIM115 (closed by close)
        try:
            reader = make_reader(self._file)
            summary = reader.get_summary()
            if summary is None or summary.statistics is None:  # counted by a pass over it
                counts: dict[int, int] = {}
                channels, schemas = {}, {}
                for schema, channel, _ in reader.iter_messages():
                    counts[channel.id] = counts.get(channel.id, 0) + 1
                    channels[channel.id] = channel
                    if schema is not None:
                        schemas[schema.id] = schema
            else:
                counts = dict(summary.statistics.channel_message_counts)
                channels, schemas = summary.channels, summary.schemas
        except Exception as e:  # mcap raises its own error types for a bad file
            self.close()
            raise ConfigError(f"{self.path}: not an MCAP file that can be read ({e})") from None
        from rosbags.typesys import Stores, get_types_from_msg, get_typestore  # noqa: PLC0415

        self._store = get_typestore(Stores.EMPTY)  # the file's own message definitions
        for channel in channels.values():
            schema = schemas.get(channel.schema_id)
            if channel.message_encoding not in ("cdr", "ros1") or schema is None:
                continue
            msgtype = schema.name if "/msg/" in schema.name else schema.name.replace("/", "/msg/")
            if schema.encoding in ("ros2msg", "ros1msg") and schema.data:
                # A definition that does not parse or clashes leaves the standard one.
                with contextlib.suppress(Exception):
                    self._store.register(get_types_from_msg(schema.data.decode(), msgtype))
            self.connections.append(
                McapConnection(
                    channel.id,
                    channel.topic,
                    msgtype,
                    counts.get(channel.id, 0),
                    channel.message_encoding,
                )
            )

    def messages(self, connections=None):
        """``(connection, log time ns, raw bytes)`` of the ``connections`` (default all), in
        the order they were written."""
        from mcap.reader import make_reader  # noqa: PLC0415

        wanted = {c.id: c for c in (connections or self.connections)}
        self._file.seek(0)
        for _, channel, message in make_reader(self._file).iter_messages(log_time_order=False):
            connection = wanted.get(channel.id)
            if connection is not None:
                yield connection, message.log_time, (message.data, connection.encoding)

    def deserialize(self, raw, msgtype: str):
        """The message of ``raw`` (what ``messages`` yields) as ``rosbags`` builds it, by the
        file's definition of ``msgtype`` (else ROS 2 Humble's, or ROS 1 Noetic's)."""
        data, encoding = raw
        ros1 = encoding == "ros1"
        store = self._store
        if msgtype not in store.types:  # no definition in the file: the distribution's
            store = ros1_typestore() if ros1 else typestore()
        return (
            store.deserialize_ros1(data, msgtype) if ros1 else store.deserialize_cdr(data, msgtype)
        )

    def close(self) -> None:
        if self._file is not None:
            self._file.close()
            self._file = None
