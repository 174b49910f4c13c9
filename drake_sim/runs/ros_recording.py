"""``--record-log FILE.mcap``: a lidar robot's run (mapping or navigate) written as a ROS 2 log
that Foxglove opens, ``ros2 bag play`` replays to RViz and ``python -m drake_sim.mapping --log``
maps again (``drake_sim.systems.recording.ros_log`` lists the topics).

The log appears at ``FILE.mcap`` when the run is complete; a run stopped or failed before its
end writes ``FILE.partial.mcap`` instead, and a log already at ``FILE.mcap`` stays as it was.
"""

import contextlib
from pathlib import Path

from drake_sim.base import cli
from drake_sim.base.map_files import OccupancyMap
from drake_sim.base.mcap_files import McapLogWriter
from drake_sim.runs import recipe
from drake_sim.runs.recipe import Flag
from drake_sim.systems.recording.ros_log import map_message

RECORD_LOG_FLAG = Flag(
    "--record-log",
    kwargs={
        "type": cli.output_file("log"),
        "metavar": "FILE.mcap",
        "help": "write the run as a ROS 2 log (MCAP: /scan, /odom, /tf, /map) that Foxglove "
        "opens and mapping --log reads",
    },
)
"""``--record-log FILE.mcap``: the run's option ``record_log``."""


def open_ros_log(options) -> McapLogWriter | None:
    """The log the options' ``record_log`` names, opened (its file appears at ``close_ros_log``),
    or None.

    Raises:
        ConfigError: the name does not end in ``.mcap``, or its folder cannot be written.
    """
    path = recipe.option(options, "record_log")
    return McapLogWriter(path) if path else None


@contextlib.contextmanager
def dropped_on_error(writer: McapLogWriter | None):
    """Within the block (a run's set-up), an error drops the log ``writer`` opened for it."""
    try:
        yield
    except BaseException:
        if writer is not None:
            writer.abort()
        raise


def partial_path(path: Path) -> Path:
    """Where an incomplete run's log goes: ``NAME.partial.mcap`` beside ``NAME.mcap``."""
    return path.with_name(f"{path.stem}.partial{path.suffix}")


def close_ros_log(
    writer: McapLogWriter | None,
    *,
    complete: bool,
    seconds: float,
    final_map: OccupancyMap | None = None,
) -> Path | None:
    """Ends the log, with ``final_map`` as its last ``/map`` (at ``seconds``), at its path when
    the run is ``complete`` (else ``partial_path``), and says where it went; None without one.

    Raises:
        ConfigError: the file cannot be written.
    """
    if writer is None:
        return None
    if final_map is not None and final_map.cells.size:
        writer.write("/map", map_message(final_map, seconds), seconds, latched=True)
    path = writer.close(writer.path if complete else partial_path(writer.path))
    kept = "" if complete or not writer.path.exists() else f"; {writer.path} is kept as it was"
    print(f"ROS 2 log: {path} ({writer.messages} messages){kept}", flush=True)
    return path
